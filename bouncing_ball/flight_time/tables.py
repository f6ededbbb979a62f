"""The pipeline's flight-time tables and bin averages: nu(T) of eq. (rate) and its asymptotic forms
at the config's flight times, its bin averages, and the return-speed law of eq. (kernel3) in the
simulation's speed bins.
"""

import numpy as np
import pandas as pd

from ..kernel import return_speed_kernel_matrix
from .asymptotic_forms import (
    long_flight_rate_density,
    long_time_decay_rate,
    short_flight_rate_density,
    short_time_constant,
    small_speed_amplitude,
)
from .equilibrium_density import flight_rate_density
from .equilibrium_moments import (
    collision_rate,
    flight_time_second_moment,
    mean_flight_time,
    time_weighted_mean_flight_time,
)

__all__ = [
    "FLIGHT_TIME_TABLE_RANGE",
    "flight_time_summary",
    "flight_time_table",
    "return_speed_table",
    "flight_rate_bin_integrals",
    "flight_time_bin_average",
    "return_speed_bin_law",
    "return_speed_bin_probabilities",
]


# 16-point Gauss-Legendre on [-1, 1] for bin averages
_BIN_NODES, _BIN_WEIGHTS = np.polynomial.legendre.leggauss(16)


#: The flight times of the pipeline's table (config solver.flight_times, min and max): from
#: 1e-100 (below SHORT_FLIGHT_TIME, 1e-30, the table's rate_density is its short_time_form,
#: A C_beta T^(-beta/2), which stays within doubles down to 1e-100 for beta < 5/2) to 1e5 (the
#: longest flights of r = 0.999 last about 4e4; beyond 1e4 nu(T) is 0 for r <= 0.618, where it
#: decays like e^(-3T/16), and the quadrature of each T costs T^(1/2) nodes).
FLIGHT_TIME_TABLE_RANGE = (1.0e-100, 1.0e5)


def flight_time_summary(solution):
    """The flight-time statistics of one r, as one row.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    dict
        r, collision_rate (I), mean_flight_time (<T> = 1/I; 0 below r_c),
        flight_time_second_moment (<T^2> per collision; 0 below r_c),
        time_weighted_mean_flight_time (the flight in progress at a random instant, any r),
        short_time_exponent (beta/2 of nu ~ T^(-beta/2), eq. (short)), short_time_amplitude
        (A C_beta) and long_time_decay_rate (kappa, eqs. (long1), (long2)).
    """
    beta = solution.small_speed_exponent
    return {
        "r": solution.restitution,
        "collision_rate": collision_rate(solution),
        "mean_flight_time": mean_flight_time(solution),
        "flight_time_second_moment": flight_time_second_moment(solution),
        "time_weighted_mean_flight_time": time_weighted_mean_flight_time(solution),
        "short_time_exponent": 0.5 * beta,
        "short_time_amplitude": small_speed_amplitude(solution) * short_time_constant(beta),
        "long_time_decay_rate": long_time_decay_rate(solution.restitution),
    }


def flight_time_table(solution, times):
    """The flight-time densities of eq. (rate) and their asymptotic forms, as a table.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    pandas.DataFrame
        Columns t, density (rho(T); NaN below r_c, where it is not defined), rate_density
        (nu(T)), time_weighted_density (T nu(T), a probability density for every r), and the
        short- and long-time forms of nu(T) (short_time_form, eq. (short); long_time_form,
        eqs. (long1), (long2)) for the figure.
    """
    times = np.asarray(times, dtype=float)
    nu = flight_rate_density(solution, times)
    rate = collision_rate(solution)
    density = nu / rate if np.isfinite(rate) else np.full_like(nu, np.nan)
    return pd.DataFrame(
        {
            "t": times,
            "density": density,
            "rate_density": nu,
            "time_weighted_density": times * nu,
            "short_time_form": short_flight_rate_density(solution, times),
            "long_time_form": long_flight_rate_density(solution, times),
        }
    )


