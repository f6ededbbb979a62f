"""P(x, v) next to the floor at large outgoing speeds: the Taylor series in x of eq. (fp).

Where v > 0 and x is small on the scale v^3, the F integral of eq. (fpsol) oscillates too fast
to evaluate (``airy.check_force_integral_point``), but there a ball at height x left the floor
a flight time ~ x / v ago, and P(x, v) is P(0, v) carried a short way up by eq. (fp),
v dP/dx = dP/dv + d^2P/dv^2.  At fixed v > 0 that is a first-order equation in x,
dP/dx = L P with L = v^-1 (d/dv + d^2/dv^2), so

    P(x, v) = sum_n x^n / n! (L^n P(0, .))(v).

With P(0, v) = e^g(v) and L^n P(0, .) = e^g p_n, p_0 = 1 and

    p_{n+1} = v^-1 [p_n'' + (1 + 2 g') p_n' + (g'' + g'^2 + g') p_n].

g = ln P(0, v) is a Chebyshev interpolant on [v - R, v + R], R = min(v / 2, 60 / q)
(``NEAR_WALL_NODES`` Chebyshev-Lobatto nodes, q the large-v decay rate of P(0, v)), and the
derivatives are its spectral derivatives at the nodes.  The terms fall like
(x q / v)^n / n! (gravity: the series of P(0, (v^2 + 2 x)^(1/2))) and (x q^2 / v)^n,
(x / v^3)^n (the noise).  The series stops where a term falls below 1e-17 of the sum; its
error estimate is the difference from the same series on a Chebyshev interpolant with every
other node (which measures the truncation and the interpolation), plus the series' response to
a rounding of ``FLOOR_NOISE`` of P(0, v) at the nodes in the highest Chebyshev mode (the
spectral derivatives amplify it by at most ~3 up to x = ``NEAR_WALL_REACH`` v^3, much less
where the series is used).  A smooth error of P(0, v) itself carries into P(x, v) one to one,
and is not in the estimate.  The contributions this expansion misses (the region v ~ x^(1/3) where
P(0, v) ~ v^-beta is singular, reached only by the noise) are of order e^(-v^3 / (9 x)): none
in doubles where the series is used, x <= ``NEAR_WALL_REACH`` v^3.
"""

import numpy as np

from .airy import LARGEST_AIRY_PHASE, force_integral_phase
from .asymptotics import large_speed_decay_rate

__all__ = [
    "NEAR_WALL_NODES",
    "NEAR_WALL_REACH",
    "NEAR_WALL_TOLERANCE",
    "NEAR_WALL_CELL_NODES",
    "FLOOR_NOISE",
    "near_wall_points",
    "distribution_near_wall",
    "distribution_near_wall_cell_average",
]


#: Chebyshev-Lobatto nodes of ln P(0, v) on each v's window; the check interpolant uses every
#: other one.
NEAR_WALL_NODES = 33


#: The series is used only for x <= NEAR_WALL_REACH v^3 (there x / v^3, the noise's expansion
#: parameter, and the spectral derivatives' rounding stay small; the F integral of eq. (fpsol)
#: takes over from x = 1.7e-8 v^3, ``airy.LARGEST_AIRY_PHASE``).
NEAR_WALL_REACH = 1.0e-6


#: The largest relative error estimate the series answers with; beyond it the point is refused.
NEAR_WALL_TOLERANCE = 1.0e-11


#: The relative rounding of P(0, v) at a window's nodes the error estimate carries through the
#: spectral derivatives (the solver's Nystrom formula is a sum of positive terms, each to
#: ~1e-15; its smooth error is P(0, v)'s own, carried into P(x, v) one to one).
FLOOR_NOISE = 1e-14


#: Gauss-Legendre nodes per panel in v of ``distribution_near_wall_cell_average``.
NEAR_WALL_CELL_NODES = 8


_MOST_TERMS = 200


