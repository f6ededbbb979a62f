"""Free flight of the randomly accelerated particle in gravity (g = Lambda = 1).

Between collisions the particle obeys eq. (eqmo) with no boundary.  Over a
step of length ``dt`` the update of eqs. (xstep), (vstep) is exact in
distribution.  Given both ends of a step, the path in between is a Gaussian
bridge whose mean is the cubic Hermite interpolant of the two ends (the
covariances of integrated Brownian motion are cubic in time, and Hermite
interpolation reproduces the cubic drift term -t^2/2); its variances are

    Var[x(t) | ends] = 2 t^3 (dt - t)^3 / (3 dt^3)
    Var[v(t) | ends] = 2 t (dt - t) (dt^2 - 3 t dt + 3 t^2) / dt^3

and their covariance is

    Cov[x(t), v(t) | ends] = t^2 (dt - t)^2 (dt - 2 t) / dt^3

(the factor 2 is the noise strength 2 Lambda of eq. (eqmo)).  The simulation
uses these to integrate x, x^2 and v^2 over a step exactly in expectation, to
place a collision inside a step, and to draw (x(t), v(t)) from the bridge
(``bridge_sample``) for the time-weighted P(x, v) and for the correction that makes
the P(x) and <v^2>_x tally exact in expectation.

Everything here is numba-compiled scalar code (no allocation, no division by
a constant: those are written as products with the reciprocal, which LLVM
folds), because it runs once or more per step.  What every step computes (its
update, the root of eq. (criterion) and its start, the integrals over a whole
step) is written with fused multiply-adds (``jit.fma``: a b + c rounded once,
the same double on every machine), where the compiler fuses none of its own.  The mean path is carried as
its four monomial coefficients ``a0 + a1 t + a2 t^2 + a3 t^3``.

A compiled function compiles on its first call (seconds); its ``py_func`` is the Python
function, which the Examples call so that they run at once.
"""

import math

import numpy as np

from .jit import fma, njit

__all__ = [
    "free_flight_step",
    "criterion_root",
    "root_predictor",
    "predicted_start",
    "largest_safe_step",
    "hermite_cubic",
    "cubic_value",
    "cubic_slope",
    "mean_path_integrals",
    "whole_step_integrals",
    "bridge_covariance",
    "bridge_sample",
    "bridge_speed_squared_given_position",
    "speed_squared_coefficients",
    "quintic_antiderivative_value",
    "piece_inverse",
    "level_time_one_step",
    "level_time",
    "cubic_level_time",
    "slope_zeros",
    "monotone_piece_end",
    "first_crossing_time",
]

SQRT3 = math.sqrt(3.0)
SQRT1_12 = math.sqrt(1.0 / 12.0)
SQRT2_3 = math.sqrt(2.0 / 3.0)
SQRT3_2 = math.sqrt(1.5)
SQRT1_2 = math.sqrt(0.5)

# Rational fits (see _fitted_root) to the positive root of the cubic
# c s^3 = x + v s^2, in units of a = (x/c)^(1/3), with t = |v| / (c a).
# The forms have the right limits (s/a -> 1 at t = 0; s/a -> t, resp.
# t^(-1/2), for t -> inf); the constants are least-squares fits of the
# relative error over a log grid of t.  They only set the root's start
# where no previous root is at hand (criterion_root).
#   v >= 0:  s / a ~ t + (1 + P t) / (1 + (P + 2/3) t + Q t^2 + P t^3)   (0.2 %)
#   v < 0:   s / a ~ (t + (1 + N3 t) / (1 + N1 t + N2 t^2))^(-1/2)      (0.04 %)
_P, _Q = 0.44356066, 0.56163652
_N1, _N2, _N3 = 0.40104058, 0.00211799, 0.06071102

_SMALLEST_NORMAL = np.finfo(np.float64).tiny


