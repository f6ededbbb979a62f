"""The tables of the shards' histograms: P(0, v), P(x) and <v^2>_x, P(x, v), the flight times
and the return speeds."""

import numpy as np
import pandas as pd

from ..tallies import (
    RATE_CONTROLS,
    SHARDS_PER_CONTROL,
    ShardTallies,
)
from .control_variates import (
    _RETURN_LAW_SHARDS,
    _controlled,
    _restitution_float,
    control_variate_adjusted,
    return_law_prediction,
    shard_controls,
)
from .jackknife import jackknife

__all__ = [
    "outgoing_speed_density",
    "outgoing_speed_histogram",
    "position_histogram",
    "distribution_histogram",
    "flight_time_histogram",
    "return_speed_table",
    "outside_fractions",
]

#: What each table's histogram counts, for ``outside_fractions``: (table, tally field, its
#: bins, what it counts).
_COVERED = (
    ("p0v", "speed_counts", "speed_bins", "collisions"),
    ("position", "position_time", "position_bins", "time"),
    ("flight_time", "flight_time_counts", "flight_time_bins", "flights"),
)


def outgoing_speed_density(counts, time, lower, upper):
    """P(0, v) averaged over a bin of outgoing speed, from the rate of collisions in it.

    The rate of collisions with outgoing speed in [lower, upper) is int v P(0, v) dv over the
    bin, eq. (collrate); the bin average weighted by v is that rate over int v dv.

    Parameters
    ----------
    counts : array_like
        Collisions in each bin.
    time : float or array_like
        The time over which they were counted.
    lower, upper : array_like
        The bins' edges.

    Returns
    -------
    numpy.ndarray or float
        counts / (time (upper^2 - lower^2) / 2), the bin average of P(0, v) weighted by v.

    Examples
    --------
    >>> from bouncing_ball.estimators import outgoing_speed_density
    >>> print(outgoing_speed_density(6.0, 4.0, 1.0, 2.0))
    1.0
    """
    return counts / (time * 0.5 * (upper**2 - lower**2))


def outgoing_speed_histogram(
    shards: list[ShardTallies], restitution=None, outgoing_density=None, return_law=None
) -> pd.DataFrame:
    """P(0, v) on the outgoing side, bin averages weighted by v.

    Bin averages mean p0v = int_bin v P(0,v) dv / int_bin v dv (``outgoing_speed_density``,
    eq. (collrate)).

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same speed bins.
    restitution : fractions.Fraction or float, optional
        The shards' r as parsed (``restitution.parse_restitution``), 0 < r < 1; needed with
        ``outgoing_density``.
    outgoing_density : callable, optional
        P(0, u) of the theory the controlled column leans on, given by the caller (the
        solver's, ``solver.solved_outgoing_density``): with it, each bin's counts are also
        corrected by its return-law control variate, counts minus ``return_law_prediction``.
        The estimators never solve eq. (inteq) themselves.
    return_law : numpy.ndarray, optional
        ``return_law_prediction`` of these shards, if already at hand (a row per shard): used
        instead of computing it from ``restitution`` and ``outgoing_density``.

    Returns
    -------
    pandas.DataFrame
        One row per speed bin, under- and overflow included, columns ``v_lo``, ``v_hi``,
        ``v`` (the geometric centre; the arithmetic one for the underflow bin), ``p0v``,
        ``p0v_err``, ``count``, ``p0v_martingale``, ``p0v_martingale_err``,
        ``p0v_controlled``, ``p0v_controlled_err``.  The overflow bin
        has p0v = NaN; an empty bin has p0v = 0 and p0v_err = NaN (no scatter to measure).
        ``p0v_martingale`` (with ``p0v_martingale_err``) is the same with each bin's counts
        corrected by the martingale control variates of ``tallies.RATE_CONTROLS``
        (``control_variate_adjusted``: the same expectation for the simulated process, less
        variance; NaN with fewer than ``SHARDS_PER_CONTROL`` x ``len(RATE_CONTROLS)``
        shards).  ``p0v_controlled`` is corrected by the bin's return-law control, built
        from eq. (kernel3), the theory under test, and with enough shards the martingale
        ones too: unbiased only if the simulated process follows eq. (kernel3) (NaN
        without ``outgoing_density`` or ``return_law``, or with fewer than 4 shards).

    Raises
    ------
    ValueError
        If ``outgoing_density`` is given without ``restitution``, or r is outside (0, 1).
    TypeError
        If ``restitution`` is not parsed (a string).

    Examples
    --------
    See the module's example.
    """
    bins = shards[0].speed_bins
    lower, upper = bins.lower, bins.upper
    counts = np.stack([s.speed_counts for s in shards])
    times = np.array([s.time for s in shards])[:, None]

    def density(c, t):
        return outgoing_speed_density(c, t, lower, upper)

    p0v, err = jackknife(density, counts, times)
    if outgoing_density is not None and restitution is None:
        raise ValueError("restitution: the return-law control needs r beside outgoing_density")
    r = None if restitution is None else _restitution_float(restitution)
    if return_law is None and outgoing_density is not None and len(shards) >= _RETURN_LAW_SHARDS:
        return_law = return_law_prediction(shards, r, outgoing_density)
    controls = shard_controls(shards, RATE_CONTROLS)
    martingale, martingale_err = _controlled(density, controls, times[:, 0], [counts], [times])
    if return_law is None:
        controlled, controlled_err = _controlled(density, None, times[:, 0], [counts], [times])
    else:
        controlled, controlled_err = _return_law_controlled(
            shards, counts, times, return_law, density
        )
    total = counts.sum(axis=0)
    for value, error in ((p0v, err), (martingale, martingale_err), (controlled, controlled_err)):
        value[~np.isfinite(upper)] = np.nan
        error[~np.isfinite(upper) | (total == 0)] = np.nan
    return pd.DataFrame(
        {
            "v_lo": lower,
            "v_hi": upper,
            "v": _bin_centres(lower, upper),
            "p0v": p0v,
            "p0v_err": err,
            "count": total.astype(np.int64),
            "p0v_martingale": martingale,
            "p0v_martingale_err": martingale_err,
            "p0v_controlled": controlled,
            "p0v_controlled_err": controlled_err,
        }
    )


