"""From summed shard tallies to P(0,v), P(x), <v^2>_x, P(x,v), the flights and the moments.

Every estimate is a function of the shards' summed tallies (``tallies.ShardTallies``); its
standard error comes from the scatter between shards by the delete-one jackknife
(``jackknife``: for a ratio of sums over shards of equal time it is the standard error of the
mean of the per-shard estimates).  ``control_variate_adjusted`` lowers the variance of any such
estimate with the shards' martingale control variates (``control_variate_rate``: of a rate);
the tables keep both estimates, plain and ``*_controlled``.

Examples
--------
Two shards of time 2 on one speed bin per decade, built by hand (``tallies``): 4 and 2
collisions, so I = 6 / 4 = 1.5 collisions per unit time, and the jackknife error is the
standard error of the mean of the shards' rates 2 and 1:

>>> from bouncing_ball.bins import LinearBins, LogBins
>>> from bouncing_ball.settings import ShardSettings
>>> from bouncing_ball.tallies import SCALAR_INDEX, ShardTallies
>>> from bouncing_ball.histograms import outgoing_speed_histogram, position_moments_summary
>>> settings = ShardSettings(
...     shard_time=2.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
...     max_steps=100, speed_bins=LogBins(0.1, 10.0, 1), position_bins=LogBins(0.1, 10.0, 1),
...     velocity_bins=LinearBins(-1.0, 1.0, 1.0), flight_time_bins=LogBins(0.1, 10.0, 1),
... )
>>> def shard(speed_counts, int_x, int_x2):
...     arrays = ShardTallies.loop_arrays(settings)
...     arrays["speed_counts"][:] = speed_counts
...     for name, value in (("time", 2.0), ("collisions", sum(speed_counts)),
...                         ("int_x", int_x), ("int_x2", int_x2)):
...         arrays["scalars"][SCALAR_INDEX[name]] = value
...     return ShardTallies.from_loop(settings, arrays)
>>> shards = [shard([0, 1, 3, 0], 1.0, 1.0), shard([0, 1, 1, 0], 2.0, 3.0)]
>>> summary = position_moments_summary(shards, restitution=0.5)
>>> print(summary[["collision_rate", "collision_rate_err", "mean_x", "mean_x_err"]].to_string())
   collision_rate  collision_rate_err  mean_x  mean_x_err
0             1.5                 0.5    0.75        0.25

Two shards are too few for the control variates: the ``*_controlled`` columns are NaN.

>>> print(summary["collision_rate_controlled"].isna().all())
True
>>> p0v = outgoing_speed_histogram(shards)
>>> print(p0v[["v_lo", "v_hi", "p0v", "count"]].round(6).to_string())
   v_lo  v_hi       p0v  count
0   0.0   0.1  0.000000      0
1   0.1   1.0  1.010101      2
2   1.0  10.0  0.020202      4
3  10.0   inf       NaN      0
"""

import functools
import math

import numpy as np
import pandas as pd

from .restitution import SOLVER_RESTITUTION_RANGE, in_range, parse_restitution
from .settings import RETURN_LAW_SPEED_BINS
from .tallies import (
    BOUNCE_LAGS,
    MOMENT_CONTROLS,
    RATE_CONTROLS,
    SHARDS_PER_CONTROL,
    ShardTallies,
    bounce_lag_pair_sums,
    merge_shards,
)

__all__ = [
    "CONTROLLED_MOMENTS",
    "jackknife",
    "deviations_from_mean",
    "shard_controls",
    "moment_controls",
    "outgoing_speed_density",
    "RETURN_LAW_POINTS",
    "return_law_prediction",
    "flight_law_prediction",
    "outgoing_speed_histogram",
    "position_histogram",
    "distribution_histogram",
    "flight_time_histogram",
    "return_speed_table",
    "position_moments_summary",
    "control_variate_rate",
    "control_variate_adjusted",
    "RESOLVED_CORRELATION",
    "bounce_autocorrelation",
    "bounce_chain_decay",
]


