"""The autocorrelation of the log outgoing speed over bounces, and the bounce chain's decay
rate fitted to it."""

import math

import numpy as np
import pandas as pd

from ..tallies import (
    BOUNCE_LAGS,
    ShardTallies,
    bounce_lag_pair_sums,
)
from .jackknife import jackknife

__all__ = [
    "RESOLVED_CORRELATION",
    "bounce_autocorrelation",
    "bounce_chain_decay",
]

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