@njit(cache=True)
def free_flight_step(x, v, dt, normal_r, normal_s):
    """One exact free-flight step of eq. (eqmo), eqs. (xstep) and (vstep).

    The same ``normal_r`` enters both equations, which gives the correct x-v covariance.
    The two noise amplitudes share one square root: sqrt(dt^3 / 6) = dt sqrt(2 dt) / sqrt(12),
    so x_new = x + dt (v - dt/2 + sqrt(2 dt) (normal_s + sqrt(3) normal_r) / sqrt(12)), in
    fused multiply-adds (``jit.fma``).

    Parameters
    ----------
    x, v : float
        Position and velocity at the step's start.
    dt : float
        The step Delta, > 0.
    normal_r, normal_s : float
        Independent standard normals (r and s of eqs. (xstep), (vstep)).

    Returns
    -------
    x_new, v_new : float

    Examples
    --------
    Without noise the step is the parabola of gravity:

    >>> from bouncing_ball.free_flight import free_flight_step
    >>> x, v = free_flight_step.py_func(1.0, 0.5, 0.01, 0.0, 0.0)
    >>> print(round(x, 12), round(v, 12))
    1.00495 0.49
    """
    root_2dt = math.sqrt(2.0 * dt)
    position_noise = SQRT1_12 * fma(SQRT3, normal_r, normal_s)
    x_new = fma(dt, fma(root_2dt, position_noise, fma(-0.5, dt, v)), x)
    v_new = fma(root_2dt, normal_r, v - dt)
    return x_new, v_new


@njit(cache=True)
def _floor_root(v, c):
    """s* at x = 0: the root of s^2 (v - c s - s^2/2), 0 for v <= 0."""
    if v <= 0.0:
        return 0.0
    return 2.0 * v / (c + math.sqrt(c * c + 2.0 * v))


@njit(cache=True)
def _fitted_root(x, v, c):
    """The root of the cubic x + v s^2 - c s^3 (no s^4/2 term), from the rational fits above
    (homogeneous in a = (x/c)^(1/3) and v/c, one division); x > 0."""
    a3 = x / c
    a = np.cbrt(a3)
    b = v / c
    a2 = a * a
    if b >= 0.0:
        return b + a * (
            (a3 + _P * a2 * b) / (a3 + b * (a2 * (_P + 2.0 / 3.0) + b * (_Q * a + _P * b)))
        )
    return math.sqrt(a3 / (-b + a2 * (a - _N3 * b) / (a2 - b * (_N1 * a - _N2 * b))))


ROOT_TOLERANCE = 2.0e-3  # a last Householder step below this (relative) leaves ~its 4th power


@njit(cache=True, inline="always")
def _householder_root(x, v, c, s, iterations):
    """Householder iterations for ``criterion_root`` from s: (s, f'(s), converged).  f and
    its derivatives by Horner's rule in fused multiply-adds."""
    f1 = -1.0
    for _ in range(iterations):
        s2 = s * s
        f = fma(s2, fma(-s, fma(0.5, s, c), v), x)
        f1 = s * fma(-s, fma(2.0, s, 3.0 * c), 2.0 * v)
        if not f1 < 0.0:
            return s, f1, False
        f2 = fma(-s, fma(6.0, s, 6.0 * c), 2.0 * v)
        f3 = fma(-12.0, s, -6.0 * c)
        f_f2 = f * f2
        six_f1_squared = 6.0 * (f1 * f1)
        denominator = fma(f1, fma(-6.0, f_f2, six_f1_squared), f * f * f3)
        # Householder where its denominator is negative, else Newton
        step = f * fma(-3.0, f_f2, six_f1_squared) / denominator if denominator < 0.0 else f / f1
        if not s - step > 0.0:  # overshot past 0: halve instead (f(0) = x > 0)
            s *= 0.5
            continue
        s -= step
        if abs(step) <= ROOT_TOLERANCE * s:
            return s, f1, True
    return s, f1, False


@njit(cache=True, inline="always")
def criterion_root(x, v, c, start):
    """The root s* = sqrt(Delta) of eq. (criterion) that sets the largest step, and f'(s*).

    s* is the positive root of f(s) = x + v s^2 - c s^3 - s^4/2 (s = sqrt(Delta)).

    By Descartes' rule f has exactly one positive root, where f' < 0 (and f' < 0,
    f'' < 0 on [s*, inf)).  At x = 0 (x below the smallest normal double counts as
    0) it is that of a quadratic.  Otherwise Householder's third-order step ::

        s -= f (6 f1^2 - 3 f f2) / (6 f1^3 - 6 f f1 f2 + f^2 f3)

    (f1, f2, f3 the derivatives of f) converges quartically from ``start``: after
    a step of relative size e about e^4 is left, so it stops after a step
    <= ROOT_TOLERANCE s (s* to ~1e-11; tests/unit/test_free_flight.py checks the
    step D = s*^2 to 1e-9 against brentq).  The simulation starts from a
    prediction off the previous step's root (about two iterations a step, no
    cube root).  ``start`` <= 0, a start left of the maximum of f (where
    f1 >= 0) or 60 iterations without convergence restart from the rational
    fits above (``_fitted_root``).  A Newton step stands in where the
    Householder denominator is not negative (far from s*), and a step past 0
    is replaced by halving s.

    Parameters
    ----------
    x, v : float
        Position (>= 0) and velocity.
    c : float
        The constant c of eq. (criterion), > 0.
    start : float
        A first guess of s* (<= 0: none, the rational fits give it).

    Returns
    -------
    root, slope : float
        s* and f'(s*).
    """
    if x < _SMALLEST_NORMAL:
        s = _floor_root(v, c)
        return s, s * (2.0 * v - s * (3.0 * c + 2.0 * s))
    if start > 0.0:
        s, f1, converged = _householder_root(x, v, c, start, 60)
        if converged:
            return s, f1
    s, f1, _ = _householder_root(x, v, c, _fitted_root(x, v, c), 60)
    return s, f1