def near_wall_points(x, v):
    """Where P(x, v) is the near-wall series rather than the F integral of eq. (fpsol).

    At x > 0, v > 0 where the Airy phase of the F integral passes ``airy.LARGEST_AIRY_PHASE``:
    x < 60 ((2/3) v^(3/2) / LARGEST_AIRY_PHASE)^2 = 1.7e-8 v^3 (``distribution_near_wall``).

    Parameters
    ----------
    x, v : array_like
        Heights and velocities; they broadcast.

    Returns
    -------
    numpy.ndarray
        Booleans, the broadcast shape.

    Examples
    --------
    >>> from bouncing_ball.near_wall import near_wall_points
    >>> near_wall_points([0.0, 1e-3, 1e-3, 1e-3], [5.0, 5.0, 50.0, -50.0])
    array([False, False,  True, False])
    """
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v, dtype=float))
    with np.errstate(invalid="ignore"):
        phase = force_integral_phase(np.where(x > 0.0, x, 1.0), v)
    return (x > 0.0) & (v > 0.0) & (phase > LARGEST_AIRY_PHASE)


def _chebyshev(count):
    """Chebyshev-Lobatto nodes on [-1, 1] (descending) and their differentiation matrix."""
    j = np.arange(count)
    nodes = np.cos(np.pi * j / (count - 1))
    c = np.where((j == 0) | (j == count - 1), 2.0, 1.0) * (-1.0) ** j
    difference = nodes[:, None] - nodes[None, :] + np.eye(count)
    matrix = np.outer(c, 1.0 / c) / difference
    matrix -= np.diag(matrix.sum(axis=1))
    return nodes, matrix


_NODES, _MATRIX = _chebyshev(NEAR_WALL_NODES)


