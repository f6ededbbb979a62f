"""Free flight of the randomly accelerated particle in gravity (g = Lambda = 1).

Between collisions the particle obeys eq. (eqmo) with no boundary.  Over a
step of length ``dt`` the update of eqs. (xstep), (vstep) is exact in
distribution.  Given both ends of a step, the path in between is a Gaussian
bridge whose mean is the cubic Hermite interpolant of the two ends (the
covariances of integrated Brownian motion are cubic in time, and Hermite
interpolation reproduces the cubic drift term -t^2/2); its variances are

    Var[x(t) | ends] = 2 t^3 (dt - t)^3 / (3 dt^3)
    Var[v(t) | ends] = 2 t (dt - t) (dt^2 - 3 t dt + 3 t^2) / dt^3

(the factor 2 is the noise strength 2 Lambda of eq. (eqmo)).  The simulation
uses these to integrate x, x^2 and v^2 over a step exactly in expectation and
to place a collision inside a step.

Everything here is numba-compiled scalar code (no allocation), because it
runs once or more per step.  The mean path is carried as its four monomial
coefficients ``a0 + a1 t + a2 t^2 + a3 t^3``.
"""

import math

import numpy as np
from numba import njit

SQRT3 = math.sqrt(3.0)


@njit(cache=True)
def free_flight_step(x, v, dt, normal_r, normal_s):
    """One exact free-flight step, eqs. (xstep) and (vstep).

    ``normal_r`` and ``normal_s`` are independent standard normals; the same
    ``normal_r`` enters both equations, which gives the correct x-v covariance.
    """
    x_new = (
        x
        + v * dt
        - 0.5 * dt * dt
        + math.sqrt(dt * dt * dt / 6.0) * (normal_s + SQRT3 * normal_r)
    )
    v_new = v - dt + math.sqrt(2.0 * dt) * normal_r
    return x_new, v_new


@njit(cache=True)
def largest_safe_step(x, v, c):
    """The largest step D(x, v) allowed by eq. (criterion).

    With s = sqrt(Delta) the criterion reads f(s) = x + v s^2 - c s^3 - s^4/2 > 0.
    By Descartes' rule f has exactly one positive root s*; f is convex and
    increasing from s = 0 up to its inflection point, so s* lies where f is
    concave and decreasing, and Newton's method started above s* decreases
    monotonically onto it.  Returns s*^2 (0 when x <= 0 and v <= 0).
    """
    vp = v if v > 0.0 else 0.0
    if x < 0.0:
        x = 0.0
    if x == 0.0 and vp == 0.0:
        return 0.0
    # Two upper bounds: c s^3 alone, or s^4/2 alone, outweighs x + v s^2.
    bound_cubic = max(np.cbrt(2.0 * x / c), 2.0 * vp / c)
    bound_quartic = max(math.sqrt(2.0 * math.sqrt(x)), 2.0 * math.sqrt(vp))
    s = min(bound_cubic, bound_quartic)
    for _ in range(100):
        f = x + s * s * (v - s * (c + 0.5 * s))
        fp = s * (2.0 * v - s * (3.0 * c + 2.0 * s))
        if fp >= 0.0:  # impossible above s*; guards against round-off
            break
        step = f / fp
        s -= step
        if step <= 1e-7 * s:  # quadratic convergence: s is now good to ~1e-14
            break
    return s * s


@njit(cache=True)
def hermite_cubic(x0, v0, x1, v1, dt):
    """Monomial coefficients of the bridge mean path m(t) on [0, dt]."""
    slope = (x1 - x0) / dt
    a2 = (3.0 * slope - 2.0 * v0 - v1) / dt
    a3 = (v0 + v1 - 2.0 * slope) / (dt * dt)
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
    int_x = tau * (a0 + tau * (a1 / 2.0 + tau * (a2 / 3.0 + tau * a3 / 4.0)))
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
            c1 / 2.0
            + tau
            * (c2 / 3.0 + tau * (c3 / 4.0 + tau * (c4 / 5.0 + tau * (c5 / 6.0 + tau * c6 / 7.0))))
        )
    )
    # int_0^tau 2 t^3 (dt - t)^3 / (3 dt^3) dt
    u = tau / dt
    int_var = (2.0 / 3.0) * dt**4 * u**4 * (
        0.25 - u * (3.0 / 5.0 - u * (0.5 - u / 7.0))
    )
    return int_x, int_m2 + int_var


@njit(cache=True)
def speed_squared_antiderivative(a1, a2, a3, dt, t):
    """int_0^t E[v(t')^2 | ends] dt' : the mean slope squared plus Var[v]."""
    # (a1 + 2 a2 t + 3 a3 t^2)^2
    d0 = a1 * a1
    d1 = 4.0 * a1 * a2
    d2 = 4.0 * a2 * a2 + 6.0 * a1 * a3
    d3 = 12.0 * a2 * a3
    d4 = 9.0 * a3 * a3
    mean_part = t * (d0 + t * (d1 / 2.0 + t * (d2 / 3.0 + t * (d3 / 4.0 + t * d4 / 5.0))))
    # int_0^t 2 t'(dt - t')(dt^2 - 3 t' dt + 3 t'^2) / dt^3 dt'
    u = t / dt
    var_part = 2.0 * dt * dt * u * u * (0.5 - u * (4.0 / 3.0 - u * (1.5 - u * 3.0 / 5.0)))
    return mean_part + var_part


@njit(cache=True)
def cubic_level_time(a0, a1, a2, a3, level, t_lo, t_hi):
    """The t in [t_lo, t_hi] where m(t) = level, m monotone there and bracketing.

    Safeguarded Newton: a Newton step that leaves the bracket is replaced by
    bisection, so it always converges.
    """
    f_lo = cubic_value(a0, a1, a2, a3, t_lo) - level
    if f_lo == 0.0:
        return t_lo
    rising = f_lo < 0.0
    lo, hi = t_lo, t_hi
    # start from the linear interpolation between the bracket ends
    f_hi = cubic_value(a0, a1, a2, a3, t_hi) - level
    t = t_lo + (t_hi - t_lo) * f_lo / (f_lo - f_hi) if f_lo != f_hi else 0.5 * (t_lo + t_hi)
    for _ in range(200):
        f = cubic_value(a0, a1, a2, a3, t) - level
        if f == 0.0:
            return t
        if (f < 0.0) == rising:
            lo = t
        else:
            hi = t
        d = cubic_slope(a1, a2, a3, t)
        t_new = t - f / d if d != 0.0 else 0.5 * (lo + hi)
        if not (lo < t_new < hi):
            t_new = 0.5 * (lo + hi)
        # 1e-10 of the bracket: far below any statistical resolution of a bin
        if abs(t_new - t) <= 1e-10 * (t_hi - t_lo) or hi - lo <= 1e-15 * hi:
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


@njit(cache=True)
def first_crossing_time(a0, a1, a2, a3, t_end):
    """First t in (0, t_end] where the mean path reaches 0.

    Requires m(0) > 0 >= m(t_end).  The path is split at the zeros of m' into
    monotone pieces; the first piece that ends at or below 0 holds the crossing.
    """
    n, t1, t2 = slope_zeros(a1, a2, a3, t_end)
    start = 0.0
    for k in range(n + 1):
        stop = t_end
        if k == 0 and n >= 1:
            stop = t1
        elif k == 1 and n == 2:
            stop = t2
        if cubic_value(a0, a1, a2, a3, stop) <= 0.0:
            return cubic_level_time(a0, a1, a2, a3, 0.0, start, stop)
        start = stop
    return t_end