@njit(cache=True, inline="always")
def root_predictor(root, slope_at_root, x, v):
    """The first-order prediction of the next step's root of eq. (criterion).

    The coefficients (k0, k1, k2) of the next step's start for ``criterion_root``,
    s ~ k0 - k1 x1 - k2 v1 at the step's end (x1, v1): f(s; x, v) is linear in x and v and
    f(root; x, v) = 0, so to first order s ~ root - (x1 - x + root^2 (v1 - v)) / f'(root).
    They depend only on the step's start, so they are ready (division included) before
    the step; ``predicted_start`` finishes the prediction.

    Parameters
    ----------
    root, slope_at_root : float
        s* and f'(s*) of ``criterion_root`` at the step's start.
    x, v : float
        The step's start.

    Returns
    -------
    tuple of float
        (k0, k1, k2).
    """
    k1 = 1.0 / slope_at_root if slope_at_root < 0.0 else 0.0
    k2 = k1 * root * root
    return fma(k2, v, fma(k1, x, root)), k1, k2


@njit(cache=True, inline="always")
def predicted_start(predictor, root, x1, v1):
    """The start of ``criterion_root`` at the end (x1, v1) of a step.

    Parameters
    ----------
    predictor : tuple of float
        (k0, k1, k2) of ``root_predictor``.
    root : float
        The previous root.
    x1, v1 : float
        The step's end.

    Returns
    -------
    float
        The first-order prediction k0 - k1 x1 - k2 v1, or the previous root where the
        prediction is not positive.
    """
    k0, k1, k2 = predictor
    predicted = fma(-k2, v1, fma(-k1, x1, k0))
    return predicted if predicted > 0.0 else root


@njit(cache=True)
def largest_safe_step(x, v, c):
    """The largest step D(x, v) allowed by eq. (criterion).

    Parameters
    ----------
    x, v : float
        Position and velocity.
    c : float
        The constant c of eq. (criterion).

    Returns
    -------
    float
        s*^2 of ``criterion_root`` from the fitted start (0 when x <= 0 and v <= 0).
    """
    s, _ = criterion_root(x, v, c, 0.0)
    return s * s


@njit(cache=True)
def hermite_cubic(x0, v0, x1, v1, dt):
    """Monomial coefficients of the bridge mean path m(t) on [0, dt].

    The cubic Hermite interpolant of the step's ends: the mean of the Gaussian bridge of
    eq. (eqmo) given both ends (see the module's account).

    Parameters
    ----------
    x0, v0 : float
        Position and velocity at t = 0.
    x1, v1 : float
        Position and velocity at t = dt.
    dt : float
        The step, > 0.

    Returns
    -------
    a0, a1, a2, a3 : float
        m(t) = a0 + a1 t + a2 t^2 + a3 t^3.

    Examples
    --------
    The ends of a noiseless step of gravity give back its parabola, 1 - t^2/2:

    >>> from bouncing_ball.free_flight import hermite_cubic
    >>> hermite_cubic.py_func(1.0, 0.0, 0.5, -1.0, 1.0)
    (1.0, 0.0, -0.5, 0.0)
    """
    inv_dt = 1.0 / dt
    slope = (x1 - x0) * inv_dt
    a2 = (3.0 * slope - 2.0 * v0 - v1) * inv_dt
    a3 = (v0 + v1 - 2.0 * slope) * (inv_dt * inv_dt)
    return x0, v0, a2, a3