_CHECK_NODES, _CHECK_MATRIX = _chebyshev((NEAR_WALL_NODES + 1) // 2)


_ALTERNATING = (-1.0) ** np.arange(NEAR_WALL_NODES)


def _window(speeds, restitution):
    """The half-width R of each v's window: v / 2, at most 60 / q."""
    return np.minimum(0.5 * speeds, 60.0 / large_speed_decay_rate(restitution))


def _coefficients(largest, speed, radius, log_density, nodes, matrix):
    """a_n = p_n(v) X^n / n! at the window's centre, X = ``largest`` (or 1 where it is 0),
    n = 0, 1, ..., until two terms in a row are below 1e-17 of the sum at x = X:
    ``log_density`` = ln P(0, .) at v = ``speed`` + ``radius`` ``nodes``, ``matrix`` the
    nodes' differentiation matrix on [-1, 1].  In the window's variable w = v' / v (D = d/dw,
    G1 = D g, G2 = D^2 g) the step is p_{n+1} = [D^2 p_n + (v + 2 G1) D p_n
    + (G2 + G1^2 + v G1) p_n] / (v^3 w): every factor stays O(1) at any v > 0."""
    scale = largest if largest > 0.0 else 1.0
    w = 1.0 + (radius / speed) * nodes
    matrix = matrix * (speed / radius)
    first = matrix @ log_density
    second = matrix @ first
    drift = speed + 2.0 * first
    rate = second + first * first + speed * first
    factor = scale / (speed**3 * w)
    centre = nodes.size // 2
    coefficients = [1.0]
    term = np.ones(nodes.size)
    total, small = 1.0, 0
    for n in range(1, _MOST_TERMS):
        slope = matrix @ term
        term = (matrix @ slope + drift * slope + rate * term) * (factor / n)
        coefficients.append(term[centre])
        total += term[centre]
        small = small + 1 if abs(term[centre]) <= 1e-17 * abs(total) else 0
        if small == 2:
            break
    return np.array(coefficients), scale


def _series_at(unique, largest, outgoing, restitution):
    """For each v of ``unique`` (with the largest x it serves, ``largest``): P(0, v) times the
    coefficients a_n of the series in x / X, of its check interpolant and of its response to
    rounding, and X (zeros where P(0, .) underflows on the window, P(0, v) below ~1e-280)."""
    radius = _window(unique, restitution)
    density = np.asarray(outgoing((unique[:, None] + radius[:, None] * _NODES).ravel()))
    density = density.reshape(unique.size, _NODES.size)
    out = []
    for k, speed in enumerate(unique):
        if not np.all(np.isfinite(density[k])):
            raise ValueError(
                f"v = {speed}: P(0, v) exceeds the largest double on the near-wall series' "
                f"window [{speed - radius[k]:.3g}, {speed + radius[k]:.3g}] (P(x, v) with it)"
            )
        if not np.all(density[k] > 0.0):
            out.append((np.zeros(1), np.zeros(1), np.zeros(1), 1.0))
            continue
        log_density = np.log(density[k])
        at = density[k, _NODES.size // 2]
        main, scale = _coefficients(largest[k], speed, radius[k], log_density, _NODES, _MATRIX)
        check, _ = _coefficients(
            largest[k], speed, radius[k], log_density[::2], _CHECK_NODES, _CHECK_MATRIX
        )
        # the spectral derivatives' response to a rounding of ln P(0, .) at the nodes: the
        # highest Chebyshev mode, (-1)^j (the worst case), of size 1e-8 (linear response)
        shaken, _ = _coefficients(
            largest[k], speed, radius[k], log_density + 1e-8 * _ALTERNATING, _NODES, _MATRIX
        )
        size = min(main.size, shaken.size)
        response = np.abs(shaken[:size] - main[:size]) / 1e-8
        out.append((at * main, at * check, at * FLOOR_NOISE * response, scale))
    return out


def _checked(value, error, x, speed):
    if np.any(~(error <= NEAR_WALL_TOLERANCE * np.abs(value))):
        worst = np.argmax(error / np.abs(value))
        raise ValueError(
            f"x = {np.ravel(x)[worst]}: at v = {speed} the near-wall series of P(x, v) "
            f"reaches only {np.ravel(error / np.abs(value))[worst]:.1e} relative (more than "
            f"{NEAR_WALL_TOLERANCE:g}); use a smaller x"
        )


def _check_domain(x, v):
    if np.any(~(v > 0.0) | ~np.isfinite(v)):
        raise ValueError("speeds: the near-wall series of P(x, v) needs finite v > 0")
    bad = ~(x >= 0.0) | ~(x <= NEAR_WALL_REACH * v**3)
    if np.any(bad):
        raise ValueError(
            f"x = {x[bad].flat[0]}: the near-wall series of P(x, v) holds for "
            f"0 <= x <= {NEAR_WALL_REACH:g} v^3 (v = {v[bad].flat[0]})"
        )


def distribution_near_wall(x, speeds, outgoing, restitution):
    """P(x, v) of eq. (fp) next to the floor, v > 0, by its Taylor series in x from P(0, v).

    See the module's docstring for the series and its error estimate.  Each v's window of
    P(0, v) serves every x at that v.

    Parameters
    ----------
    x : array_like
        Heights, 0 <= x <= ``NEAR_WALL_REACH`` v^3; they broadcast against ``speeds``.
    speeds : array_like
        Outgoing speeds v > 0, finite.
    outgoing : callable
        P(0, v) at an array of v > 0 (``solver.OutgoingSpeedSolution.outgoing_speed_density``,
        or an exact P(0, v)).
    restitution : float
        r, for the large-v decay rate q of P(0, v) that bounds the windows.

    Returns
    -------
    values : numpy.ndarray
        P(x, v), the broadcast shape; 0 where P(0, .) underflows on v's window (P(0, v) below
        ~1e-280, P(x, v) below it).
    errors : numpy.ndarray
        Estimates of their absolute errors (besides that of P(0, v) itself).

    Raises
    ------
    ValueError
        If a v is not > 0, an x is outside [0, NEAR_WALL_REACH v^3], P(0, .) exceeds the
        largest double on v's window, or the error estimate of a point exceeds
        ``NEAR_WALL_TOLERANCE`` of its value.

    Examples
    --------
    At r = 1/2 (P(0, v) = e^(-v) / (3 v)) just off the floor at v = 20, where the F integral
    of eq. (fpsol) is out of reach; against the exact P(x, v) on a rotated F contour
    (``exact.distribution_on_ray``):

    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> from bouncing_ball.near_wall import distribution_near_wall
    >>> outgoing = lambda v: exact.outgoing_speed_density(v, "1/2")
    >>> values, errors = distribution_near_wall([1e-5, 1e-3], 20.0, outgoing, 0.5)
    >>> reference = exact.distribution_on_ray([1e-5, 1e-3], 20.0, "1/2")
    >>> print(bool(np.all(np.abs(values / reference - 1.0) < 1e-12)), bool(np.all(errors < 1e-12 * values)))
    True True
    """
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(speeds, dtype=float))
    _check_domain(x, v)
    values, errors = np.zeros(x.shape), np.zeros(x.shape)
    unique, which = np.unique(v, return_inverse=True)
    which = which.reshape(v.shape)
    largest = np.zeros(unique.size)
    np.maximum.at(largest, which.ravel(), x.ravel())
    series = _series_at(unique, largest, outgoing, restitution)
    for k, (main, check, response, scale) in enumerate(series):
        at = which == k
        t = x[at] / scale
        value = np.polynomial.polynomial.polyval(t, main)
        error = np.abs(value - np.polynomial.polynomial.polyval(t, check))
        error += np.polynomial.polynomial.polyval(t, response) + 4e-16 * np.abs(value)
        _checked(value, error, x[at], unique[k])
        values[at], errors[at] = value, error
    return values, errors


def distribution_near_wall_cell_average(x_lo, x_hi, v_lo, v_hi, outgoing, restitution):
    """The average of P(x, v) over a cell next to the floor at large v, from the near-wall series.

    (1 / area) int_{x_lo}^{x_hi} dx int_{v_lo}^{v_hi} dv P(x, v), by the series of
    ``distribution_near_wall``.
    The x average of each power x^n in closed form, the v average by Gauss-Legendre
    (``NEAR_WALL_CELL_NODES`` nodes) on panels no wider than v / 8 and 1 / (q + 1 / v) (q the
    large-v decay rate of P(0, v)), across which P(0, v) changes by at most about e.

    Parameters
    ----------
    x_lo, x_hi, v_lo, v_hi : float
        One cell: 0 <= x_lo < x_hi <= ``NEAR_WALL_REACH`` v_lo^3, 0 < v_lo < v_hi < inf.
    outgoing : callable
        P(0, v) at an array of v > 0.
    restitution : float
        r.

    Returns
    -------
    value : float
        The cell average.
    error : float
        An estimate of its absolute error (the series' check, as ``distribution_near_wall``).

    Raises
    ------
    ValueError
        As ``distribution_near_wall`` at the cell's corner (x_hi, v_lo), or for edges out of
        order.
    """
    if not (0.0 <= x_lo < x_hi and 0.0 < v_lo < v_hi < np.inf):
        raise ValueError("a near-wall cell needs 0 <= x_lo < x_hi and 0 < v_lo < v_hi < inf")
    _check_domain(np.array([x_hi]), np.array([v_lo]))
    rate = large_speed_decay_rate(restitution)
    edges = [v_lo]
    while edges[-1] < v_hi:
        edges.append(min(v_hi, edges[-1] + min(edges[-1] / 8.0, 1.0 / (rate + 1.0 / edges[-1]))))
    edges = np.array(edges)
    nodes, weights = np.polynomial.legendre.leggauss(NEAR_WALL_CELL_NODES)
    half = 0.5 * np.diff(edges)[:, None]
    speeds = (0.5 * (edges[:-1, None] + edges[1:, None]) + half * nodes).ravel()
    weights = (half * weights).ravel()
    # the x average of x^n over [x_lo, x_hi]
    total, error = 0.0, 0.0
    series = _series_at(speeds, np.full(speeds.size, x_hi), outgoing, restitution)
    for speed, weight, (main, check, response, scale) in zip(speeds, weights, series):
        n = np.arange(max(main.size, check.size, response.size))
        # the average of (x / X)^n over [x_lo, x_hi], X = x_hi
        lo = x_lo / scale
        average = (1.0 - lo ** (n + 1)) / ((n + 1) * (1.0 - lo))
        value = float(main @ average[: main.size])
        difference = abs(value - float(check @ average[: check.size])) + 4e-16 * abs(value)
        difference += float(response @ average[: response.size])
        _checked(np.array([value]), np.array([difference]), x_hi, speed)
        total += weight * value
        error += weight * difference
    return total / (v_hi - v_lo), error / (v_hi - v_lo)