def _return_law_controlled(shards, counts, times, return_law, density):
    """P(0, v) and its error from counts corrected bin by bin by the return-law control of
    the bin and, with ``SHARDS_PER_CONTROL`` shards per control for them, those of
    ``tallies.RATE_CONTROLS`` (NaN with fewer than 4 shards)."""
    if len(shards) < _RETURN_LAW_SHARDS:
        return _controlled(density, None, times[:, 0], [counts], [times])
    # the martingale controls too, where the shards are enough for them and the bin's own
    rate = None
    if len(shards) >= SHARDS_PER_CONTROL * (len(RATE_CONTROLS) + 1):
        rate = shard_controls(shards, RATE_CONTROLS)
    adjusted = counts.astype(float)
    surprise = counts - return_law
    for j in range(counts.shape[1]):
        own = surprise[:, j : j + 1] if np.ptp(surprise[:, j]) > 0 else np.empty((len(shards), 0))
        controls = own if rate is None else np.column_stack([own, rate])
        if controls.shape[1]:  # else a bin no shard reached or could reach: as it is
            adjusted[:, j] = control_variate_adjusted(counts[:, j], times[:, 0], controls)[0]
    return jackknife(density, adjusted, times)


def position_histogram(shards: list[ShardTallies]) -> pd.DataFrame:
    """P(x) (bin averages) and <v^2>_x, eq. (moment2), per bin of x.

    The tally is exact in expectation but in the steps cut by a collision (``simulation``:
    the mean path corrected by one bridge point a step), so a bin's total can come out
    slightly negative where the particle hardly goes; the underflow bin (x below the first
    edge) also holds the bridge points below x = 0.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same position bins.

    Returns
    -------
    pandas.DataFrame
        One row per position bin, under- and overflow included, columns ``x_lo``, ``x_hi``,
        ``x`` (as ``v`` of ``outgoing_speed_histogram``), ``px``, ``px_err``,
        ``v2_given_x``, ``v2_given_x_err``, ``px_controlled``, ``px_controlled_err``,
        ``v2_given_x_controlled``, ``v2_given_x_controlled_err``.  NaN where a value is
        undefined: P(x) in the overflow bin, errors and <v^2>_x in bins the particle never
        visited.  The ``*_controlled`` columns are the same with each bin's time and
        int v^2 dt corrected by the control variates of ``tallies.RATE_CONTROLS``
        (``control_variate_adjusted``: the same expectation, less variance; NaN with fewer
        than ``SHARDS_PER_CONTROL`` x ``len(RATE_CONTROLS)`` shards).

    Examples
    --------
    See the module's example.
    """
    bins = shards[0].position_bins
    lower, upper = bins.lower, bins.upper
    in_bin = np.stack([s.position_time for s in shards])
    v2 = np.stack([s.position_v2_time for s in shards])
    times = np.array([s.time for s in shards])[:, None]

    def density(b, t):
        return b / (t * (upper - lower))

    def given_x(w, b):
        return w / b

    px, px_err = jackknife(density, in_bin, times)
    v2x, v2x_err = jackknife(given_x, v2, in_bin)
    controls = shard_controls(shards, RATE_CONTROLS)
    px_c, px_c_err = _controlled(density, controls, times[:, 0], [in_bin], [times])
    v2x_c, v2x_c_err = _controlled(given_x, controls, times[:, 0], [v2, in_bin])
    empty = in_bin.sum(axis=0) == 0
    for value, error in ((px, px_err), (px_c, px_c_err)):
        value[~np.isfinite(upper)] = np.nan
        error[~np.isfinite(upper) | empty] = np.nan
    return pd.DataFrame(
        {
            "x_lo": lower,
            "x_hi": upper,
            "x": _bin_centres(lower, upper),
            "px": px,
            "px_err": px_err,
            "v2_given_x": v2x,
            "v2_given_x_err": v2x_err,
            "px_controlled": px_c,
            "px_controlled_err": px_c_err,
            "v2_given_x_controlled": v2x_c,
            "v2_given_x_controlled_err": v2x_c_err,
        }
    )