@njit(cache=True)
def cubic_value(a0, a1, a2, a3, t):
    """The mean path m(t) = a0 + a1 t + a2 t^2 + a3 t^3 (Horner, in fused multiply-adds).

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The coefficients of ``hermite_cubic``.
    t : float
        The time in the step.

    Returns
    -------
    float

    Examples
    --------
    >>> from bouncing_ball.free_flight import cubic_value
    >>> cubic_value.py_func(1.0, 0.0, -0.5, 0.0, 1.0)
    0.5
    """
    return fma(t, fma(t, fma(t, a3, a2), a1), a0)


@njit(cache=True)
def cubic_slope(a1, a2, a3, t):
    """The mean path's slope m'(t) = a1 + 2 a2 t + 3 a3 t^2: the mean velocity.

    By Horner's rule in fused multiply-adds, as ``cubic_value``.

    Parameters
    ----------
    a1, a2, a3 : float
        The coefficients of ``hermite_cubic`` (a0 does not enter).
    t : float
        The time in the step.

    Returns
    -------
    float
    """
    return fma(t, fma(3.0 * t, a3, 2.0 * a2), a1)


@njit(cache=True)
def mean_path_integrals(a0, a1, a2, a3, dt, tau):
    """E[int_0^tau x dt'] and E[int_0^tau x^2 dt'] given the ends of a step.

    The first is the integral of the mean path; the second adds the bridge
    variance of x to its square.  They make the tallies of <x> and <x^2>
    (eq. (xandDeltax)) exact in expectation.

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    dt : float
        The step.
    tau : float
        The upper limit, 0 <= tau <= dt (< dt where a collision cuts the step).

    Returns
    -------
    int_x, int_x2 : float

    Examples
    --------
    At rest at x = 1 over a unit step, the bridge adds int 2 t^3 (1 - t)^3 / 3 dt = 1/210:

    >>> from bouncing_ball.free_flight import mean_path_integrals
    >>> int_x, int_x2 = mean_path_integrals.py_func(1.0, 0.0, 0.0, 0.0, 1.0, 1.0)
    >>> print(int_x, round((int_x2 - 1.0) * 210, 12))
    1.0 1.0
    """
    int_x = tau * (a0 + tau * (0.5 * a1 + tau * ((1.0 / 3.0) * a2 + tau * 0.25 * a3)))
    c0 = a0 * a0
    c1 = 2.0 * a0 * a1
    c2 = a1 * a1 + 2.0 * a0 * a2
    c3 = 2.0 * (a0 * a3 + a1 * a2)
    c4 = a2 * a2 + 2.0 * a1 * a3
    c5 = 2.0 * a2 * a3
    c6 = a3 * a3
    int_m2 = tau * (
        c0
        + tau
        * (
            0.5 * c1
            + tau
            * (
                (1.0 / 3.0) * c2
                + tau
                * (
                    0.25 * c3
                    + tau * ((1.0 / 5.0) * c4 + tau * ((1.0 / 6.0) * c5 + tau * (1.0 / 7.0) * c6))
                )
            )
        )
    )
    # int_0^tau 2 t^3 (dt - t)^3 / (3 dt^3) dt
    u = tau / dt
    tau2 = tau * tau
    int_var = (2.0 / 3.0) * tau2 * tau2 * (0.25 - u * (3.0 / 5.0 - u * (0.5 - u * (1.0 / 7.0))))
    return int_x, int_m2 + int_var


@njit(cache=True, inline="always")
def whole_step_integrals(x0, v0, x1, v1, dt):
    """``mean_path_integrals`` over a whole step (tau = dt), from its two ends: no cubic.

    Over [0, dt] the integrals of the cubic Hermite mean path and of its square are the
    Hermite mass matrix applied to the ends (x0, v0), (x1, v1), and the bridge variance of x
    integrates to dt^4 / 210.  Equal to ``mean_path_integrals`` of ``hermite_cubic`` at
    tau = dt up to rounding, with no division and a third of the operations: the shard loop
    takes it for every step not cut by a collision.

    Parameters
    ----------
    x0, v0 : float
        Position and velocity at the step's start.
    x1, v1 : float
        Position and velocity at its end.
    dt : float
        The step.

    Returns
    -------
    int_x, int_x2 : float

    Examples
    --------
    >>> from bouncing_ball.free_flight import whole_step_integrals
    >>> int_x, int_x2 = whole_step_integrals.py_func(1.0, 0.0, 1.0, 0.0, 1.0)
    >>> print(int_x, round((int_x2 - 1.0) * 210, 12))
    1.0 1.0
    """
    int_x = dt * fma(dt * (1.0 / 12.0), v0 - v1, 0.5 * (x0 + x1))
    m0 = fma(13.0 / 35.0, fma(x0, x0, x1 * x1), (9.0 / 35.0) * (x0 * x1))
    m1 = fma(11.0 / 105.0, fma(x0, v0, -(x1 * v1)), (13.0 / 210.0) * fma(x1, v0, -(x0 * v1)))
    m2 = fma(1.0 / 105.0, fma(v0, v0, v1 * v1), -(1.0 / 70.0) * (v0 * v1))
    return int_x, dt * fma(dt, fma(dt, fma(dt, 1.0 / 210.0, m2), m1), m0)


