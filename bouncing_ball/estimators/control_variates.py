"""Martingale control variates: the shards' noise sums, and the return-law and flight-law
predictions, as controls that lower the variance of an estimate."""

import numbers

import numpy as np

from ..settings import return_law_speed_bins
from ..tallies import (
    MOMENT_CONTROLS,
    RATE_CONTROLS,
    SHARDS_PER_CONTROL,
    ShardTallies,
)
from .jackknife import jackknife

__all__ = [
    "shard_controls",
    "moment_controls",
    "RETURN_LAW_POINTS",
    "return_law_prediction",
    "flight_law_prediction",
    "control_variate_rate",
    "control_variate_adjusted",
]


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


def _restitution_float(restitution) -> float:
    """The shards' r as the estimators take it: parsed (a ``Fraction`` or a real number, as
    ``restitution.parse_restitution`` returns it), in (0, 1)."""
    if isinstance(restitution, (str, bytes, bool)) or not isinstance(restitution, numbers.Real):
        raise TypeError(
            f"restitution: give r as parsed (restitution.parse_restitution), a Fraction or a "
            f"float, not {restitution!r}"
        )
    r = float(restitution)
    if not 0.0 < r < 1.0:
        raise ValueError(f"restitution: r = {restitution!r} is outside 0 < r < 1")
    return r


def _occupied_fine_bins(shards):
    """The shards' ``return_law_speed_counts`` in the fine bins any shard reached, and those
    bins' edges (the fine under- and overflow bins as the decade beyond each end)."""
    fine = return_law_speed_bins(shards[0].speed_bins)
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


#: Gauss-Legendre points in ln u per fine bin of ``settings.return_law_speed_bins`` (2.3 %
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
    ``settings.return_law_speed_bins``) times M_j averaged over each fine bin with weight
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
    >>> from bouncing_ball.settings import ShardSettings
    >>> from bouncing_ball.tallies import ShardTallies
    >>> from bouncing_ball.estimators import return_law_prediction
    >>> settings = ShardSettings(
    ...     shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
    ...     max_steps=100, speed_bins=LogBins(0.1, 10.0, 1),
    ... )
    >>> arrays = ShardTallies.loop_arrays(settings)
    >>> arrays["return_law_speed_counts"][1 + 100] = 100  # u in [1, 1.023): 0.1 to 10, 100 a decade
    >>> shard = ShardTallies.from_loop(settings, arrays)
    >>> density = lambda u: outgoing_speed_density(u, "1/2")
    >>> prediction = return_law_prediction([shard], 0.5, density)
    >>> print(np.round(prediction, 1), round(float(prediction.sum()), 9))
    [[ 0.4 58.5 41.1  0. ]] 100.0
    """
    from ..flight_time import return_speed_bin_probabilities

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
    >>> from bouncing_ball.estimators import flight_law_prediction
    >>> settings = ShardSettings(
    ...     shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
    ...     max_steps=100,
    ... )
    >>> arrays = ShardTallies.loop_arrays(settings)
    >>> arrays["return_law_speed_counts"][1 + 400] = 100  # u in [1, 1.023): from 1e-4, 100 a decade
    >>> shard = ShardTallies.from_loop(settings, arrays)
    >>> density = lambda u: outgoing_speed_density(u, "1/2")
    >>> print(np.round(flight_law_prediction([shard], density), 1))
    [[ 317.8 2294.7]]
    """
    from ..flight_time import (
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
    >>> from bouncing_ball.estimators import control_variate_rate
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
    >>> from bouncing_ball.estimators import control_variate_adjusted
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
