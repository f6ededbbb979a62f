"""P(x, v) of eq. (fpsol) at x > 0 from w(F), at x = 0 from P(0, v) and eq. (bc), and its cell averages.

At x > 0, P(x, v) is an integral over F of w(F) against an Airy factor that oscillates: by
adaptive quadrature (``distribution_by_force_integral``) or by Gauss-Legendre panels between
the Airy function's phase steps (``distribution_by_force_rule``), with an error estimate
(``distribution_with_error``).  The cell averages over x and v are those of the simulation's
tables (``distribution_cell_average``).
"""

import math

import numpy as np
from scipy import integrate, special

from ..airy import (
    LARGEST_AIRY_PHASE,
    check_force_integral_point,
    oscillating_airy_ai,
    scaled_airy_ai,
)
from ..near_wall import (
    distribution_near_wall,
    distribution_near_wall_cell_average,
    near_wall_points,
)
from .position import _total_decay

__all__ = [
    "DISTRIBUTION_NOISE",
    "CELL_SPEED_NODES",
    "distribution_by_force_integral",
    "distribution_cell_average",
    "distribution_with_error",
    "distribution",
]


#: P(x, v) at x > 0 by the F integral of eq. (fpsol) is accurate to about this fraction of its
#: largest value at that x (w(F) is known to ~1e-10 relative, and the oscillating Airy factor
#: cancels): far-tail values below it are noise of either sign (at r = 0.05, x = 0.0126,
#: v = 2.3 to 6: +-9e-11 where the peak is 3.4; the quadrature's own error estimate does not
#: see it).
DISTRIBUTION_NOISE = 1e-10


def _distribution_integrand(log_force, x, v, weight, width=0.0):
    # e^{-v/2} w(F) e^{-F x} psi_{1/4,F}(-v) F, eqs. (fpsol), (psi); dF = F d(ln F); with
    # width > 0, e^{-F x} is replaced by its average over [x, x + width],
    # e^{-F x} (1 - e^{-F width}) / (F width)
    f = math.exp(log_force)
    argument = -(f ** (1.0 / 3.0)) * v + 0.25 * f ** (-2.0 / 3.0)
    log_w = weight.log_scalar(f) if hasattr(weight, "log_scalar") else float(weight.log(f))
    log_rest = log_w + log_force - f * x - 0.5 * v - log_force / 6.0
    if width > 0.0:
        log_rest += math.log(-math.expm1(-f * width) / (f * width))
    if argument <= 0.0 or (argument < 30.0 and abs(log_rest) < 600.0):
        # (Ai alone: scipy's airy is half the cost of airye; Ai(30) ~ 1e-48 is still a double)
        return special.airy(argument)[0] * math.exp(log_rest)
    airy = special.airye(argument)[0] if argument < 1e6 else float(scaled_airy_ai(argument))
    return airy * math.exp(log_rest - (2.0 / 3.0) * argument**1.5)


def _force_range(weight, x):
    """ln F from where w(F) e^{-v/2} psi_F(-v) of eq. (fpsol) has fallen below e^-150 of its
    largest at small F (e^{-(S + 1/12)/F}) to where e^{-F x} < e^-60, at one x > 0; widened to
    where e^{-(S + 1/12)/F - F x} has fallen by e^-60 from its saddle value at
    F_s = ((S + 1/12) / x)^(1/2), which lies beyond both ends at large x (beyond ~1e3)."""
    total = _total_decay(weight)
    root = math.sqrt(total * x)
    centre = 0.5 * math.log(total / x)
    reach = math.acosh(1.0 + 30.0 / root) + 1.0
    lower = min(math.log(total / 150.0), centre - reach)
    return lower, max(math.log(60.0 / x), centre + reach, lower + 1.0)