def bridge_covariance(dt, t):
    """The covariance of (x(t), v(t)) on the bridge of a step, given both ends.

    Conditioning the integrated Brownian motion (x, v) of eq. (eqmo) at t on its value at dt
    (Schur complement of the joint covariance; with w = u (1 - u), u = t / dt):
    Var x = (2/3) dt^3 w^3, Cov = dt^2 w^2 (1 - 2u), Var v = 2 dt w (1 - 3w).

    Parameters
    ----------
    dt : float
        The step's length.
    t : array_like
        Times in the step, 0 <= t <= dt.

    Returns
    -------
    var_x, cov_xv, var_v : numpy.ndarray

    Examples
    --------
    In the middle of a unit step (w = 1/4):

    >>> from bouncing_ball.free_flight import bridge_covariance
    >>> print([round(float(value), 12) for value in bridge_covariance(1.0, 0.5)])
    [0.010416666667, 0.0, 0.125]
    """
    u = np.asarray(t, dtype=float) / dt
    w = u * (1.0 - u)
    return (
        (2.0 / 3.0) * dt**3 * w**3,
        dt**2 * w**2 * (1.0 - 2.0 * u),
        2.0 * dt * w * (1.0 - 3.0 * w),
    )


@njit(cache=True)
def bridge_sample(a0, a1, a2, a3, dt, t, normal_1, normal_2):
    """(x(t), v(t)) on the bridge of a step of length dt, given its ends (``a``: the mean path).

    The mean is (m(t), m'(t)); with w = u (1 - u), u = t / dt, the covariance
    of ``bridge_covariance`` factors as x = m + (2/3)^(1/2) dt w (dt w)^(1/2) n1 and
    v = m' + (dt w)^(1/2) ((3/2)^(1/2) (1 - 2u) n1 + (1/2)^(1/2) n2): Var v given x
    is dt w / 2.

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    dt : float
        The step.
    t : float
        The time in the step.
    normal_1, normal_2 : float
        Independent standard normals.

    Returns
    -------
    x, v : float
    """
    u = t * (1.0 / dt)
    w = max(u * (1.0 - u), 0.0)  # u may exceed 1 by a rounding error at t = dt
    root = math.sqrt(dt * w)
    x = cubic_value(a0, a1, a2, a3, t) + SQRT2_3 * dt * w * root * normal_1
    v = cubic_slope(a1, a2, a3, t) + root * (
        SQRT3_2 * (1.0 - 2.0 * u) * normal_1 + SQRT1_2 * normal_2
    )
    return x, v


@njit(cache=True)
def bridge_speed_squared_given_position(a1, a2, a3, dt, t, normal_1):
    """E[v(t)^2 | x(t), ends] for the x(t) that ``bridge_sample`` draws with ``normal_1``.

    In ``bridge_sample``'s factorisation, x(t) fixes normal_1, and v(t) given x(t) is
    Gaussian with mean m'(t) + (3/2)^(1/2) (dt w)^(1/2) (1 - 2u) normal_1 and variance
    dt w / 2 (w = u (1 - u), u = t / dt).  Averaged over normal_1 it is E[v(t)^2 | ends],
    the integrand of ``speed_squared_coefficients``.  It makes the <v^2>_x tally
    (eq. (moment2)) exact in expectation.

    Parameters
    ----------
    a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    dt : float
        The step.
    t : float
        The time in the step.
    normal_1 : float
        The normal ``bridge_sample`` drew x(t) with.

    Returns
    -------
    float
    """
    u = t * (1.0 / dt)
    w = max(u * (1.0 - u), 0.0)
    root = math.sqrt(dt * w)
    mean = cubic_slope(a1, a2, a3, t) + root * SQRT3_2 * (1.0 - 2.0 * u) * normal_1
    return mean * mean + 0.5 * dt * w


