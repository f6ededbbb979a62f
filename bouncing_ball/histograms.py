"""From summed shard tallies to P(0,v), P(x), <v^2>_x, P(x,v), the flights and the moments.

Every estimate is a function of the shards' summed tallies; its standard
error comes from the scatter between shards by the delete-one jackknife
(for a ratio of sums over shards of equal time it is the standard error of
the mean of the per-shard estimates).  ``control_variate_rate`` lowers the
variance of a rate with the shards' martingale control variates.
"""

import numpy as np
import pandas as pd

from . import stages
from .tallies import CONTROL_VARIATE_SUMS, MOMENT_CONTROLS, ShardTallies, merge_shards

# the modules whose code decides the merged tables (see ``source_digest``)
SOURCES = stages.MERGE


def jackknife(estimator, *per_shard):
    """Value and jackknife standard error of ``estimator`` of summed tallies.

    Each argument of ``per_shard`` has the shard index as its first axis; the
    estimator receives the sums over shards.  With one shard the error is NaN.
    """
    per_shard = [np.asarray(a, dtype=float) for a in per_shard]
    totals = [a.sum(axis=0) for a in per_shard]
    with np.errstate(divide="ignore", invalid="ignore"):
        value = estimator(*totals)
        n = per_shard[0].shape[0]
        if n < 2:
            return value, np.full_like(np.asarray(value, dtype=float), np.nan)
        leave_one_out = np.stack(
            [estimator(*[t - a[k] for t, a in zip(totals, per_shard)]) for k in range(n)]
        )
    spread = leave_one_out - leave_one_out.mean(axis=0)
    return value, np.sqrt((n - 1) / n * (spread**2).sum(axis=0))


def outgoing_speed_density(counts, time, lower, upper):
    """eq. (collrate): the rate of collisions in a bin is int v P(0,v) dv."""
    return counts / (time * 0.5 * (upper**2 - lower**2))


def outgoing_speed_histogram(shards: list[ShardTallies]) -> pd.DataFrame:
    """P(0, v) on the outgoing side, bin averages weighted by v.

    Columns v_lo, v_hi, v (the geometric centre; the arithmetic one for the
    underflow bin), p0v, p0v_err, count.  Bin averages mean
    p0v = int_bin v P(0,v) dv / int_bin v dv.  The overflow bin has p0v = NaN;
    an empty bin has p0v = 0 and p0v_err = NaN (no scatter to measure).
    """
    bins = shards[0].speed_bins
    lower, upper = bins.lower, bins.upper
    counts = np.stack([s.speed_counts for s in shards])
    times = np.array([s.time for s in shards])[:, None]
    p0v, err = jackknife(lambda c, t: outgoing_speed_density(c, t, lower, upper), counts, times)
    total = counts.sum(axis=0)
    p0v[~np.isfinite(upper)] = np.nan
    err[~np.isfinite(upper) | (total == 0)] = np.nan
    return pd.DataFrame(
        {
            "v_lo": lower,
            "v_hi": upper,
            "v": _bin_centres(lower, upper),
            "p0v": p0v,
            "p0v_err": err,
            "count": total.astype(np.int64),
        }
    )


def position_histogram(shards: list[ShardTallies]) -> pd.DataFrame:
    """P(x) (bin averages) and <v^2>_x, eq. (moment2), per bin of x.

    NaN where a value is undefined: P(x) in the overflow bin, errors and
    <v^2>_x in bins the particle never visited.  The tally is exact in expectation
    but in the steps cut by a collision (``simulation``: the mean path corrected by one
    bridge point a step), so a bin's
    total can come out slightly negative where the particle hardly goes; the underflow
    bin (x below the first edge) also holds the bridge points below x = 0.
    """
    bins = shards[0].position_bins
    lower, upper = bins.lower, bins.upper
    in_bin = np.stack([s.position_time for s in shards])
    v2 = np.stack([s.position_v2_time for s in shards])
    times = np.array([s.time for s in shards])[:, None]
    px, px_err = jackknife(lambda b, t: b / (t * (upper - lower)), in_bin, times)
    v2x, v2x_err = jackknife(lambda w, b: w / b, v2, in_bin)
    empty = in_bin.sum(axis=0) == 0
    px[~np.isfinite(upper)] = np.nan
    px_err[~np.isfinite(upper) | empty] = np.nan
    return pd.DataFrame(
        {
            "x_lo": lower,
            "x_hi": upper,
            "x": _bin_centres(lower, upper),
            "px": px,
            "px_err": px_err,
            "v2_given_x": v2x,
            "v2_given_x_err": v2x_err,
        }
    )