def distribution_by_force_integral(x, v, weight):
    """P(x, v) of eq. (fpsol) by integration over ln F, and quad's error estimate.

    Converges absolutely for x > 0, and for x = 0 on the incoming side v < 0
    (there the Airy function decays); at x = 0, v > 0 only conditionally.

    Parameters
    ----------
    x : float
        The height, x >= 0 (x = 0 only with v < 0: ``check_force_integral_point``).
    v : float
        The velocity.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    value : float
        P(x, v).
    error : float
        quad's estimate of its absolute error.

    Raises
    ------
    ValueError
        As ``check_force_integral_point``.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.distribution import distribution_by_force_integral
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> value, error = distribution_by_force_integral(0.5, 1.0, weight)
    >>> print(round(value, 8), error < 1e-10)
    0.07568971 True
    >>> print(round(exact.distribution_by_force_integral(0.5, 1.0, "1/2")[0], 8))
    0.07568971
    """
    xi, vi = float(x), float(v)
    check_force_integral_point(xi, vi)
    # w(F) e^{-v/2} psi_F(-v) vanishes like e^{-(S + 1/12)/F} at small F (or faster);
    # e^{-F x} cuts large F (at x = 0, v < 0 the Airy factor ~ exp(-(2/3) F^(1/2) |v|^(3/2)))
    if xi > 0.0:
        lower, upper = _force_range(weight, xi)
    else:
        lower = np.log(_total_decay(weight) / 150.0)
        upper = max(np.log((90.0 / abs(vi) ** 1.5) ** 2 + 1.0), lower + 1.0)
    value, error, *_ = integrate.quad(
        _distribution_integrand,
        lower,
        upper,
        args=(xi, vi, weight),
        limit=2000,
        epsabs=0.0,
        epsrel=1e-10,
        full_output=1,
    )
    return value, error


#: The fixed rule of ``distribution_by_force_rule``: Gauss-Legendre with FORCE_RULE_NODES nodes
#: on panels in ln F across each of which the integrand of eq. (fpsol) turns through at most
#: FORCE_RULE_PHASE radians or e-folds, split at the panel edges of the interpolated w (where
#: its series join with jumps of the order of its interpolation error); its check rule,
#: FORCE_CHECK_NODES nodes on panels of FORCE_CHECK_PHASE.  Against a rule six times finer
#: both are within 1e-13 of the largest value at that x (tests/unit/test_distribution.py).
#: Where the integrand's bound is below e^-FORCE_RULE_MARGIN of its largest value the range of
#: ln F is cut.
FORCE_RULE_NODES = 20


FORCE_RULE_PHASE = 16.0


FORCE_CHECK_NODES = 16


FORCE_CHECK_PHASE = 12.0


FORCE_RULE_MARGIN = 50.0


FORCE_RULE_GRID = 1500  # points in ln F on which the bound and the panel edges are found


def _force_rule_sum(x, speeds, log_rest_grid, y_grid, decay, phase, nodes, weight):
    """sum over the panels of Gauss-Legendre (``nodes``) of the integrand of eq. (fpsol) in
    ln F, per v (see ``distribution_by_force_rule``)."""
    gx, gw = np.polynomial.legendre.leggauss(nodes)
    force = np.exp(y_grid)
    airy_argument = -np.cbrt(force)[None, :] * speeds[:, None] + 0.25 * force[None, :] ** (
        -2.0 / 3.0
    )
    # |Ai(z)| <= e^(-(2/3) z^(3/2)) (z > 0), <= 1 (z < 0): a bound of the integrand's log
    bound = (
        log_rest_grid[None, :]
        - 0.5 * speeds[:, None]
        - (2.0 / 3.0) * np.maximum(airy_argument, 0.0) ** 1.5
    )
    which, y, w = [], [], []
    for k, v in enumerate(speeds):
        kept = np.nonzero(bound[k] >= np.max(bound[k]) - FORCE_RULE_MARGIN)[0]
        grid = y_grid[max(kept[0] - 1, 0) : min(kept[-1] + 2, y_grid.size)]
        # the integrand turns through e^-decay/F (small F), e^-F x, and the Airy phase or decay
        # (2/3) F^(1/2) |v|^(3/2): phi counts them, panels are equal in phi
        phi = grid - decay * np.exp(-grid) + x * np.exp(grid)
        phi += (2.0 / 3.0) * abs(v) ** 1.5 * np.exp(0.5 * grid)
        count = max(1, int(np.ceil((phi[-1] - phi[0]) / phase)))
        edges = np.interp(np.linspace(phi[0], phi[-1], count + 1), phi, grid)
        if hasattr(weight, "edges"):  # a WeightFunction: smooth only within its panels
            inside = (weight.edges > edges[0]) & (weight.edges < edges[-1])
            edges = np.union1d(edges, weight.edges[inside])
        half = 0.5 * np.diff(edges)[:, None]
        y.append((0.5 * (edges[:-1, None] + edges[1:, None]) + half * gx).ravel())
        w.append((half * gw).ravel())
        which.append(np.full(y[-1].size, k))
    which, y, w = np.concatenate(which), np.concatenate(y), np.concatenate(w)
    force, v = np.exp(y), speeds[which]
    argument = -np.cbrt(force) * v + 0.25 * force ** (-2.0 / 3.0)
    log_rest = weight.log(force) + (5.0 / 6.0) * y - force * x - 0.5 * v
    positive = argument > 0.0
    airy = np.empty(argument.size)
    airy[positive] = scaled_airy_ai(argument[positive])
    airy[~positive] = oscillating_airy_ai(-argument[~positive])
    terms = w * airy * np.exp(log_rest - (2.0 / 3.0) * np.maximum(argument, 0.0) ** 1.5)
    return np.bincount(which, terms, minlength=speeds.size)