@njit(cache=True)
def speed_squared_coefficients(a1, a2, a3, dt):
    """The coefficients of S(t) = int_0^t E[v(t')^2 | ends] dt' on a step.

    S(t) = t (s1 + t (s2 + t (s3 + t (s4 + t s5)))): the mean slope squared,
    (a1 + 2 a2 t + 3 a3 t^2)^2, plus Var[v(t) | ends],
    2 t (dt - t)(dt^2 - 3 t dt + 3 t^2) / dt^3 = 2 t - 8 t^2/dt + 12 t^3/dt^2 - 6 t^4/dt^3.

    Parameters
    ----------
    a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    dt : float
        The step.

    Returns
    -------
    s1, s2, s3, s4, s5 : float

    Examples
    --------
    Over a whole unit step at unit mean velocity, S(1) = 1 + int_0^1 Var v dt = 1 + 2/15:

    >>> from bouncing_ball.free_flight import (
    ...     quintic_antiderivative_value, speed_squared_coefficients)
    >>> coefficients = speed_squared_coefficients.py_func(1.0, 0.0, 0.0, 1.0)
    >>> print(round(quintic_antiderivative_value.py_func(*coefficients, 1.0), 12))
    1.133333333333
    """
    inv_dt = 1.0 / dt
    s1 = a1 * a1
    s2 = 2.0 * a1 * a2 + 1.0
    s3 = (4.0 / 3.0) * a2 * a2 + 2.0 * a1 * a3 - (8.0 / 3.0) * inv_dt
    s4 = 3.0 * a2 * a3 + 3.0 * inv_dt * inv_dt
    s5 = (9.0 / 5.0) * a3 * a3 - (6.0 / 5.0) * inv_dt * inv_dt * inv_dt
    return s1, s2, s3, s4, s5


@njit(cache=True)
def quintic_antiderivative_value(s1, s2, s3, s4, s5, t):
    """S(t) = t (s1 + t (s2 + t (s3 + t (s4 + t s5)))) (Horner, in fused multiply-adds).

    Parameters
    ----------
    s1, s2, s3, s4, s5 : float
        The coefficients of ``speed_squared_coefficients``.
    t : float
        The time in the step.

    Returns
    -------
    float
    """
    return t * fma(t, fma(t, fma(t, fma(t, s5, s4), s3), s2), s1)


@njit(cache=True, inline="always")
def piece_inverse(t_lo, t_hi, x_lo, x_hi, d_lo, d_hi):
    """The inverse of a monotone piece of the mean path, as ``level_time`` needs it.

    What ``level_time`` needs of a monotone piece [t_lo, t_hi] of the mean path, from
    x_lo, x_hi and the slopes d_lo, d_hi at its ends (its divisions, done once a piece):
    (t_lo, width, x_lo, rise, 1 / rise, m0, m1), where m0 and m1 are the end slopes of
    the inverse t(m) on [0, 1] x [0, 1] (0, 0 where an end slope is below 0.1 of the
    piece's mean slope, next to a zero of m': the start is then linear).

    Parameters
    ----------
    t_lo, t_hi : float
        The piece's ends.
    x_lo, x_hi : float
        The mean path there.
    d_lo, d_hi : float
        Its slopes there.

    Returns
    -------
    tuple of float
        (t_lo, width, x_lo, rise, 1 / rise, m0, m1).
    """
    width = t_hi - t_lo
    rise = x_hi - x_lo
    inv_rise = 1.0 / rise
    m0 = m1 = 0.0
    if d_lo * rise * width > 0.1 * rise * rise and d_hi * rise * width > 0.1 * rise * rise:
        inv = rise / (d_lo * d_hi * width)
        m0 = d_hi * inv  # (rise / width) / m'(t_lo)
        m1 = d_lo * inv
    return t_lo, width, x_lo, rise, inv_rise, m0, m1


@njit(cache=True, inline="always")
def _level_time_estimate(level, inverse):
    """The start of ``level_time``: the inverse cubic Hermite interpolant t(m) through the
    ends of the monotone piece (their values and slopes 1/m'), or the linear one next to a
    zero of m' (``inverse``: the piece's ``piece_inverse``).  No iteration: its error is
    below 1e-3 of the piece for about 60 % of the crossings of simulated steps and up to
    a few tenths of it next to a turning point."""
    t_lo, width, x_lo, rise, inv_rise, m0, m1 = inverse
    u = (level - x_lo) * inv_rise
    if m0 == 0.0:
        return t_lo + width * u
    return t_lo + width * (u * u * (3.0 - 2.0 * u) + u * (1.0 - u) * ((1.0 - u) * m0 - u * m1))