def return_speed_table(solution, speed_bins):
    """The return-speed law v G_g(v, u) of eq. (kernel3) on a simulation's speed bins.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    speed_bins : bins.LogBins
        The simulation's bins of speeds.

    Returns
    -------
    pandas.DataFrame
        Columns u_lo, u_hi, v_lo, v_hi, probability (``return_speed_bin_probabilities`` with
        the solver's P(0, u)), for every finite u-bin and every v-bin (under- and overflow
        included).
    """
    u_lo, u_hi = speed_bins.edges[:-1], speed_bins.edges[1:]
    v_lo, v_hi = speed_bins.lower, speed_bins.upper
    cells = return_speed_bin_probabilities(solution.outgoing_speed_density, u_lo, u_hi, v_lo, v_hi)
    rows, columns = np.indices(cells.shape)
    return pd.DataFrame(
        {
            "u_lo": u_lo[rows.ravel()],
            "u_hi": u_hi[rows.ravel()],
            "v_lo": v_lo[columns.ravel()],
            "v_hi": v_hi[columns.ravel()],
            "probability": cells.ravel(),
        }
    )


def _log_gauss(lower, upper, points=16):
    """Gauss-Legendre in ln x on each finite bin, 16 points unless ``points`` says otherwise:
    nodes (bins x points) and weights for dx."""
    lower = np.asarray(lower, dtype=float)[:, None]
    upper = np.asarray(upper, dtype=float)[:, None]
    half = 0.5 * np.log(upper / lower)
    nodes, weights = (
        (_BIN_NODES, _BIN_WEIGHTS) if points == 16 else np.polynomial.legendre.leggauss(points)
    )
    x = np.exp(half * nodes[None, :] + 0.5 * np.log(upper * lower))
    return x, half * x * weights[None, :]


def flight_rate_bin_integrals(solution, lower, upper):
    """The integral of nu(T) dT over each bin: flights per unit time with duration in the bin.

    For any r.  Finite bins: 16-point Gauss-Legendre in ln T.  An underflow bin (lo = 0):
    twelve decades below hi the same way, and below those eq. (short) in closed form (inf
    below r_c, where nu is not integrable at T = 0).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    lower, upper : array_like
        The bins' edges [lo, hi); lo = 0 allowed.

    Returns
    -------
    numpy.ndarray
        One value per bin; NaN for an overflow bin (hi = inf), which is not supported.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    result = np.full(lower.shape, np.nan)
    finite = (lower > 0.0) & np.isfinite(upper)
    if np.any(finite):
        t, weights = _log_gauss(lower[finite], upper[finite])
        result[finite] = np.sum(flight_rate_density(solution, t) * weights, axis=1)
    beta = solution.small_speed_exponent
    for index in np.flatnonzero((lower <= 0.0) & np.isfinite(upper)):
        edges = upper[index] * np.logspace(-12.0, 0.0, 13)
        t, weights = _log_gauss(edges[:-1], edges[1:])
        above = np.sum(flight_rate_density(solution, t) * weights)
        if beta >= 2.0:
            result[index] = np.inf
        else:
            head = short_flight_rate_density(solution, edges[0]) * edges[0] / (1.0 - 0.5 * beta)
            result[index] = above + head
    return result


def flight_time_bin_average(solution, lower, upper):
    """rho(T) averaged over each bin, what a histogram of simulated flight times measures.

    int_bin rho dT / (hi - lo), rho = nu / I the flight-time distribution per collision.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    lower, upper : array_like
        The bins' edges [lo, hi); lo = 0 (underflow) allowed, hi = inf not (NaN).

    Returns
    -------
    numpy.ndarray
        Defined above r_c; below, I = inf and this is 0 (use ``flight_rate_bin_integrals``).
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    rate = collision_rate(solution)
    if not np.isfinite(rate):
        return np.where(np.isfinite(upper), 0.0, np.nan)
    return flight_rate_bin_integrals(solution, lower, upper) / rate / (upper - lower)


