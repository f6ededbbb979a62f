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
(``bridge_sample``) for the time-weighted P(x, v).

Everything here is numba-compiled scalar code (no allocation, no division by
a constant: those are written as products with the reciprocal, which LLVM
folds), because it runs once or more per step.  The mean path is carried as
its four monomial coefficients ``a0 + a1 t + a2 t^2 + a3 t^3``.
"""

import math

import numpy as np

from .jit import njit

SQRT3 = math.sqrt(3.0)
SQRT1_12 = math.sqrt(1.0 / 12.0)
SQRT2_3 = math.sqrt(2.0 / 3.0)
SQRT3_2 = math.sqrt(1.5)
SQRT1_2 = math.sqrt(0.5)

# Rational fits (see largest_safe_step) to the positive root of the cubic
# c s^3 = x + v s^2, in units of a = (x/c)^(1/3), with t = |v| / (c a).
# The forms have the right limits (s/a -> 1 at t = 0; s/a -> t, resp.
# t^(-1/2), for t -> inf); the constants are least-squares fits of the
# relative error over a log grid of t.  They only set Halley's starting
# point: any start within a few per cent gives the same root.
#   v >= 0:  s / a ~ t + (1 + P t) / (1 + (P + 2/3) t + Q t^2 + P t^3)   (0.2 %)
#   v < 0:   s / a ~ (t + (1 + N3 t) / (1 + N1 t + N2 t^2))^(-1/2)      (0.04 %)
_P, _Q = 0.44356066, 0.56163652
_N1, _N2, _N3 = 0.40104058, 0.00211799, 0.06071102

_SMALLEST_NORMAL = np.finfo(np.float64).tiny


@njit(cache=True)
def free_flight_step(x, v, dt, normal_r, normal_s):
    """One exact free-flight step, eqs. (xstep) and (vstep).

    ``normal_r`` and ``normal_s`` are independent standard normals; the same
    ``normal_r`` enters both equations, which gives the correct x-v covariance.
    The two noise amplitudes share one square root:
    sqrt(dt^3 / 6) = dt sqrt(2 dt) / sqrt(12).
    """
    root_2dt = math.sqrt(2.0 * dt)
    x_new = x + v * dt - 0.5 * dt * dt + dt * root_2dt * SQRT1_12 * (normal_s + SQRT3 * normal_r)
    v_new = v - dt + root_2dt * normal_r
    return x_new, v_new


@njit(cache=True, inline="always")
def largest_safe_step(x, v, c):
    """The largest step D(x, v) allowed by eq. (criterion).

    With s = sqrt(Delta) the criterion reads f(s) = x + v s^2 - c s^3 - s^4/2 > 0.
    By Descartes' rule f has exactly one positive root s*, where f' < 0;
    returns s*^2 (0 when x <= 0 and v <= 0; x below the smallest normal
    double counts as 0).

    At x = 0 the root is that of a quadratic.  Otherwise the start is the
    root of the cubic without the s^4/2 term, from the rational fits above
    (homogeneous in a and v/c, one division); near the floor, where most
    steps are taken, that term is a small correction.  Halley's method then
    converges cubically: two iterations from a start good to ~1 %, and a
    last step of relative size <= 1e-5 leaves s* good to ~1e-14.  A Newton
    step stands in where the Halley denominator is not positive (only far
    from s*), and the iteration stops where f' >= 0 (only on underflow).
    """
    if x < _SMALLEST_NORMAL:
        if v <= 0.0:
            return 0.0
        s = 2.0 * v / (c + math.sqrt(c * c + 2.0 * v))  # s^2 (v - c s - s^2/2) = 0
        return s * s
    a3 = x / c
    a = np.cbrt(a3)
    b = v / c
    if b >= 0.0:
        a2 = a * a
        s = b + a * (
            (a3 + _P * a2 * b) / (a3 + b * (a2 * (_P + 2.0 / 3.0) + b * (_Q * a + _P * b)))
        )
    else:
        a2 = a * a
        s = math.sqrt(a3 / (-b + a2 * (a - _N3 * b) / (a2 - b * (_N1 * a - _N2 * b))))
    for _ in range(100):
        f = x + s * s * (v - s * (c + 0.5 * s))
        fp = s * (2.0 * v - s * (3.0 * c + 2.0 * s))
        if not fp < 0.0:
            break
        fpp = 2.0 * v - s * (6.0 * c + 6.0 * s)
        denominator = 2.0 * fp * fp - f * fpp
        step = 2.0 * f * fp / denominator if denominator > 0.0 else f / fp
        s -= step
        if abs(step) <= 1e-5 * s:
            break
    return s * s


@njit(cache=True)
def hermite_cubic(x0, v0, x1, v1, dt):
    """Monomial coefficients of the bridge mean path m(t) on [0, dt]."""
    inv_dt = 1.0 / dt
    slope = (x1 - x0) * inv_dt
    a2 = (3.0 * slope - 2.0 * v0 - v1) * inv_dt
    a3 = (v0 + v1 - 2.0 * slope) * (inv_dt * inv_dt)
    return x0, v0, a2, a3


@njit(cache=True)
def cubic_value(a0, a1, a2, a3, t):
    return a0 + t * (a1 + t * (a2 + t * a3))


@njit(cache=True)
def cubic_slope(a1, a2, a3, t):
    return a1 + t * (2.0 * a2 + t * 3.0 * a3)


@njit(cache=True)
def mean_path_integrals(a0, a1, a2, a3, dt, tau):
    """E[int_0^tau x dt'] and E[int_0^tau x^2 dt'] given the ends of a step.

    The first is the integral of the mean path; the second adds the bridge
    variance of x to its square.
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


