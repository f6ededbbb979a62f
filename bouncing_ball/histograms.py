"""From summed shard tallies to P(0,v), P(x), <v^2>_x and the moments.

Every estimate is a function of the shards' summed tallies; its standard
error comes from the scatter between shards by the delete-one jackknife
(for a ratio of sums over shards of equal time it is the standard error of
the mean of the per-shard estimates).
"""

import numpy as np
import pandas as pd

from . import stages
from .tallies import ShardTallies, merge_shards

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
    <v^2>_x in bins the particle never visited.
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


def _mean_x(int_x, time):
    return int_x / time


def _delta_x(int_x, int_x2, time):
    return np.sqrt(int_x2 / time - (int_x / time) ** 2)


def position_moments_summary(shards: list[ShardTallies], restitution: float) -> pd.DataFrame:
    """One row: <x>, Delta x and the collision rate I, eqs. (collrate), (xandDeltax)."""
    time = np.array([s.time for s in shards])
    int_x = np.array([s.int_x for s in shards])
    int_x2 = np.array([s.int_x2 for s in shards])
    collisions = np.array([s.collisions for s in shards], dtype=float)
    mean_x, mean_x_err = jackknife(_mean_x, int_x, time)
    delta_x, delta_x_err = jackknife(_delta_x, int_x, int_x2, time)
    rate, rate_err = jackknife(lambda c, t: c / t, collisions, time)
    total = merge_shards(shards)
    return pd.DataFrame(
        {
            "r": [float(restitution)],
            "mean_x": [float(mean_x)],
            "mean_x_err": [float(mean_x_err)],
            "delta_x": [float(delta_x)],
            "delta_x_err": [float(delta_x_err)],
            "collision_rate": [float(rate)],
            "collision_rate_err": [float(rate_err)],
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