def jackknife(estimator, *per_shard):
    """Value and delete-one jackknife standard error of a function of summed tallies.

    The estimator is evaluated on the sums over all shards and on the sums leaving out each
    shard k in turn; the error is sqrt((n - 1) / n * sum_k (estimate_{-k} - mean)^2) over the
    n shards.

    Parameters
    ----------
    estimator : callable
        A function of the sums over shards, one argument per array of ``per_shard``,
        vectorised over their remaining axes.
    *per_shard : array_like
        The shards' tallies, each with the shard index as its first axis.

    Returns
    -------
    value : numpy.ndarray or float
        ``estimator`` of the sums over all shards.
    error : numpy.ndarray or float
        Its jackknife standard error, of the shape of ``value``; NaN with one shard.

    Examples
    --------
    For a ratio of sums over shards of equal time, the error is the standard error of the
    mean of the per-shard ratios (here 2 and 1):

    >>> from bouncing_ball.histograms import jackknife
    >>> value, error = jackknife(lambda c, t: c / t, [4.0, 2.0], [2.0, 2.0])
    >>> print(value, error)
    1.5 0.5
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
    spread = deviations_from_mean(leave_one_out)
    return value, np.sqrt((n - 1) / n * (spread**2).sum(axis=0))


def deviations_from_mean(values):
    """The values less their mean over the first axis, exact zeros where every value is equal.

    The mean is taken of the values less the first one (the same deviations in exact
    arithmetic): equal values give exact zeros, and so an error of exactly 0, while the
    plain mean of n equal values can be off in its last bit and leave a scatter of ~1e-17
    that a test such as ``error > 0`` takes for an error.

    Parameters
    ----------
    values : array_like, shape (n, ...), n >= 1
        The values, e.g. the delete-one estimates of the shards.

    Returns
    -------
    numpy.ndarray
        Of the shape of ``values``.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.histograms import deviations_from_mean
    >>> values = np.full(3, 0.8132702392002724)
    >>> print(np.std(values) > 0, np.abs(deviations_from_mean(values)).max())
    True 0.0
    """
    values = np.asarray(values, dtype=float)
    if values.ndim == 0 or len(values) == 0:
        raise ValueError(f"values: need at least one value, got shape {values.shape}")
    shifted = values - values[0]
    return shifted - shifted.mean(axis=0)


def shard_controls(shards, names):
    """The control sums ``names`` of each shard, if the shards are enough to fit their slopes.

    The jackknife of the cross-fitted adjusted tallies (``control_variate_adjusted``) keeps
    the slopes of the fit without each shard k as they are; it does not refit them without
    each left-out shard, and needs no correction for that: each adjusted tally already holds
    its own out-of-sample slope's noise, so its squared error is unbiased for the estimate's
    variance (Gaussian and Student-t controls at three shards per control,
    tests/unit/test_control_variates.py), while refitting in each leave-one-out sample
    counts the slopes' noise twice and overstates the variance.  The error itself is
    noisy: z = (estimate - truth) / error follows Student's t, with n - 1 degrees of freedom
    at most and fewer as p grows, so its tails are heavy with few shards per control; at
    least ``tallies.SHARDS_PER_CONTROL`` shards per control are asked for.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards.
    names : sequence of str
        The control sums, fields of ``ShardTallies`` (e.g. ``tallies.RATE_CONTROLS``).

    Returns
    -------
    numpy.ndarray or None
        The sums, shape (shards, p) with p = ``len(names)``; None with fewer than
        ``SHARDS_PER_CONTROL * p`` shards.

    Examples
    --------
    See the module's example: two shards are too few for any control.
    """
    if len(shards) < SHARDS_PER_CONTROL * len(names):
        return None
    return np.array([[getattr(s, name) for name in names] for s in shards], dtype=float)


def moment_controls(shards, flight_law=None):
    """The control sums of the summary's moments, as many as the shards can fit.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards.
    flight_law : numpy.ndarray, optional
        ``flight_law_prediction`` of the shards: the flight-law controls, each shard's sums
        of T and T^2 less their prediction, join the martingale sums.

    Returns
    -------
    numpy.ndarray or None
        The first of ``tallies.MOMENT_CONTROLS`` with the flight-law controls,
        ``MOMENT_CONTROLS``, the fewer ``tallies.RATE_CONTROLS`` with the flight-law
        controls, ``RATE_CONTROLS``, that the shards are enough to fit
        (``SHARDS_PER_CONTROL`` per control), else None.

    Examples
    --------
    See the module's example: two shards are too few for any control.
    """
    extra = None
    if flight_law is not None:
        sums = np.array([[s.flight_time_sum, s.flight_time_squared_sum] for s in shards])
        extra = sums - np.asarray(flight_law, dtype=float)
    flight_options = (None,) if extra is None else (extra, None)
    for names in (MOMENT_CONTROLS, RATE_CONTROLS):
        for flights in flight_options:
            width = len(names) + (0 if flights is None else flights.shape[1])
            if len(shards) >= SHARDS_PER_CONTROL * width:
                controls = shard_controls(shards, names)
                return controls if flights is None else np.column_stack([controls, flights])
    return None


def _controlled(estimator, controls, times, adjusted, fixed=()):
    """Value and jackknife error of ``estimator`` of the sums over shards of ``adjusted``, each
    first adjusted by the control variates (``control_variate_adjusted``; ``times`` are the
    shards' times), and of ``fixed`` as they are; NaN where ``controls`` is None."""
    if controls is None:
        sums = [np.asarray(a, dtype=float).sum(axis=0) for a in (*adjusted, *fixed)]
        with np.errstate(divide="ignore", invalid="ignore"):
            shape = np.shape(estimator(*sums))
        return np.full(shape, np.nan), np.full(shape, np.nan)
    arrays = [np.asarray(a, dtype=float) for a in adjusted]
    n = len(times)
    # one fit for all: the columns of every array side by side, split again after
    stacked = np.concatenate([a.reshape(n, -1) for a in arrays], axis=1)
    corrected = control_variate_adjusted(stacked, times, controls)[0]
    ends = np.cumsum([a[0].size for a in arrays])[:-1]
    parts = [c.reshape(a.shape) for c, a in zip(np.split(corrected, ends, axis=1), arrays)]
    return jackknife(estimator, *parts, *fixed)


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
    >>> from bouncing_ball.histograms import outgoing_speed_density
    >>> print(outgoing_speed_density(6.0, 4.0, 1.0, 2.0))
    1.0
    """
    return counts / (time * 0.5 * (upper**2 - lower**2))


@functools.lru_cache(maxsize=8)
def _solver_outgoing_density(exact):
    """The solver's P(0, u) of eq. (inteq) at the exact r, or None outside its range."""
    if not in_range(exact, SOLVER_RESTITUTION_RANGE):
        return None
    from .solver import solve_outgoing_speed_density  # numba and scipy: only where solved

    return solve_outgoing_speed_density(exact).outgoing_speed_density


def _occupied_fine_bins(shards):
    """The shards' ``return_law_speed_counts`` in the fine bins any shard reached, and those
    bins' edges (the fine under- and overflow bins as the decade beyond each end)."""
    fine = RETURN_LAW_SPEED_BINS
    counts = np.stack([s.return_law_speed_counts for s in shards]).astype(float)
    occupied = np.flatnonzero(counts.sum(axis=0))
    lower = np.maximum(fine.lower[occupied], 0.1 * fine.lo)
    upper = np.minimum(fine.upper[occupied], 10.0 * fine.hi)
    return counts[:, occupied], lower, upper


# the fewest shards for the return-law control: SHARDS_PER_CONTROL, and 4 for a slope and
# an intercept fitted out of sample
_RETURN_LAW_SHARDS = max(SHARDS_PER_CONTROL, 4)
# the fewest shards for the flight-law controls, beside at least the RATE_CONTROLS
_FLIGHT_LAW_SHARDS = SHARDS_PER_CONTROL * (len(RATE_CONTROLS) + 2)


#: Gauss-Legendre points in ln u per fine bin of ``settings.RETURN_LAW_SPEED_BINS`` (2.3 %
#: wide) in ``return_law_prediction``.
RETURN_LAW_POINTS = 4


def return_law_prediction(shards: list[ShardTallies], restitution: float, outgoing_density):
    """Each shard's expected collisions per speed bin, given the outgoing speeds it recorded.

    A ball leaving the floor at speed u comes back at speed v with the return-speed law
    v G_g(v, u) of eq. (kernel3) and leaves again at r v, eq. (restitution).  So the n-th
    collision's outgoing speed falls in bin j with probability M_j(u_(n-1)), the law's
    probability of v in bin j / r, and in equilibrium (the balance eq. (inteq) expresses)

        E[collisions in bin j] = E[sum_n M_j(u_n)]

    over the collisions of a shard, up to one collision at the ends of its recording.  This
    is the shard's ``return_law_speed_counts`` (outgoing speeds on the fine
    ``settings.RETURN_LAW_SPEED_BINS``) times M_j averaged over each fine bin with weight
    u P(0, u) (``flight_time.return_speed_bin_probabilities``; the solver's P(0, u) only
    weighs u inside a 2.3 % wide bin).  Counts minus prediction is the return-law control
    variate of ``outgoing_speed_histogram``: mean 0 for the process of eq. (kernel3); in a
    rare bin of P(0, v) it removes most of the counting noise, as the prediction spreads
    each collision over every bin it can reach next.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same speed bins.
    restitution : float
        r.
    outgoing_density : callable
        P(0, u) of an array of u > 0 (the solver's; its normalisation does not matter).

    Returns
    -------
    numpy.ndarray, shape (shards, speed bins)
        The prediction for each shard and bin of ``speed_bins`` (under- and overflow
        included).

    Examples
    --------
    At r = 1/2 a shard whose collisions all left at u = 1 (a fine bin near 1) expects its
    next collisions mostly between 0.1 and 10:

    >>> import numpy as np
    >>> from bouncing_ball.bins import LinearBins, LogBins
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.settings import RETURN_LAW_SPEED_BINS, ShardSettings
    >>> from bouncing_ball.tallies import ShardTallies
    >>> from bouncing_ball.histograms import return_law_prediction
    >>> settings = ShardSettings(
    ...     shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
    ...     max_steps=100, speed_bins=LogBins(0.1, 10.0, 1),
    ... )
    >>> arrays = ShardTallies.loop_arrays(settings)
    >>> arrays["return_law_speed_counts"][1 + 1000] = 100  # u in [1, 1.023)
    >>> shard = ShardTallies.from_loop(settings, arrays)
    >>> density = lambda u: outgoing_speed_density(u, "1/2")
    >>> prediction = return_law_prediction([shard], 0.5, density)
    >>> print(np.round(prediction, 1), round(float(prediction.sum()), 9))
    [[ 0.4 58.5 41.1  0. ]] 100.0
    """
    from .flight_time import return_speed_bin_probabilities

    counts, lower, upper = _occupied_fine_bins(shards)
    bins = shards[0].speed_bins
    if lower.size == 0:
        return np.zeros((len(shards), bins.n + 2))
    r = float(restitution)
    with np.errstate(invalid="ignore"):  # a bin where P(0, u) underflows: NaN, redone below
        law = return_speed_bin_probabilities(
            outgoing_density, lower, upper, bins.lower / r, bins.upper / r, RETURN_LAW_POINTS
        )
    lost = ~np.all(np.isfinite(law), axis=1)  # P(0, u) of 0 all over a bin: weigh ln u evenly
    if np.any(lost):
        law[lost] = return_speed_bin_probabilities(
            lambda u: u**-2.0, lower[lost], upper[lost], bins.lower / r, bins.upper / r
        )
    return counts @ law


def flight_law_prediction(shards: list[ShardTallies], outgoing_density) -> np.ndarray:
    """Each shard's expected sums of the flight times T and T^2, given its outgoing speeds.

    A flight that leaves the floor at speed u lasts T with mean E[T | u], eq. (meanT), and
    second moment E[T^2 | u], eq. (meanT2).  Summed over a shard's collisions (its
    ``return_law_speed_counts``, each fine bin's E averaged over it with weight u P(0, u) as
    in ``return_law_prediction``) they have the expectation of the shard's
    ``flight_time_sum`` and ``flight_time_squared_sum``, up to one flight at the ends of its
    recording.  The differences are the flight-law control variates of
    ``position_moments_summary``.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards.
    outgoing_density : callable
        P(0, u) of an array of u > 0 (the solver's; its normalisation does not matter).

    Returns
    -------
    numpy.ndarray, shape (shards, 2)
        The predicted sum of T and of T^2 of each shard.

    Examples
    --------
    100 flights leaving at u in [1, 1.023) last about 100 E[T | 1] = 315 in all:

    >>> import dataclasses
    >>> import numpy as np
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> from bouncing_ball.settings import ShardSettings
    >>> from bouncing_ball.tallies import ShardTallies
    >>> from bouncing_ball.histograms import flight_law_prediction
    >>> settings = ShardSettings(
    ...     shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
    ...     max_steps=100,
    ... )
    >>> arrays = ShardTallies.loop_arrays(settings)
    >>> arrays["return_law_speed_counts"][1 + 1000] = 100  # u in [1, 1.023)
    >>> shard = ShardTallies.from_loop(settings, arrays)
    >>> density = lambda u: outgoing_speed_density(u, "1/2")
    >>> print(np.round(flight_law_prediction([shard], density), 1))
    [[ 317.8 2294.7]]
    """
    from .flight_time import (
        _log_gauss,
        flight_time_second_moment_given_speed,
        mean_flight_time_given_speed,
    )

    counts, lower, upper = _occupied_fine_bins(shards)
    if lower.size == 0:
        return np.zeros((len(shards), 2))
    u, weights = _log_gauss(lower, upper, RETURN_LAW_POINTS)
    flux = u * outgoing_density(u) * weights
    lost = ~(np.sum(flux, axis=1) > 0.0)  # P(0, u) of 0 all over a bin: weigh ln u evenly
    flux[lost] = weights[lost] / u[lost]
    flux /= flux.sum(axis=1)[:, None]
    moments = np.stack(
        [
            np.sum(flux * mean_flight_time_given_speed(u), axis=1),
            np.sum(flux * flight_time_second_moment_given_speed(u), axis=1),
        ],
        axis=1,
    )
    return counts @ moments


def outgoing_speed_histogram(
    shards: list[ShardTallies], restitution=None, return_law=None
) -> pd.DataFrame:
    """P(0, v) on the outgoing side, bin averages weighted by v.

    Bin averages mean p0v = int_bin v P(0,v) dv / int_bin v dv (``outgoing_speed_density``,
    eq. (collrate)).

    Parameters
    ----------
    shards : list of ShardTallies
        The shards, all on the same speed bins.
    restitution : float, str or fractions.Fraction, optional
        The shards' r.  Given, and inside the solver's range
        (``restitution.SOLVER_RESTITUTION_RANGE``), each bin's counts are also corrected by
        its return-law control variate, counts minus ``return_law_prediction`` with the
        solver's P(0, u) of eq. (inteq).
    return_law : numpy.ndarray, optional
        ``return_law_prediction`` of these shards, if already at hand (a row per shard): used
        instead of computing it from ``restitution``.

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
        without ``restitution`` or ``return_law``, outside the solver's range, or with
        fewer than 4 shards).

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
    if return_law is None and restitution is not None and len(shards) >= _RETURN_LAW_SHARDS:
        exact = parse_restitution(restitution)
        solver_density = _solver_outgoing_density(exact)
        if solver_density is not None:
            return_law = return_law_prediction(shards, float(exact), solver_density)
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


def _mean_x(int_x, time):
    return int_x / time


def _delta_x(int_x, int_x2, time):
    return np.sqrt(int_x2 / time - (int_x / time) ** 2)


#: The moments ``position_moments_summary`` also gives corrected by the control variates of
#: ``moment_controls`` (its columns ``{name}_controlled``).
CONTROLLED_MOMENTS = ("mean_x", "delta_x", "mean_flight_time", "flight_time_second_moment")


# each moment as a function of the sums of the collisions, int x dt, int x^2 dt, the
# flights, sum T and sum T^2, and of the times
_MOMENT_ESTIMATORS = {
    "collision_rate": lambda c, ix, ix2, n, f, f2, t: c / t,
    "mean_x": lambda c, ix, ix2, n, f, f2, t: _mean_x(ix, t),
    "delta_x": lambda c, ix, ix2, n, f, f2, t: _delta_x(ix, ix2, t),
    "mean_flight_time": lambda c, ix, ix2, n, f, f2, t: f / n,
    "flight_time_second_moment": lambda c, ix, ix2, n, f, f2, t: f2 / n,
}


def _controlled_moments(controls, time, sums, suffix):
    """The columns ``{moment}_{suffix}`` and ``{moment}_{suffix}_err`` of every moment of
    ``_MOMENT_ESTIMATORS``, its sums ``sums`` adjusted by ``controls`` (NaN where None)."""
    columns = {}
    for name, estimator in _MOMENT_ESTIMATORS.items():
        value, error = _controlled(estimator, controls, time, sums, [time])
        columns[f"{name}_{suffix}"] = [float(value)]
        columns[f"{name}_{suffix}_err"] = [float(error)]
    return columns


def position_moments_summary(shards: list[ShardTallies], restitution: float) -> pd.DataFrame:
    """One row of moments: <x>, Delta x, the collision rate I and the flight time's moments.

    <x> and Delta x are eq. (xandDeltax), I eq. (collrate); the flight time T has its mean and
    second moment per flight.  Each is given three times:

    - plain: the time averages, collisions per time, the flights' averages;
    - ``*_martingale``: the same with each sum (the collisions, int x dt, int x^2 dt, the
      flights, sum T, sum T^2) corrected before the ratio by the martingale control
      variates of ``moment_controls`` without a flight law (``tallies.MOMENT_CONTROLS`` or
      the fewer ``tallies.RATE_CONTROLS``, as many as the shards can fit,
      ``shard_controls``; NaN with too few shards).  Their mean is 0 for the simulated
      process whatever it is, so the estimate has the plain one's expectation
      (``control_variate_adjusted``) with less variance: with the plain one, it is
      independent of the theory it is held against;
    - ``*_controlled``: corrected by the same controls and, where r is in the solver's
      range and the shards suffice, the flight-law controls of ``flight_law_prediction``
      (``kernel3_controls`` True).  Those are built from E[T | u] and E[T^2 | u] of
      eq. (kernel3), the theory under test: their mean is 0 only if the simulated process
      follows it, so a simulation that departs from eq. (kernel3) shifts this estimate by
      more or less than its own departure.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards.
    restitution : float, str or fractions.Fraction
        The restitution coefficient r of the shards, written in column ``r``; the solver's
        P(0, u) at r weighs the fine bins of the flight-law controls.

    Returns
    -------
    pandas.DataFrame
        One row: ``r``; ``mean_x``, ``delta_x``, ``collision_rate``, ``mean_flight_time``,
        ``flight_time_second_moment``, each with ``_err``, ``_martingale``,
        ``_martingale_err``, ``_controlled`` and ``_controlled_err``; ``kernel3_controls``
        (whether ``_controlled`` uses the flight-law controls of eq. (kernel3)); the totals
        ``flights``, ``total_time``, ``collisions``, ``steps``, ``shards`` and
        ``shards_out_of_budget``; ``control_variates``, the number of controls fitted to the
        shards for the ``_controlled`` values (0: none, and those are NaN).

    Examples
    --------
    See the module's example.
    """
    time = np.array([s.time for s in shards])
    int_x = np.array([s.int_x for s in shards])
    int_x2 = np.array([s.int_x2 for s in shards])
    collisions = np.array([s.collisions for s in shards], dtype=float)
    mean_x, mean_x_err = jackknife(_mean_x, int_x, time)
    delta_x, delta_x_err = jackknife(_delta_x, int_x, int_x2, time)
    rate, rate_err = jackknife(lambda c, t: c / t, collisions, time)
    flight_law = None
    if len(shards) >= _FLIGHT_LAW_SHARDS:  # else too few shards to fit them
        density = _solver_outgoing_density(parse_restitution(restitution))
        flight_law = None if density is None else flight_law_prediction(shards, density)
    flights = np.array([s.flights for s in shards], dtype=float)
    flight_time = np.array([s.flight_time_sum for s in shards])
    flight_time_squared = np.array([s.flight_time_squared_sum for s in shards])
    mean_t, mean_t_err = jackknife(lambda f, n: f / n, flight_time, flights)
    second_t, second_t_err = jackknife(lambda f, n: f / n, flight_time_squared, flights)
    sums = (collisions, int_x, int_x2, flights, flight_time, flight_time_squared)
    martingale = moment_controls(shards)
    controls = moment_controls(shards, flight_law)
    # the flight-law controls in use: the *_controlled columns lean on eq. (kernel3)
    kernel3 = controls is not None and martingale is not None
    kernel3 = kernel3 and controls.shape[1] > martingale.shape[1]
    estimates = {
        **_controlled_moments(martingale, time, sums, "martingale"),
        **_controlled_moments(controls, time, sums, "controlled"),
    }
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
            "mean_flight_time": [float(mean_t)],
            "mean_flight_time_err": [float(mean_t_err)],
            "flight_time_second_moment": [float(second_t)],
            "flight_time_second_moment_err": [float(second_t_err)],
            **estimates,
            "kernel3_controls": [bool(kernel3)],
            "flights": [int(total.flights)],
            "total_time": [float(total.time)],
            "collisions": [int(total.collisions)],
            "steps": [int(total.steps)],
            "shards": [len(shards)],
            "shards_out_of_budget": [int(total.budget_exhausted)],
            "control_variates": [0 if controls is None else int(np.shape(controls)[1])],
        }
    )


def _bin_centres(lower, upper):
    with np.errstate(invalid="ignore"):
        centre = np.sqrt(lower * upper)
    centre[lower == 0.0] = 0.5 * upper[lower == 0.0]
    return centre


def control_variate_rate(tallies, times, controls):
    """A rate per unit time corrected by martingale control variates, and its standard error.

    The controls are sums over the shard's steps of noise terms whose expectation is exactly
    0 under the simulated process (``tallies.ShardTallies``: e.g. ``noise_sum``, the sum of
    the velocity noise sqrt(2 dt) normal_r of eq. (vstep)).  The estimate is::

        sum_k (tallies_k - beta_{-k} . controls_k) / sum_k times_k

    with beta_{-k} the weighted least-squares slope (with intercept, weights times_j) of
    tallies_j / times_j on controls_j / times_j over the other shards j != k (cross-fitting,
    ``control_variate_adjusted``).  As controls_k has mean 0 and is independent of
    beta_{-k}, each correction has mean 0: the estimate has the plain estimator's
    expectation, with no O(1 / shards) bias from the fitted slope.  The standard error is
    the delete-one jackknife of the corrected per-shard tallies over the times
    (``jackknife``), which holds the slope's own scatter (the corrections are made out of
    sample).

    Parameters
    ----------
    tallies : array_like
        What each shard counted (e.g. its collisions), shape (shards,) or (shards, bins).
    times : array_like
        Each shard's recorded time, shape (shards,).
    controls : array_like
        Each shard's control sums, shape (shards, p) or (shards,) for p = 1.

    Returns
    -------
    value : numpy.ndarray
        The corrected rate, of the shape of a shard's tallies.
    error : numpy.ndarray
        Its jackknife standard error.
    beta : numpy.ndarray
        The slope fitted to all shards, (p,) or (p, bins), for reporting.

    Raises
    ------
    ValueError
        With fewer than p + 3 shards.

    Examples
    --------
    Tallies that are a rate of 5 plus 3 times a control: the control explains all the
    scatter, so the corrected rate is 5 with no error.

    >>> import numpy as np
    >>> from bouncing_ball.histograms import control_variate_rate
    >>> controls = np.array([1.0, -1.0, 2.0, -2.0, 0.5, -0.5])
    >>> times = np.full(6, 2.0)
    >>> value, error, beta = control_variate_rate(5.0 * times + 3.0 * controls, times, controls)
    >>> print(np.round(value, 12), np.round(error, 12), np.round(beta, 12))
    5.0 0.0 [3.]
    """
    times = np.asarray(times, dtype=float)
    adjusted, beta = control_variate_adjusted(tallies, times, controls)
    value, error = jackknife(lambda a, t: a / t, adjusted, times[:, None])
    shape = np.shape(tallies)[1:]
    return value.reshape(shape), error.reshape(shape), beta


def control_variate_adjusted(tallies, times, controls):
    """Each shard's tallies less their cross-fitted share of the control variates.

    These are the terms ``tallies_k - beta_{-k} . controls_k`` of ``control_variate_rate``.
    Each adjusted tally has the plain tally's expectation (controls_k has mean 0 and is
    independent of beta_{-k}), so any function of their sums is estimated as of the plain
    ones, with its error by ``jackknife`` (e.g. Delta x from the adjusted int x dt and
    int x^2 dt).

    Parameters
    ----------
    tallies : array_like
        Each shard's tallies, shape (shards,) or (shards, ...).
    times : array_like
        Each shard's recorded time, shape (shards,): the weights of the fit.
    controls : array_like
        Each shard's control sums, shape (shards, p) or (shards,) for p = 1.

    Returns
    -------
    adjusted : numpy.ndarray
        The adjusted tallies, of the shape of ``tallies``.
    beta : numpy.ndarray
        The slope fitted to all shards, shape (p, ...).

    Raises
    ------
    ValueError
        With fewer than p + 3 shards.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.histograms import control_variate_adjusted
    >>> controls = np.array([1.0, -1.0, 2.0, -2.0])
    >>> adjusted, beta = control_variate_adjusted(10.0 + 3.0 * controls, np.ones(4), controls)
    >>> print(np.round(adjusted, 12), np.round(beta, 12))
    [10. 10. 10. 10.] [3.]
    >>> control_variate_adjusted(np.ones(3), np.ones(3), np.ones(3))
    Traceback (most recent call last):
    ...
    ValueError: 3 shards are too few for 1 control variates (need 4)
    """
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


#: The least ratio of a lag's principal correlation to its jackknife error for the lag to
#: enter the fit of the bounce chain's decay rate (``bounce_chain_decay``): past it, ln of
#: the correlation is dominated by its noise (and biased by it, E[ln X] != ln E[X]).
RESOLVED_CORRELATION = 5.0


def _bounce_lag_covariances(sums):
    """C_ab(k) = <f_a(u_{n-k}) f_b(u_n)> - <f_a(u_{n-k})> <f_b(u_n)>, f = (ln u, u), from
    the bounce-lag sums (``tallies.BOUNCE_LAG_SUMS``; shape (..., 9, lags)): shape
    (..., lags, 2, 2), each mean over the pairs of its lag."""
    named = bounce_lag_pair_sums(sums)
    pairs = named["lag_pairs"][..., None]
    leading = np.stack([named["lag_log_speed_leading"], named["lag_speed_leading"]], -1) / pairs
    trailing = np.stack([named["lag_log_speed_trailing"], named["lag_speed_trailing"]], -1) / pairs
    products = (
        np.stack(
            [
                np.stack([named["lag_log_log"], named["lag_log_speed"]], -1),
                np.stack([named["lag_speed_log"], named["lag_speed_speed"]], -1),
            ],
            -2,
        )
        / pairs[..., None]
    )
    return products - leading[..., :, None] * trailing[..., None, :]


def _log_speed_autocorrelation(sums):
    """rho_k of ln u_n, k = 1 .. BOUNCE_LAGS: C_00(k) / C_00(0)."""
    covariance = _bounce_lag_covariances(sums)[..., 0, 0]
    return covariance[..., 1:] / covariance[..., :1]


def _principal_correlation(sums):
    """The largest lag-k correlation of a combination a ln u + b u, k = 1 .. BOUNCE_LAGS: the
    largest eigenvalue of S(k) x = mu C(0) x, S(k) the symmetric part of C(k)."""
    covariance = _bounce_lag_covariances(sums)
    symmetric = 0.5 * (covariance + np.swapaxes(covariance, -1, -2))
    inverse = np.linalg.inv(np.linalg.cholesky(symmetric[..., :1, :, :]))
    whitened = inverse @ symmetric[..., 1:, :, :] @ np.swapaxes(inverse, -1, -2)
    return np.linalg.eigvalsh(whitened)[..., -1]


def _lag_sums(shards):
    sums = np.stack([shard.bounce_lag_sums for shard in shards])
    if np.any(sums[:, 0, :] < 2.0):
        raise ValueError(
            "shards: every shard needs at least BOUNCE_LAGS + 2 recorded collisions after "
            f"{BOUNCE_LAGS} earlier ones for the bounce chain's correlations; use longer shards"
        )
    return sums


def bounce_autocorrelation(shards: list[ShardTallies]) -> pd.DataFrame:
    """The autocorrelation of the bounce chain over lags k = 1 .. BOUNCE_LAGS, with errors.

    From the shards' bounce-lag sums (``tallies.BOUNCE_LAG_SUMS``): the autocorrelation of
    ln u_n (u_n the outgoing speed of bounce n),

        rho_k = C(k) / C(0),   C(k) = <ln u_{n-k} ln u_n> - <ln u_{n-k}> <ln u_n>,

    each mean over the pairs k apart (a per-lag covariance, unbiased by the ends of the
    recording), and the principal correlation mu_k: the largest lag-k correlation of a
    combination a ln u + b u, the largest eigenvalue of the generalised problem
    S(k) x = mu C(0) x on the 2 x 2 covariances of (ln u, u) (S(k) the symmetric part of
    C(k)).  rho_k holds every mode of the chain that ln u projects on, the faster ones too;
    mu_k picks the slowest, and decays as lambda_2^k of eq. (inteq)'s operator
    (``relaxation.bounce_chain_relaxation``) from the first lags.  Errors by the delete-one
    jackknife over the shards (``jackknife``).

    Parameters
    ----------
    shards : list of tallies.ShardTallies
        At least 2, each with at least BOUNCE_LAGS + 2 recorded collisions.

    Returns
    -------
    pandas.DataFrame
        lag (1 .. BOUNCE_LAGS), autocorrelation, autocorrelation_err, principal_correlation,
        principal_correlation_err.

    Raises
    ------
    ValueError
        With fewer than 2 shards, or a shard with too few collisions.
    """
    if len(shards) < 2:
        raise ValueError(f"shards: the jackknife needs at least 2 shards, got {len(shards)}")
    sums = _lag_sums(shards)
    rho, rho_err = jackknife(_log_speed_autocorrelation, sums)
    mu, mu_err = jackknife(_principal_correlation, sums)
    return pd.DataFrame(
        {
            "lag": np.arange(1, BOUNCE_LAGS + 1),
            "autocorrelation": rho,
            "autocorrelation_err": rho_err,
            "principal_correlation": mu,
            "principal_correlation_err": mu_err,
        }
    )


def _fitted_decay_rate(correlation, lags, weights):
    """-slope of the weighted least-squares line through (k, ln correlation_k)."""
    log_correlation = np.log(correlation)
    total = weights.sum()
    mean_lag = (weights * lags).sum() / total
    mean_log = (weights * log_correlation).sum(axis=-1, keepdims=True) / total
    centred = lags - mean_lag
    return (
        -(weights * centred * (log_correlation - mean_log)).sum(axis=-1)
        / (weights * centred**2).sum()
    )


def bounce_chain_decay(shards: list[ShardTallies]) -> dict:
    """The decay rate of the bounce chain's correlations, -ln lambda_2, with its error.

    A weighted least-squares fit of ln mu_k = a - gamma k (mu_k the principal correlation of
    ``bounce_autocorrelation``) over the lags k = 1 .. k_max where mu_k is resolved: k_max
    the last lag before the first with mu_k < RESOLVED_CORRELATION x its jackknife error.
    The weights are 1 / (error of ln mu_k)^2 and the window are those of the whole run, held
    fixed in the delete-one jackknife over the shards, whose scatter of the fitted gamma is
    its error (the lags' correlated noise included).  mu_k rather than rho_k of ln u: rho_k
    holds the faster modes of the chain, which die slowly near r = 1 (lambda_j ~ r^(j-1)),
    so a fit of ln rho_k over the first 16 lags gives a rate 3-9 % (r = 0.9) to 30-40 %
    (r = 0.99) above -ln lambda_2, whereas the pair (ln u, u) spans the second mode to
    10^-4 at r >= 0.9 and 0.3 % at r = 0.75 (the solver's matrix, docs/methods.md).

    Parameters
    ----------
    shards : list of tallies.ShardTallies
        At least 2, each with at least BOUNCE_LAGS + 2 recorded collisions.

    Returns
    -------
    dict
        decay_rate (gamma = -ln lambda, per bounce), decay_rate_err, relaxation_eigenvalue
        (exp(-gamma)), relaxation_eigenvalue_err, correlation_bounces (1 / gamma),
        correlation_bounces_err, first_lag and last_lag of the fit.  The values are NaN
        (and last_lag 0) where fewer than 2 lags are resolved: too few collisions for the
        rate.

    Raises
    ------
    ValueError
        As ``bounce_autocorrelation``.
    """
    table = bounce_autocorrelation(shards)
    mu = table["principal_correlation"].to_numpy()
    mu_err = table["principal_correlation_err"].to_numpy()
    unresolved = np.flatnonzero(~(mu > RESOLVED_CORRELATION * mu_err))
    last = int(unresolved[0]) if unresolved.size else mu.size  # lags 1 .. last
    result = {"first_lag": 1, "last_lag": last}
    if last < 2:
        nan = float("nan")
        return {
            **{
                f"{name}{suffix}": nan
                for name in ("decay_rate", "relaxation_eigenvalue", "correlation_bounces")
                for suffix in ("", "_err")
            },
            "first_lag": 1,
            "last_lag": 0,
        }
    lags = np.arange(1, last + 1, dtype=float)
    weights = (mu[:last] / mu_err[:last]) ** 2

    def rate(sums):
        return _fitted_decay_rate(_principal_correlation(sums)[..., :last], lags, weights)

    gamma, gamma_err = jackknife(rate, _lag_sums(shards))
    gamma, gamma_err = float(gamma), float(gamma_err)
    eigenvalue = math.exp(-gamma)
    result.update(
        decay_rate=gamma,
        decay_rate_err=gamma_err,
        relaxation_eigenvalue=eigenvalue,
        relaxation_eigenvalue_err=eigenvalue * gamma_err,
        correlation_bounces=1.0 / gamma,
        correlation_bounces_err=gamma_err / gamma**2,
    )
    return result
