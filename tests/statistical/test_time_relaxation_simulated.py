"""The simulated ball forgets in time at the predicted slowest rate gamma (``time_relaxation``).

A sample path per shard, summed over windows of length 1 / (4 gamma) (``time_windows``: a small
loop driven by the library's step functions), gives the series int x dt and int x^(1/2) dt
per window.  Their principal correlation mu_k (the largest lag-k correlation of a combination of
the two, ``time_windows.principal_correlation``) decays as e^(-gamma k W): the slowest mode's
eigenfunction changes sign once, and x and x^(1/2) project on it (the
second takes out part of the faster modes' share in x, below).  A least-squares line through
ln mu_k over the lags of 1 to 4 relaxation times (k = 4 .. 16) gives the simulated rate, with a
delete-one jackknife error over the independent shards.  The z-score
(gamma_sim - gamma) / error is held to |z| < Z_LIMIT at each r: with 32 shards z follows
Student's t with 31 degrees of freedom, P(|t| > 4.5) < 1e-4, so the family false-alarm
probability of the three comparisons is below 3e-4.  Seeds are fixed, so the outcome is
deterministic.

The estimator's bias: faster parts of the spectrum (the large-speed continuum from
gamma_e = 1.2 - 1.33 gamma) still weigh on the first lags.  Measured at r = 0.75 on 3e8 time
units (32 shards, other seeds): x alone gives gamma_sim / gamma = 1.073 +- 0.020, the pair
(x, x^(1/2)) 1.048 +- 0.022; the pair's ~5 % is about 1.4 errors of this test's runs, within
Z_LIMIT but not negligible (a test several times longer would need the continuum modelled).

Power: the rate is held against two wrong answers, each asserted beyond Z_LIMIT: the bounce
chain's time 1 / (n_c <T>) at every r (32 % above gamma at r = 0.5, 2.6 times it at r = 0.75),
and from r = 0.75 on the large-speed continuum edge gamma_e (what the rate would be were the
root not isolated, 30 - 33 % above gamma there; at r = 0.5, 21 % above, these runs reach
z ~ -3.6 only).
"""

import math

import numpy as np
import pytest
from time_windows import fitted_rate, lag_pair_sums, principal_correlation, window_sums

from bouncing_ball.equilibrium import Equilibrium
from bouncing_ball.estimators import jackknife
from bouncing_ball.restitution import restitution_label
from bouncing_ball.simulation import shard_seed_sequence

SHARDS = 32
SEED = 67
Z_LIMIT = 4.5
CRITERION_C = 3.0  # the default config's c and delta rule
MIN_STEP_DIVISOR = 500
WINDOWS_PER_TIME = 4  # windows per relaxation time
LAGS = np.arange(4, 17)  # 1 to 4 relaxation times
EQUILIBRATION_WINDOWS = 80
EDGE_POWER_RESTITUTION = 0.75  # 20 relaxation times
# the recorded time per shard, in relaxation times
SHARD_RELAXATION_TIMES = {0.5: 3.2e4, 0.75: 3.5e4, 0.9: 2.0e4}


def _rate(r):
    eq = Equilibrium(r)
    window = eq.relaxation_time / WINDOWS_PER_TIME
    count = int(SHARD_RELAXATION_TIMES[r] * WINDOWS_PER_TIME)
    series = []
    for shard in range(SHARDS):
        stream = shard_seed_sequence(SEED, restitution_label(r), shard)
        series.append(
            np.stack(
                window_sums(
                    r, stream, window, count, EQUILIBRATION_WINDOWS, CRITERION_C, MIN_STEP_DIVISOR
                )
            )
        )
    sums = lag_pair_sums(np.stack(series), LAGS[-1])
    rate, error = jackknife(
        lambda total: fitted_rate(principal_correlation(total), LAGS, window), sums
    )
    return {"rate": float(rate), "error": float(error), "equilibrium": eq}


@pytest.fixture(scope="module", params=sorted(SHARD_RELAXATION_TIMES))
def simulated(request):
    return request.param, _rate(request.param)


def _z(simulated_rate, predicted):
    return (simulated_rate["rate"] - predicted) / simulated_rate["error"]


def test_the_simulated_decay_rate_in_time_is_gamma(simulated):
    r, fit = simulated
    eq = fit["equilibrium"]
    z = _z(fit, eq.relaxation_rate)
    print(
        f"r = {r}: gamma_sim = {fit['rate']:.6g} +- {fit['error']:.2g}, "
        f"gamma = {eq.relaxation_rate:.6g}, z = {z:.2f}"
    )
    assert abs(z) < Z_LIMIT, (r, z, fit)


def test_the_comparison_rejects_the_continuum_edge_and_the_chain_time(simulated):
    r, fit = simulated
    eq = fit["equilibrium"]
    if r >= EDGE_POWER_RESTITUTION:  # at r = 1/2 gamma_e is 21 % above gamma: z ~ -3.6 only
        assert _z(fit, eq._time_relaxation.large_speed_edge) < -Z_LIMIT
    assert abs(_z(fit, 1.0 / eq.bounce_chain_time)) > Z_LIMIT
    assert math.isfinite(fit["error"]) and fit["error"] > 0.0
