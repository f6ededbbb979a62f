"""A sample path in time, summed over windows: the ball's time series, which a shard does not
return (its tallies are sums over the whole recording).

A small compiled loop drives the library's own step functions the way the shard loop does
(``simulation.loop``): the step root(x, v)^2 + delta of eq. (criterion) (``free_flight.
criterion_root`` with its predicted start), the exact free-flight step of eqs. (xstep), (vstep)
(``free_flight.free_flight_step``, normals from ``pcg64.standard_normal``), a collision where
the bridge mean path first reaches 0 (``hermite_cubic``, ``first_crossing_time``, the impact
speed its slope there), v_out = r v_in (eq. (restitution)), delta reset to (v_out / divisor)^2
/ 2.  A step is cut at the end of a window (the free-flight step is exact for any dt, as at the
end of a shard), so each step lies in one window.  Each window of length ``window`` adds up
int x dt (``whole_step_integrals``, ``mean_path_integrals``: exact in expectation given the
step's ends) and int x^(1/2) dt (the trapezoidal rule on each step's ends, x = 0 at a
collision: a functional of the path, so its correlations in time decay at the process's
rates, which is all the test asks of it).
"""

import math

import numpy as np

from bouncing_ball.free_flight import (
    criterion_root,
    cubic_slope,
    first_crossing_time,
    free_flight_step,
    hermite_cubic,
    mean_path_integrals,
    predicted_start,
    root_predictor,
    whole_step_integrals,
)
from bouncing_ball.jit import fma, njit
from bouncing_ball.pcg64 import standard_normal, stream_words


@njit(cache=True)
def _window_sums(stream, restitution, c, min_step_divisor, skipped, window, count):
    high, low, inc_high, inc_low = stream
    int_x = np.zeros(count)
    int_root = np.zeros(count)
    x = 1.0
    v = 0.0
    root, slope_at_root = criterion_root(x, v, c, 0.0)
    min_root_2delta = 1.0 / min_step_divisor
    delta = 0.5 * min_root_2delta * min_root_2delta
    for n in range(-skipped, count):
        t = 0.0
        while t < window:
            dt = fma(root, root, delta)
            if t + dt > window:
                dt = window - t
            predictor = root_predictor(root, slope_at_root, x, v)
            high, low, normal_r = standard_normal(high, low, inc_high, inc_low)
            high, low, normal_s = standard_normal(high, low, inc_high, inc_low)
            x1, v1 = free_flight_step(x, v, dt, normal_r, normal_s)
            x_start = x
            if x1 < 0.0:
                a0, a1, a2, a3 = hermite_cubic(x, v, x1, v1, dt)
                tau = first_crossing_time(a0, a1, a2, a3, dt, x1)
                ix, _ = mean_path_integrals(a0, a1, a2, a3, dt, tau)
                v = restitution * abs(cubic_slope(a1, a2, a3, tau))
                x = 0.0
                root_2delta = v * min_root_2delta
                delta = 0.5 * root_2delta * root_2delta
                root, slope_at_root = criterion_root(x, v, c, 0.0)
            else:
                tau = dt
                ix, _ = whole_step_integrals(x, v, x1, v1, dt)
                x = x1
                v = v1
                root, slope_at_root = criterion_root(
                    x, v, c, predicted_start(predictor, root, x, v)
                )
            if n >= 0:
                int_root[n] += 0.5 * tau * (math.sqrt(x_start) + math.sqrt(x))
                int_x[n] += ix
            t += tau
    return int_x, int_root


def window_sums(restitution, seed_sequence, window, count, skipped, criterion_c, divisor):
    """(int x dt, int x^(1/2) dt) over ``count`` consecutive windows of length ``window`` after
    ``skipped`` windows of equilibration, from rest at x = 1; one stream (a SeedSequence)."""
    generator = np.random.Generator(np.random.PCG64(seed_sequence))
    return _window_sums(
        stream_words(generator),
        float(restitution),
        float(criterion_c),
        float(divisor),
        int(skipped),
        float(window),
        int(count),
    )


def lag_pair_sums(series, lags):
    """The pair sums of each shard's window series f_a (shape (shards, m, n)) at lags
    k = 0 .. lags: count, sum f_a(n), sum f_b(n + k), sum f_a(n) f_b(n + k); shape
    (shards, lags + 1, 1 + 2 m + m^2), for ``principal_correlation`` of sums over shards."""
    series = np.asarray(series, dtype=float)
    shards, m, n = series.shape
    sums = np.empty((shards, lags + 1, 1 + 2 * m + m * m))
    for k in range(lags + 1):
        lead, trail = series[:, :, : n - k], series[:, :, k:]
        sums[:, k, 0] = n - k
        sums[:, k, 1 : 1 + m] = lead.sum(axis=2)
        sums[:, k, 1 + m : 1 + 2 * m] = trail.sum(axis=2)
        sums[:, k, 1 + 2 * m :] = np.einsum("san,sbn->sab", lead, trail).reshape(shards, -1)
    return sums


def principal_correlation(sums):
    """mu_k, k = 0 .. lags: the largest lag-k correlation of a combination of the series, the
    largest eigenvalue of S(k) x = mu C(0) x (C(k) the lag-k covariance matrix, each mean
    over the pairs k apart, S(k) its symmetric part), from pair sums over shards
    (``lag_pair_sums`` summed over axis 0; vectorised over leading axes)."""
    m = int(round(math.sqrt(sums.shape[-1]))) - 1
    pairs = sums[..., :1]
    lead = sums[..., 1 : 1 + m] / pairs
    trail = sums[..., 1 + m : 1 + 2 * m] / pairs
    products = sums[..., 1 + 2 * m :].reshape(*sums.shape[:-1], m, m) / pairs[..., None]
    covariance = products - lead[..., :, None] * trail[..., None, :]
    symmetric = 0.5 * (covariance + np.swapaxes(covariance, -1, -2))
    inverse = np.linalg.inv(np.linalg.cholesky(symmetric[..., :1, :, :]))
    whitened = inverse @ symmetric @ np.swapaxes(inverse, -1, -2)
    return np.linalg.eigvalsh(whitened)[..., -1]


def fitted_rate(correlation, lags, window):
    """-slope / window of the least-squares line through (k, ln mu_k) over ``lags`` (the
    last axis of ``correlation`` indexed by lag)."""
    log_mu = np.log(correlation[..., lags])
    centred = lags - lags.mean()
    slope = (log_mu * centred).sum(axis=-1) / (centred**2).sum()
    return -slope / window