def _speed_sub_bins(lower, upper, panels=10, efolds=40.0):
    """Finite sub-bins covering each v-bin: itself if finite; an underflow bin [0, hi) by
    ``panels`` log-panels over ``efolds`` e-folds below hi (v G_g ~ v^(3/2): e^-100 beyond);
    an overflow bin by none.  Returns their edges and the index of the bin each belongs to."""
    lo, hi, owner = [], [], []
    for index, (a, b) in enumerate(zip(lower, upper)):
        if not np.isfinite(b):
            continue
        underflow = b * np.exp(np.linspace(-efolds, 0.0, panels + 1))
        edges = np.array([a, b]) if a > 0.0 else underflow
        lo.extend(edges[:-1])
        hi.extend(edges[1:])
        owner.extend([index] * (edges.size - 1))
    return np.array(lo), np.array(hi), np.array(owner, dtype=int)


#: Chebyshev nodes per panel in ln u of ``return_speed_bin_law(..., interpolated=True)``.
LAW_PANEL_NODES = 24


def _law_panel_edges():
    """The panels in ln u on which ``return_speed_bin_law`` interpolates: from 1e-12 to 1e5,
    each min(1, 2 u^(-1/2)) wide at its lower end u (the law of a ball leaving at speed
    u >> 1 varies over |v - u| ~ u^(1/2)).  One fixed set, whatever the points, so that a
    point's value does not depend on which others are asked for."""
    edges = [np.log(1e-12)]
    while edges[-1] < np.log(1e5):
        edges.append(edges[-1] + min(1.0, 2.0 * np.exp(-0.5 * edges[-1])))
    return np.array(edges)


_LAW_PANEL_EDGES = _law_panel_edges()


_LAW_PANEL_X = np.cos(np.pi * (np.arange(LAW_PANEL_NODES) + 0.5) / LAW_PANEL_NODES)


_LAW_PANEL_VANDERMONDE = np.polynomial.chebyshev.chebvander(_LAW_PANEL_X, LAW_PANEL_NODES - 1)


def _direct_return_speed_bin_law(u, v_lower, v_upper):
    """M_j(u) of ``return_speed_bin_law`` at each u, Gauss-Legendre in ln v on each finite
    v-bin (its sub-bins, ``_speed_sub_bins``); the overflow bin left at 0."""
    lo, hi, owner = _speed_sub_bins(v_lower, v_upper)
    v, v_weights = _log_gauss(lo, hi)  # (n_sub, 16)
    # G_g(v, u) of every pair as [u, v sub-bin, v point] (the matrix is [v, u]: a copy of its
    # transpose costs less than broadcasting the pairs)
    kernel = np.ascontiguousarray(return_speed_kernel_matrix(v.ravel(), u).T)
    sub = np.einsum("acd,cd->ac", kernel.reshape(u.size, *v.shape), v * v_weights)
    cells = np.zeros((u.size, v_lower.size))
    np.add.at(cells.T, owner, sub.T)
    return cells