def distribution_by_force_rule(x, speeds, weight):
    """P(x, v) of eq. (fpsol) at one x > 0 and many v by a fixed rule in ln F, with an error
    estimate.

    The F integral of eq. (fpsol) over ln F, between the limits of
    ``distribution_by_force_integral``, by Gauss-Legendre (FORCE_RULE_NODES nodes) on panels
    across each of which the integrand turns through at most FORCE_RULE_PHASE radians (the
    Airy phase (2/3) F^(1/2) v^(3/2)) or e-folds (e^(-(S + 1/12)/F), e^(-F x), the Airy decay
    for v < 0), cut where a bound of the integrand is below e^-FORCE_RULE_MARGIN of its
    largest value, and split at the panel edges of an interpolated w.  w(F) is evaluated at all
    nodes of all v at once.  The error estimate is the difference from a second, coarser rule
    (FORCE_CHECK_NODES nodes on panels of FORCE_CHECK_PHASE).

    Parameters
    ----------
    x : float
        The height, x > 0.
    speeds : array_like
        Velocities v (1-d); each (x, v) as ``check_force_integral_point`` allows.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).

    Returns
    -------
    values : numpy.ndarray
        P(x, v), the shape of ``speeds``.
    errors : numpy.ndarray
        The estimates of their absolute errors.

    Raises
    ------
    ValueError
        As ``check_force_integral_point``, or if x is not > 0.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.distribution import distribution_by_force_rule
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> values, errors = distribution_by_force_rule(0.5, [-1.0, 1.0], weight)
    >>> print(values.round(8), bool(np.all(errors < 1e-10 * values)))
    [0.04201018 0.07568971] True
    """
    x = float(x)
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if not x > 0.0:
        raise ValueError(f"x = {x}: the fixed rule of eq. (fpsol) needs x > 0")
    for v in speeds:
        check_force_integral_point(x, float(v))
    decay = _total_decay(weight)
    y_grid = np.linspace(*_force_range(weight, x), FORCE_RULE_GRID)
    log_rest_grid = weight.log(np.exp(y_grid)) + (5.0 / 6.0) * y_grid - np.exp(y_grid) * x
    values, check = (
        _force_rule_sum(x, speeds, log_rest_grid, y_grid, decay, phase, nodes, weight)
        for phase, nodes in (
            (FORCE_RULE_PHASE, FORCE_RULE_NODES),
            (FORCE_CHECK_PHASE, FORCE_CHECK_NODES),
        )
    )
    return values, np.abs(values - check)


#: Gauss-Legendre nodes per panel in v of ``distribution_cell_average``.
CELL_SPEED_NODES = 8


