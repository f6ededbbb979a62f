"""The delete-one jackknife over shards, and the shards' deviations from their mean."""

import numpy as np

__all__ = [
    "jackknife",
    "deviations_from_mean",
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

    >>> from bouncing_ball.estimators import jackknife
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
    >>> from bouncing_ball.estimators import deviations_from_mean
    >>> values = np.full(3, 0.8132702392002724)
    >>> print(np.std(values) > 0, np.abs(deviations_from_mean(values)).max())
    True 0.0
    """
    values = np.asarray(values, dtype=float)
    if values.ndim == 0 or len(values) == 0:
        raise ValueError(f"values: need at least one value, got shape {values.shape}")
    shifted = values - values[0]
    return shifted - shifted.mean(axis=0)