def distribution_histogram(shards: list[ShardTallies]) -> pd.DataFrame:
    """P(x, v) as cell averages: the time in each cell of (x, v) over the total time and the
    cell's area (x on the position bins, v on the velocity bins).

    Columns x_lo, x_hi, v_lo, v_hi, pxv, pxv_err, one row per cell, v fastest.  pxv is NaN
    in cells of infinite area (x overflow, v under- and overflow); pxv_err also in cells the
    particle never visited.  The x underflow cell [0, x_lo) also holds the rare bridge draws
    below x = 0 (see ``simulation``).
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
    """The density of the flight time T between consecutive collisions, per unit T and per
    flight (bin averages): counts / (flights x bin width).

    Columns t_lo, t_hi, t (geometric centre; the arithmetic one for the underflow bin
    [0, t_lo)), density, density_err.  NaN in the overflow bin; density_err NaN in empty bins.
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
    """The return speed v at the next collision given the outgoing speed u of a bounce: the
    probability of each v bin given the u bin, counts over the counts of that u row.

    Columns u_lo, u_hi, v_lo, v_hi, probability, probability_err, one row per (u, v) bin
    pair of the speed bins, v fastest.  NaN (both) in rows of u with no flight;
    probability_err NaN where the pair was never seen.
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


def _mean_x(int_x, time):
    return int_x / time


def _delta_x(int_x, int_x2, time):
    return np.sqrt(int_x2 / time - (int_x / time) ** 2)


# the moments the summary also gives corrected by MOMENT_CONTROLS (``{name}_controlled``)
CONTROLLED_MOMENTS = ("mean_x", "delta_x", "mean_flight_time", "flight_time_second_moment")


def position_moments_summary(shards: list[ShardTallies], restitution: float) -> pd.DataFrame:
    """One row: <x>, Delta x and the collision rate I, eqs. (collrate), (xandDeltax), and the
    mean and second moment of the flight time per flight.  Each is given twice: plain (the
    time averages, collisions per time, the flights' averages) and ``*_controlled``, the same
    corrected by martingale control variates of mean 0 (the same expectation, less
    variance): I by ``control_variate_rate`` with the noise sums of CONTROL_VARIATE_SUMS (NaN
    with fewer than 7 shards), the others by ``control_variate_adjusted`` with those of
    MOMENT_CONTROLS, which adjusts each sum (int x dt, int x^2 dt, the flights, sum T,
    sum T^2) before the ratio (NaN with fewer than ``len(MOMENT_CONTROLS) + 3`` shards)."""
    time = np.array([s.time for s in shards])
    int_x = np.array([s.int_x for s in shards])
    int_x2 = np.array([s.int_x2 for s in shards])
    collisions = np.array([s.collisions for s in shards], dtype=float)
    mean_x, mean_x_err = jackknife(_mean_x, int_x, time)
    delta_x, delta_x_err = jackknife(_delta_x, int_x, int_x2, time)
    rate, rate_err = jackknife(lambda c, t: c / t, collisions, time)
    controls = np.array([[getattr(s, name) for name in CONTROL_VARIATE_SUMS] for s in shards])
    if len(shards) >= len(CONTROL_VARIATE_SUMS) + 3:  # enough shards to fit the slopes
        controlled, controlled_err, _ = control_variate_rate(collisions, time, controls)
    else:
        controlled = controlled_err = np.nan
    flights = np.array([s.flights for s in shards], dtype=float)
    flight_time = np.array([s.flight_time_sum for s in shards])
    flight_time_squared = np.array([s.flight_time_squared_sum for s in shards])
    mean_t, mean_t_err = jackknife(lambda f, n: f / n, flight_time, flights)
    second_t, second_t_err = jackknife(lambda f, n: f / n, flight_time_squared, flights)
    controlled_moments = dict.fromkeys(CONTROLLED_MOMENTS, (np.nan, np.nan))
    if len(shards) >= len(MOMENT_CONTROLS) + 3:
        moment_controls = np.array([[getattr(s, name) for name in MOMENT_CONTROLS] for s in shards])

        def adjusted(tallies):
            return control_variate_adjusted(tallies, time, moment_controls)[0]

        x_sum, x2_sum = adjusted(int_x), adjusted(int_x2)
        flights_sum, t_sum, t2_sum = (
            adjusted(flights),
            adjusted(flight_time),
            adjusted(flight_time_squared),
        )
        controlled_moments = {
            "mean_x": jackknife(_mean_x, x_sum, time),
            "delta_x": jackknife(_delta_x, x_sum, x2_sum, time),
            "mean_flight_time": jackknife(lambda f, n: f / n, t_sum, flights_sum),
            "flight_time_second_moment": jackknife(lambda f, n: f / n, t2_sum, flights_sum),
        }
    controlled_columns = {
        column: [float(value)]
        for name, pair in controlled_moments.items()
        for column, value in zip((f"{name}_controlled", f"{name}_controlled_err"), pair)
    }
    total = merge_shards(shards)
    return pd.DataFrame(
        {
            "r": [float(restitution)],
            "mean_x": [float(mean_x)],
            "mean_x_err": [float(mean_x_err)],
            "delta_x": [float(delta_x)],
            "delta_x_err": [float(delta_x_err)],
            **controlled_columns,
            "collision_rate": [float(rate)],
            "collision_rate_err": [float(rate_err)],
            "collision_rate_controlled": [float(controlled)],
            "collision_rate_controlled_err": [float(controlled_err)],
            "mean_flight_time": [float(mean_t)],
            "mean_flight_time_err": [float(mean_t_err)],
            "flight_time_second_moment": [float(second_t)],
            "flight_time_second_moment_err": [float(second_t_err)],
            "flights": [int(total.flights)],
            "total_time": [float(total.time)],
            "collisions": [int(total.collisions)],
            "steps": [int(total.steps)],
            "shards": [len(shards)],
            "shards_out_of_budget": [int(total.budget_exhausted)],
        }
    )


def _bin_centres(lower, upper):
    with np.errstate(invalid="ignore"):
        centre = np.sqrt(lower * upper)
    centre[lower == 0.0] = 0.5 * upper[lower == 0.0]
    return centre


def control_variate_rate(tallies, times, controls):
    """A rate per unit time corrected by martingale control variates, and its standard error.

    ``tallies`` (shards, or shards x bins) are what each shard counted (e.g. its collisions),
    ``times`` (shards) its recorded time and ``controls`` (shards x p) sums over the shard's
    steps of noise terms whose expectation is exactly 0 under the simulated process
    (``ShardTallies.noise_sum``, the sum of the velocity noise sqrt(2 dt) normal_r of
    eq. (vstep), ``noise_v_sum``, ``noise_scaled_sum``, ``normal_sum``).  The estimate is

        sum_k (tallies_k - beta_{-k} . controls_k) / sum_k times_k

    with beta_{-k} the weighted least-squares slope (with intercept, weights times_j) of
    tallies_j / times_j on controls_j / times_j over the other shards j != k (cross-fitting).
    As controls_k has mean 0 and is independent of beta_{-k}, each correction has mean 0: the
    estimate has the plain estimator's expectation, with no O(1 / shards) bias from the
    fitted slope.  The standard error is the delete-one jackknife of the corrected per-shard
    tallies over the times (``jackknife``), which holds the slope's own scatter (the
    corrections are made out of sample).  Returns (value, error, beta) with beta the slope
    fitted to all shards (p, or p x bins), for reporting.
    """
    times = np.asarray(times, dtype=float)
    adjusted, beta = control_variate_adjusted(tallies, times, controls)
    value, error = jackknife(lambda a, t: a / t, adjusted, times[:, None])
    shape = np.shape(tallies)[1:]
    return value.reshape(shape), error.reshape(shape), beta


def control_variate_adjusted(tallies, times, controls):
    """Each shard's tallies less their cross-fitted share of the control variates: the terms
    ``tallies_k - beta_{-k} . controls_k`` of ``control_variate_rate`` (shards, or shards x
    bins), and the slope fitted to all shards (p, or p x bins).  Each adjusted tally has the
    plain tally's expectation (controls_k has mean 0 and is independent of beta_{-k}), so any
    function of their sums is estimated as of the plain ones, with its error by ``jackknife``
    (e.g. Delta x from the adjusted int x dt and int x^2 dt)."""
    tallies = np.asarray(tallies, dtype=float)
    times = np.asarray(times, dtype=float)
    controls = np.asarray(controls, dtype=float)
    if controls.ndim == 1:
        controls = controls[:, None]
    n, p = controls.shape
    if n < p + 3:
        raise ValueError(f"{n} shards are too few for {p} control variates (need {p + 3})")
    flat = tallies.reshape(n, -1)
    y = flat / times[:, None]
    design = np.column_stack([np.ones(n), controls / times[:, None]]) * np.sqrt(times)[:, None]
    weighted_y = y * np.sqrt(times)[:, None]

    def slope(keep):
        fitted, *_ = np.linalg.lstsq(design[keep], weighted_y[keep], rcond=None)
        return fitted[1:]  # (p, bins)

    adjusted = np.empty_like(flat)
    everyone = np.ones(n, dtype=bool)
    for k in range(n):
        others = everyone.copy()
        others[k] = False
        adjusted[k] = flat[k] - controls[k] @ slope(others)
    shape = tallies.shape[1:]
    return adjusted.reshape(tallies.shape), slope(everyone).reshape((p, *shape))