def distribution_histogram(shards: list[ShardTallies]) -> pd.DataFrame:
    """P(x, v) as cell averages: the time in each cell of (x, v) over the total time and its area.

    x is on the position bins, v on the velocity bins.  The x underflow cell [0, x_lo) also
    holds the rare bridge draws below x = 0 (see ``simulation``).

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same position and velocity bins.

    Returns
    -------
    pandas.DataFrame
        One row per cell, v fastest, columns ``x_lo``, ``x_hi``, ``v_lo``, ``v_hi``,
        ``pxv``, ``pxv_err``.  pxv is NaN in cells of infinite area (x overflow, v under- and
        overflow); pxv_err also in cells the particle never visited.

    Examples
    --------
    See the module's example.
    """
    first = shards[0]
    x_lower, x_upper = first.position_bins.lower, first.position_bins.upper
    v_lower, v_upper = first.velocity_bins.lower, first.velocity_bins.upper
    area = np.outer(x_upper - x_lower, v_upper - v_lower)
    in_cell = np.stack([s.position_velocity_time for s in shards])
    times = np.array([s.time for s in shards])[:, None, None]
    pxv, err = jackknife(lambda b, t: b / (t * area), in_cell, times)
    infinite = ~np.isfinite(area)
    pxv[infinite] = np.nan
    err[infinite | (in_cell.sum(axis=0) == 0)] = np.nan
    nx, nv = area.shape
    return pd.DataFrame(
        {
            "x_lo": np.repeat(x_lower, nv),
            "x_hi": np.repeat(x_upper, nv),
            "v_lo": np.tile(v_lower, nx),
            "v_hi": np.tile(v_upper, nx),
            "pxv": pxv.ravel(),
            "pxv_err": err.ravel(),
        }
    )