def return_speed_bin_law(u, v_lower, v_upper, interpolated=False):
    """M_j(u) = int_(v-bin j) dv v G_g(v, u): the return-speed law of eq. (kernel3) in v-bins.

    The probability that a ball leaving the floor at speed u comes back with a speed in
    v-bin j.  A v-bin may start at 0 (underflow) or end at inf (overflow: 1 minus the rest,
    by eq. (normG)).  Gauss-Legendre in ln v.

    Parameters
    ----------
    u : array_like
        Outgoing speeds, 1-d, > 0.
    v_lower, v_upper : array_like
        The v-bins' edges.
    interpolated : bool, optional
        M_j computed at ``LAW_PANEL_NODES`` Chebyshev nodes on each panel in ln u that holds
        a u (panels of fixed edges, one e-fold wide, narrower above u = 4) and interpolated,
        where that takes fewer kernel evaluations: for many u close together.  M_j is
        analytic in ln u on that scale, and the interpolation agrees with the direct
        evaluation to rounding (a few 1e-15, ``tests/unit/test_flight_time.py``).

    Returns
    -------
    numpy.ndarray, shape (u, v-bins)
        Each row sums to 1 where the v-bins cover [0, inf).
    """
    u = np.ascontiguousarray(u, dtype=float)
    v_lower, v_upper = np.asarray(v_lower, dtype=float), np.asarray(v_upper, dtype=float)
    s = np.log(u)
    panel = np.searchsorted(_LAW_PANEL_EDGES, s, side="right") - 1
    used = np.unique(panel)
    inside = used.size and used[0] >= 0 and used[-1] < _LAW_PANEL_EDGES.size - 1
    if interpolated and inside and used.size * LAW_PANEL_NODES < u.size:
        middle = 0.5 * (_LAW_PANEL_EDGES[used + 1] + _LAW_PANEL_EDGES[used])
        half = 0.5 * (_LAW_PANEL_EDGES[used + 1] - _LAW_PANEL_EDGES[used])
        nodes = np.exp(middle[:, None] + half[:, None] * _LAW_PANEL_X[None, :])
        at_nodes = _direct_return_speed_bin_law(nodes.ravel(), v_lower, v_upper)
        coefficients = np.linalg.solve(
            _LAW_PANEL_VANDERMONDE, at_nodes.reshape(used.size, LAW_PANEL_NODES, -1)
        )
        k = np.searchsorted(used, panel)
        x = (s - middle[k]) / half[k]
        vandermonde = np.polynomial.chebyshev.chebvander(x, LAW_PANEL_NODES - 1)
        cells = np.einsum("pn,pnj->pj", vandermonde, coefficients[k])
    else:
        cells = _direct_return_speed_bin_law(u, v_lower, v_upper)
    overflow = np.flatnonzero(~np.isfinite(v_upper))
    if overflow.size:
        cells[:, overflow[0]] = 0.0
        cells[:, overflow[0]] = 1.0 - cells.sum(axis=1)
    return cells


def return_speed_bin_probabilities(
    outgoing_density, u_lower, u_upper, v_lower, v_upper, outgoing_points=16
):
    """The return-speed law v G_g(v, u) of eq. (kernel3) between bins of u and of v.

    Matrix [i, j]: probability that the return speed lies in v-bin j, given an outgoing speed in
    u-bin i distributed as u P(0, u) (the rate of collisions, eq. (collrate)) within the bin:

        int_(u-bin) du u P(0, u) int_(v-bin) dv v G_g(v, u) / int_(u-bin) du u P(0, u).

    ``outgoing_density`` is P(0, u) as a function of an array (e.g. the solver's
    ``outgoing_speed_density``).  u-bins must be finite; a v-bin may start at 0 (underflow) or end
    at inf (overflow: 1 minus the rest, by eq. (normG)).  Gauss-Legendre in ln u and ln v, the
    law at the points of u interpolated in ln u where that takes fewer kernel evaluations
    (``return_speed_bin_law``, the same values to rounding).

    Parameters
    ----------
    outgoing_density : callable
        P(0, u) of an array of u.
    u_lower, u_upper : array_like
        The finite u-bins' edges.
    v_lower, v_upper : array_like
        The v-bins' edges.
    outgoing_points : int, optional
        Gauss-Legendre points in ln u per u-bin (16; fewer suffice for narrow u-bins).

    Returns
    -------
    numpy.ndarray, shape (u-bins, v-bins)
        Each row sums to 1 where the v-bins cover [0, inf).
    """
    u, u_weights = _log_gauss(u_lower, u_upper, outgoing_points)
    flux = u * outgoing_density(u) * u_weights  # (n_u, points)
    law = return_speed_bin_law(u.ravel(), v_lower, v_upper, interpolated=True)
    return np.einsum("ab,abj->aj", flux, law.reshape(*u.shape, -1)) / flux.sum(axis=1)[:, None]