@njit(cache=True, inline="always")
def level_time_one_step(a0, a1, a2, a3, level, inverse):
    """The time the mean path crosses a level, to one Halley step (no test, no iteration).

    ``_level_time_estimate`` and one Halley step from it, with no test and no iteration
    (it may leave the piece, or be NaN where m' vanishes: the caller clips it).  On the
    crossings of simulated steps (r = 1/2, c = 5) its error is below 1e-9 of the piece for
    about 70 % of them and below 3e-3 for 99 %; next to a turning point it can be a few
    tenths of the piece.  The P(x) tally uses it: its errors only move time between
    neighbouring bins of one step's assignment, which the tally's bridge correction
    undoes in expectation (``simulation``).

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    level : float
        The height crossed.
    inverse : tuple of float
        The piece's ``piece_inverse``.

    Returns
    -------
    float
        The time of the crossing, unclipped.
    """
    t = _level_time_estimate(level, inverse)
    f = cubic_value(a0, a1, a2, a3, t) - level
    d1 = cubic_slope(a1, a2, a3, t)
    d2 = 2.0 * a2 + 6.0 * a3 * t
    return t - 2.0 * f * d1 / (2.0 * d1 * d1 - f * d2)


@njit(cache=True, inline="always")
def level_time(a0, a1, a2, a3, level, inverse):
    """The time the mean path crosses a level on a monotone piece, to about 1e-9 of the piece.

    The t where the mean path m(t) = level on a monotone piece that brackets it
    (``inverse``: the piece's ``piece_inverse``), to about 1e-9 of the piece: where a
    collision cuts a step (``first_crossing_time``), and the P(x) tally's edge crossings
    in such a step; its other crossings use ``level_time_one_step``.

    The start is ``_level_time_estimate``: the inverse cubic Hermite interpolant t(m)
    through the piece's ends (their values and slopes 1/m'), or the linear one next to a
    zero of m'.
    Safeguarded Halley iteration follows: a step that leaves the bracket is
    replaced by bisection, so it always converges.  It stops after a Halley
    step below 1e-3 of the piece where the slope there is at least 0.1 of the
    piece's mean slope: the error before that step was about the step, and
    Halley's cubic convergence leaves about its cube, ~1e-9 of the piece
    (tests/unit/test_free_flight.py checks 1e-8 on random pieces; on the 2.7
    million bin-edge crossings of a simulated trajectory at r = 1/2, c = 5, 1 in 1000 is
    off by more than 1e-9 of its piece and the worst by 2e-7).  Crossings take 1.44
    Halley steps on average from the Hermite start (2.2 from the linear one).  Next to
    a zero of m' (a piece ends where the path turns) a Halley step is short because m'
    is small, not because the root is near; such a step is replaced by bisection, which
    stops when the bracket is 1e-10 of the piece.  The crossings of one piece do not depend
    on each other, so the processor overlaps them.

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    level : float
        The height crossed, between the piece's ends.
    inverse : tuple of float
        The piece's ``piece_inverse``.

    Returns
    -------
    float
        The time of the crossing.
    """
    t_lo, width, x_lo, rise, inv_rise, m0, m1 = inverse
    if (level - x_lo) * inv_rise <= 0.0:
        return t_lo
    rising = rise > 0.0
    lo, hi = t_lo, t_lo + width
    t = _level_time_estimate(level, inverse)
    for _ in range(200):
        f = cubic_value(a0, a1, a2, a3, t) - level
        if f == 0.0:
            return t
        if (f < 0.0) == rising:
            lo = t
        else:
            hi = t
        d1 = cubic_slope(a1, a2, a3, t)
        d2 = 2.0 * a2 + 6.0 * a3 * t
        t_new = t - 2.0 * f * d1 / (2.0 * d1 * d1 - f * d2)
        short = abs(t_new - t) <= 1e-3 * width
        # not lo < t_new < hi: outside the bracket, or a zero or NaN denominator
        if not lo < t_new < hi or (short and abs(d1) * width < 0.1 * abs(rise)):
            t_new = 0.5 * (lo + hi)  # bisect (also where a step is short only because m' is small)
            if hi - lo <= 1e-10 * width:
                return t_new
        elif short:
            return t_new
        t = t_new
    return t