def flight_time_histogram(shards: list[ShardTallies]) -> pd.DataFrame:
    """The density of the flight time T between consecutive collisions, per unit T and per flight.

    Bin averages: counts / (flights x bin width).

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same flight-time bins.

    Returns
    -------
    pandas.DataFrame
        One row per flight-time bin, under- and overflow included, columns ``t_lo``,
        ``t_hi``, ``t`` (geometric centre; the arithmetic one for the underflow bin
        [0, t_lo)), ``density``, ``density_err``.  NaN in the overflow bin; density_err NaN
        in empty bins.

    Examples
    --------
    See the module's example.
    """
    bins = shards[0].flight_time_bins
    lower, upper = bins.lower, bins.upper
    counts = np.stack([s.flight_time_counts for s in shards])
    flights = np.array([s.flights for s in shards], dtype=float)[:, None]
    density, err = jackknife(lambda c, n: c / (n * (upper - lower)), counts, flights)
    density[~np.isfinite(upper)] = np.nan
    err[~np.isfinite(upper) | (counts.sum(axis=0) == 0)] = np.nan
    return pd.DataFrame(
        {
            "t_lo": lower,
            "t_hi": upper,
            "t": _bin_centres(lower, upper),
            "density": density,
            "density_err": err,
        }
    )


def return_speed_table(shards: list[ShardTallies]) -> pd.DataFrame:
    """The return speed v at the next collision given the outgoing speed u of a bounce.

    The probability of each v bin given the u bin: counts over the counts of that u row.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same speed bins.

    Returns
    -------
    pandas.DataFrame
        One row per (u, v) pair of the speed bins, v fastest, columns ``u_lo``, ``u_hi``,
        ``v_lo``, ``v_hi``, ``probability``, ``probability_err``.  NaN (both) in rows of u
        with no flight; probability_err NaN where the pair was never seen.

    Examples
    --------
    See the module's example.
    """
    bins = shards[0].speed_bins
    lower, upper = bins.lower, bins.upper
    counts = np.stack([s.return_speed_counts for s in shards])
    probability, err = jackknife(lambda c: c / c.sum(axis=-1, keepdims=True), counts)
    total = counts.sum(axis=0)
    err[total == 0] = np.nan
    n = lower.shape[0]
    return pd.DataFrame(
        {
            "u_lo": np.repeat(lower, n),
            "u_hi": np.repeat(upper, n),
            "v_lo": np.tile(lower, n),
            "v_hi": np.tile(upper, n),
            "probability": probability.ravel(),
            "probability_err": err.ravel(),
        }
    )


def _bin_centres(lower, upper):
    with np.errstate(invalid="ignore"):
        centre = np.sqrt(lower * upper)
    centre[lower == 0.0] = 0.5 * upper[lower == 0.0]
    return centre


def outside_fractions(shards: list[ShardTallies]) -> dict:
    """How much of each histogram's distribution lies outside its finite bins.

    The under- and overflow bins of the shards' tallies, over the whole: the collisions of
    P(0, v), the time of P(x) (its underflow bin [0, x_lo) counts as outside: the table does not
    resolve it), the flights of the flight-time density, and the time of P(x, v) outside its
    finite cells (x or v beyond their bins).

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same bins.

    Returns
    -------
    dict
        {table: {"below": fraction, "above": fraction, "outside": their sum, "counts": what
        is counted, "lo", "hi": the range of the finite bins}} for the tables ``p0v``,
        ``position``, ``flight_time`` and ``distribution`` (whose below, above, lo and hi are
        of v: its x overflow is in ``outside``); NaN where the shards recorded nothing.

    Examples
    --------
    See the module's example.
    """
    fractions = {}
    first = shards[0]
    for table, field, bins, counted in _COVERED:
        total = np.sum([getattr(s, field) for s in shards], axis=0).astype(float)
        whole = total.sum()
        below, above = (total[0] / whole, total[-1] / whole) if whole > 0 else (np.nan,) * 2
        fractions[table] = {
            "below": float(below),
            "above": float(above),
            "outside": float(below + above),
            "counts": counted,
            "lo": float(getattr(first, bins).lo),
            "hi": float(getattr(first, bins).hi),
        }
    cells = np.sum([s.position_velocity_time for s in shards], axis=0)
    whole = cells.sum()
    if whole > 0:
        v_below, v_above = cells[:, 0].sum() / whole, cells[:, -1].sum() / whole
        inside = cells[1:-1, 1:-1].sum() / whole
    else:
        v_below = v_above = inside = np.nan
    fractions["distribution"] = {
        "below": float(v_below),
        "above": float(v_above),
        "outside": float(1.0 - inside),
        "counts": "time",
        "lo": float(first.velocity_bins.lo),
        "hi": float(first.velocity_bins.hi),
    }
    return fractions