def distribution_cell_average(
    x_lo, x_hi, v_lo, v_hi, weight, speed_nodes=CELL_SPEED_NODES, outgoing=None
):
    """The average of P(x, v) of eq. (fpsol) over a cell, as a simulation's histogram measures it.

    (1 / area) int_{x_lo}^{x_hi} dx int_{v_lo}^{v_hi} dv P(x, v), for broadcast arrays of cells
    with 0 < x_lo < x_hi and finite v_lo < v_hi.

    The x average is done under the F integral of eq. (fpsol) in closed form,
    (1 / (x_hi - x_lo)) int dx e^{-F x} = e^{-F x_lo} (1 - e^{-F (x_hi - x_lo)}) / (F (x_hi - x_lo)),
    the v average by Gauss-Legendre with ``speed_nodes`` nodes on equal panels no wider than
    x_lo^(1/3), the width in v of the layer next to the floor in which P(x, v) crosses over from
    P(0, v) ~ v^-beta (P(x, v) is analytic in v for x > 0).  Good to 1e-9 against brute-force
    quadrature of the exact solutions for x_lo >= 0.01 (tests/unit/test_distribution_cells.py);
    at x_lo = 1e-3 (r = 0.25, v in [0, 1)) 3 to 12 nodes per panel agree to 1e-8, not checked
    against an independent computation.

    Parameters
    ----------
    x_lo, x_hi, v_lo, v_hi : array_like
        The cells' edges in x and v; they broadcast.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).
    speed_nodes : int, optional
        Gauss-Legendre nodes per panel in v (``CELL_SPEED_NODES``).
    outgoing : callable, optional
        P(0, v) at an array of v > 0 (``solver.OutgoingSpeedSolution.outgoing_speed_density``,
        or an exact P(0, v)).  Given, the part of a cell at speeds above those the F integral
        reaches at x_lo, v > v_c(x_lo) = (x_lo / 1.7e-8)^(1/3) (``airy.LARGEST_AIRY_PHASE``),
        is averaged from the near-wall series (``near_wall.distribution_near_wall_cell_average``),
        which needs x_hi <= 60 x_lo there; without it such a cell is refused.

    Returns
    -------
    numpy.ndarray
        The cell averages of P(x, v), the broadcast shape of the edges.

    Raises
    ------
    ValueError
        If a cell is not 0 < x_lo < x_hi < inf with finite v_lo < v_hi; or reaches an x and
        v > 0 at which the F integral oscillates too fast (``LARGEST_AIRY_PHASE``) without
        ``outgoing``, or with it at x_hi > 60 x_lo or where the near-wall series refuses.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.distribution import distribution_cell_average
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(distribution_cell_average([0.5, 1.0], [1.0, 2.0], 0.0, 1.0, weight).round(8))
    [0.06005725 0.03294018]
    """
    x_lo, x_hi, v_lo, v_hi = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (x_lo, x_hi, v_lo, v_hi))
    )
    if np.any(~(x_lo > 0.0) | ~(x_hi > x_lo) | ~(v_hi > v_lo) | ~np.isfinite(x_hi + v_lo + v_hi)):
        raise ValueError("cells need 0 < x_lo < x_hi < inf and finite v_lo < v_hi")
    # the speed up to which the F integral reaches at x_lo: phase (2/3) (60 / x)^(1/2) v^(3/2)
    reach = (LARGEST_AIRY_PHASE / ((2.0 / 3.0) * np.sqrt(60.0 / x_lo))) ** (2.0 / 3.0)
    beyond = v_hi > reach
    if np.any(beyond) and outgoing is None:
        raise ValueError(
            "x_lo: a cell reaches an x and v > 0 at which the F integral of eq. (fpsol) "
            "oscillates too fast to evaluate (check_force_integral_point); give outgoing, "
            "P(0, v), for the near-wall series there"
        )
    if np.any(beyond & (x_hi > 60.0 * x_lo)):
        raise ValueError(
            "x_hi: a cell reaching speeds beyond the F integral's at x_lo needs "
            "x_hi <= 60 x_lo (the near-wall series holds for x <= 1e-6 v^3)"
        )
    result = np.empty(x_lo.shape)
    for index in np.ndindex(x_lo.shape):
        lo, hi = float(x_lo[index]), float(x_hi[index])
        a, b, c = float(v_lo[index]), float(v_hi[index]), float(reach[index])
        total = 0.0
        if a < c:
            total += (min(b, c) - a) * _force_cell_average(
                lo, hi, a, min(b, c), weight, speed_nodes
            )
        if b > c:
            start = max(a, c)
            near, _ = distribution_near_wall_cell_average(
                lo, hi, start, b, outgoing, weight.restitution
            )
            total += (b - start) * near
        result[index] = total / (b - a)
    return result


def _force_cell_average(x_lo, x_hi, v_lo, v_hi, weight, speed_nodes):
    """The cell average of P(x, v) by the F integral of eq. (fpsol)
    (``distribution_cell_average``), one cell whose speeds the F integral reaches."""
    nodes, node_weights = np.polynomial.legendre.leggauss(speed_nodes)
    lo, width = x_lo, x_hi - x_lo
    lower, upper = _force_range(weight, lo)
    panels = int(np.ceil((v_hi - v_lo) / lo ** (1.0 / 3.0)))
    edges = np.linspace(v_lo, v_hi, panels + 1)
    total = 0.0
    for a, b in zip(edges[:-1], edges[1:]):
        for node, node_weight in zip(nodes, node_weights):
            value, *_ = integrate.quad(
                _distribution_integrand,
                lower,
                upper,
                args=(lo, float(0.5 * (a + b) + 0.5 * (b - a) * node), weight, width),
                limit=2000,
                epsabs=0.0,
                epsrel=1e-10,
                full_output=1,
            )
            total += 0.5 * (b - a) * node_weight * value
    return total / (v_hi - v_lo)