@njit(cache=True, inline="always")
def cubic_level_time(a0, a1, a2, a3, level, t_lo, t_hi, x_lo, x_hi, d_lo, d_hi):
    """The t in [t_lo, t_hi] where the mean path m(t) = level (``level_time``, one crossing).

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The mean path (``hermite_cubic``), monotone on [t_lo, t_hi].
    level : float
        The height crossed, between x_lo and x_hi.
    t_lo, t_hi : float
        The piece's ends.
    x_lo, x_hi : float
        m there.
    d_lo, d_hi : float
        m' there.

    Returns
    -------
    float
    """
    return level_time(a0, a1, a2, a3, level, piece_inverse(t_lo, t_hi, x_lo, x_hi, d_lo, d_hi))


@njit(cache=True)
def slope_zeros(a1, a2, a3, t_end):
    """The zeros of the mean path's slope m'(t) strictly inside (0, t_end).

    Parameters
    ----------
    a1, a2, a3 : float
        The mean path (``hermite_cubic``).
    t_end : float
        The step's end.

    Returns
    -------
    count : int
        0, 1 or 2.
    t1, t2 : float
        The zeros, t1 < t2 (t_end where there is none).

    Examples
    --------
    m'(t) = 1 - 6 t + 3 t^2 vanishes at 1 -+ (2/3)^(1/2):

    >>> from bouncing_ball.free_flight import slope_zeros
    >>> count, t1, t2 = slope_zeros.py_func(1.0, -3.0, 1.0, 3.0)
    >>> print(count, round(t1, 10), round(t2, 10))
    2 0.1835034191 1.8164965809
    """
    a, b, c = 3.0 * a3, 2.0 * a2, a1
    t1 = t_end
    t2 = t_end
    n = 0
    if a == 0.0:
        if b != 0.0:
            r = -c / b
            if 0.0 < r < t_end:
                t1 = r
                n = 1
        return n, t1, t2
    disc = b * b - 4.0 * a * c
    if disc <= 0.0:
        return 0, t1, t2
    sq = math.sqrt(disc)
    qq = -0.5 * (b + sq) if b >= 0.0 else -0.5 * (b - sq)
    r1 = qq / a
    r2 = c / qq if qq != 0.0 else r1
    if r1 > r2:
        r1, r2 = r2, r1
    if 0.0 < r1 < t_end:
        t1 = r1
        n = 1
    if 0.0 < r2 < t_end and r2 > r1:
        if n == 0:
            t1 = r2
        else:
            t2 = r2
        n += 1
    return n, t1, t2


@njit(cache=True, inline="always")
def monotone_piece_end(piece, n_zero, t1, t2, t_end):
    """The end of a monotone piece of [0, t_end], split at the slope zeros t1 < t2.

    Parameters
    ----------
    piece : int
        The piece, 0, 1 or 2.
    n_zero : int
        The number of slope zeros (``slope_zeros``).
    t1, t2 : float
        The zeros.
    t_end : float
        The step's end.

    Returns
    -------
    float
    """
    if piece == 0 and n_zero >= 1:
        return t1
    if piece == 1 and n_zero == 2:
        return t2
    return t_end


@njit(cache=True)
def first_crossing_time(a0, a1, a2, a3, t_end, x_end):
    """The first t in (0, t_end] where the mean path reaches the floor, x = 0.

    Where a collision cuts a step.  The path is split at the zeros of m' into monotone
    pieces; the first piece that ends at or below 0 holds the crossing.

    Parameters
    ----------
    a0, a1, a2, a3 : float
        The mean path (``hermite_cubic``), m(0) = a0 > 0.
    t_end : float
        The step's end.
    x_end : float
        m(t_end) <= 0.

    Returns
    -------
    float
    """
    n, t1, t2 = slope_zeros(a1, a2, a3, t_end)
    start = 0.0
    m_start = a0
    for k in range(n + 1):
        stop = monotone_piece_end(k, n, t1, t2, t_end)
        m_stop = x_end if stop == t_end else cubic_value(a0, a1, a2, a3, stop)
        if m_stop <= 0.0:
            return cubic_level_time(
                a0,
                a1,
                a2,
                a3,
                0.0,
                start,
                stop,
                m_start,
                m_stop,
                cubic_slope(a1, a2, a3, start),
                cubic_slope(a1, a2, a3, stop),
            )
        start = stop
        m_start = m_stop
    return t_end