def bridge_covariance(dt, t):
    """(Var x, Cov(x, v), Var v) of the bridge at time t of a step of length dt, given its ends.

    Conditioning the integrated Brownian motion (x, v) at t on its value at dt
    (Schur complement of the joint covariance; with w = u (1 - u), u = t / dt):
    Var x = (2/3) dt^3 w^3, Cov = dt^2 w^2 (1 - 2u), Var v = 2 dt w (1 - 3w).
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
    is dt w / 2.  ``normal_1``, ``normal_2`` are independent standard normals.
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
def speed_squared_coefficients(a1, a2, a3, dt):
    """S(t) = int_0^t E[v(t')^2 | ends] dt' = t (s1 + t (s2 + t (s3 + t (s4 + t s5)))).

    The mean slope squared, (a1 + 2 a2 t + 3 a3 t^2)^2, plus Var[v(t) | ends],
    2 t (dt - t)(dt^2 - 3 t dt + 3 t^2) / dt^3 = 2 t - 8 t^2/dt + 12 t^3/dt^2 - 6 t^4/dt^3.
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
    return t * (s1 + t * (s2 + t * (s3 + t * (s4 + t * s5))))


@njit(cache=True, inline="always")
def cubic_level_time(a0, a1, a2, a3, level, t_lo, t_hi, f_lo, f_hi):
    """The t in [t_lo, t_hi] where m(t) = level, m monotone there and bracketing.

    ``f_lo`` and ``f_hi`` are m - level at the two ends (opposite signs, or
    f_lo = 0).  Safeguarded Halley iteration from the linear interpolation of
    the ends: a step that leaves the bracket is replaced by bisection, so it
    always converges.  It stops after a Halley step below 1e-5 of the bracket
    where the slope there is at least 0.1 of the bracket's mean slope: then m'
    changes by < 1e-3 over the step, the step measures the distance to the
    root and the error left is at rounding (most crossings need one or two
    steps from the linear start).  Next to a zero of m' (a piece ends where
    the path turns) a Halley step is short because m' is small, not because
    the root is near; such a step is replaced by bisection, which stops when
    the bracket is 1e-10 of its start.
    """
    if f_lo == 0.0:
        return t_lo
    rising = f_lo < 0.0
    width = t_hi - t_lo
    lo, hi = t_lo, t_hi
    t = t_lo + width * f_lo / (f_lo - f_hi)
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
        short = abs(t_new - t) <= 1e-5 * width
        # not lo < t_new < hi: outside the bracket, or a zero or NaN denominator
        if not lo < t_new < hi or (short and abs(d1) * width < 0.1 * abs(f_hi - f_lo)):
            t_new = 0.5 * (lo + hi)  # bisect (also where a step is short only because m' is small)
            if hi - lo <= 1e-10 * width:
                return t_new
        elif short:
            return t_new
        t = t_new
    return t


@njit(cache=True)
def slope_zeros(a1, a2, a3, t_end):
    """The zeros of m'(t) strictly inside (0, t_end), as (count, t1, t2), t1 < t2."""
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
    """End of monotone piece ``piece`` of [0, t_end] split at the slope zeros t1 < t2."""
    if piece == 0 and n_zero >= 1:
        return t1
    if piece == 1 and n_zero == 2:
        return t2
    return t_end


@njit(cache=True)
def first_crossing_time(a0, a1, a2, a3, t_end, x_end):
    """First t in (0, t_end] where the mean path reaches 0.

    Requires m(0) = a0 > 0 >= m(t_end) = x_end.  The path is split at the
    zeros of m' into monotone pieces; the first piece that ends at or below 0
    holds the crossing.
    """
    n, t1, t2 = slope_zeros(a1, a2, a3, t_end)
    start = 0.0
    m_start = a0
    for k in range(n + 1):
        stop = monotone_piece_end(k, n, t1, t2, t_end)
        m_stop = x_end if stop == t_end else cubic_value(a0, a1, a2, a3, stop)
        if m_stop <= 0.0:
            return cubic_level_time(a0, a1, a2, a3, 0.0, start, stop, m_start, m_stop)
        start = stop
        m_start = m_stop
    return t_end