def distribution_with_error(x, v, weight, solution):
    """P(x, v) and an estimate of its absolute error, for broadcast arrays x >= 0 and v.

    x > 0: eq. (fpsol) by the F integral, every v at one x by one fixed rule
    (``distribution_by_force_rule``), except next to the floor at large v > 0, where its Airy
    factor oscillates too fast (x < 1.7e-8 v^3, ``near_wall.near_wall_points``): there the
    Taylor series in x of eq. (fp) from the solver's P(0, v)
    (``near_wall.distribution_near_wall``).  x = 0: the outgoing side is the
    solver's P(0, v), the incoming side the boundary condition eq. (bc),
    P(0, -v) = r^2 P(0, r v); P(0, 0) diverges and is NaN.

    Parameters
    ----------
    x, v : array_like
        Heights x >= 0 and velocities; they broadcast.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).
    solution : solver.OutgoingSpeedSolution
        P(0, v) of eq. (inteq), used at x = 0 and by the near-wall series (evaluating it
        compiles the kernel on its first call).

    Returns
    -------
    values : numpy.ndarray
        P(x, v), the broadcast shape.
    errors : numpy.ndarray
        Estimates of their absolute errors (``distribution_by_force_rule``, or
        ``near_wall.distribution_near_wall``; 0 at x = 0).

    Raises
    ------
    ValueError
        Before any integral, for an x < 0 or NaN (``check_force_integral_point``); as
        ``near_wall.distribution_near_wall`` for a point next to the floor.

    Examples
    --------
    At x > 0 (``solution``, the exact P(0, v) of r = 1/2 on the solver's nodes, is not used):

    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.distribution import distribution_with_error
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = exact.outgoing_speed_density(nodes, "1/2")
    >>> solution = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> values, errors = distribution_with_error([0.5, 1.0], 1.0, weight, solution)
    >>> print(values.round(8), bool(np.all(errors < 1e-10 * values)))
    [0.07568971 0.04549126] True
    """
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v, dtype=float))
    near = near_wall_points(x, v)
    for index in np.ndindex(x.shape):
        if x[index] != 0.0 and not near[index]:
            check_force_integral_point(float(x[index]), float(v[index]))
    values, errors = np.empty(x.shape), np.zeros(x.shape)
    r = solution.restitution
    if near.any():
        values[near], errors[near] = distribution_near_wall(
            x[near], v[near], solution.outgoing_speed_density, r
        )
    for index in np.ndindex(x.shape):
        xi, vi = float(x[index]), float(v[index])
        if xi == 0.0:
            if vi > 0.0:
                values[index] = solution.outgoing_speed_density(vi)
            elif vi < 0.0:
                values[index] = r * r * solution.outgoing_speed_density(-r * vi)
            else:
                values[index] = np.nan
    # x > 0: every v at one x by one fixed rule in ln F (w(F) evaluated once for them all)
    for xi in np.unique(x[(x > 0.0) & ~near]):
        at = (x == xi) & ~near
        values[at], errors[at] = distribution_by_force_rule(xi, v[at], weight)
    return values, errors


def distribution(x, v, weight, solution):
    """P(x, v), eq. (fpsol) for x > 0 (eq. (bc) and the solver's P(0, v) at x = 0).

    Parameters
    ----------
    x, v : array_like
        Heights x >= 0 and velocities; they broadcast.
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).
    solution : solver.OutgoingSpeedSolution
        P(0, v) of eq. (inteq), used at x = 0 and next to the floor at large v
        (``distribution_with_error``).

    Returns
    -------
    numpy.ndarray
        P(x, v), the broadcast shape of ``x`` and ``v``; NaN at x = v = 0.

    Raises
    ------
    ValueError
        As ``distribution_with_error``.

    Examples
    --------
    At r = 1/2, from the exact w(F), it is eq. (fpsol) with eq. (weightfunc2) (``solution``,
    the exact P(0, v) on the solver's nodes, is used only at x = 0):

    >>> from bouncing_ball.distribution import closed_form_weight_function, distribution
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = exact.outgoing_speed_density(nodes, "1/2")
    >>> solution = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> print(distribution([0.5, 1.0], [1.0, -1.0], weight, solution).round(8))
    [0.07568971 0.02794986]
    >>> print(exact.distribution([0.5, 1.0], [1.0, -1.0], "1/2").round(8))
    [0.07568971 0.02794986]
    """
    return distribution_with_error(x, v, weight, solution)[0]
