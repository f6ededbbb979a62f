"""The fitter's intervals on synthetic shards with known truth: honest 95% intervals, a joint test
of the exponents that rejects the truth 5% of the time, unbiased estimates (600 trials per side)."""

import numpy as np
import pytest
from fit_support import CASES, SHARDS, _bins, synthetic_shards

from bouncing_ball import fits
from bouncing_ball.estimators import jackknife, outgoing_speed_density


@pytest.mark.parametrize("side", list(CASES))
def test_intervals_cover_the_truth_as_often_as_they_claim(side):
    """The 95% intervals (jackknife errors over 16 shards, Student t) cover the truth 95% of
    the time, the joint test of the exponents rejects the truth 5% of the time at p < 0.05,
    and the estimates are unbiased; on shards with a shard-wide factor and tilt."""
    r, truth, edges, time = CASES[side]
    lower, upper = _bins(edges)
    rng = np.random.default_rng(20061121)
    names = fits.EXPONENT_NAMES[side]
    within_95, estimates = dict.fromkeys(names, 0), {n: [] for n in names}
    joint_rejected = 0
    trials = 600
    t95 = fits.interval_factor(SHARDS)
    for _ in range(trials):
        counts, times = synthetic_shards(rng, side, truth, edges, time)
        _, errors = jackknife(
            lambda c, t: outgoing_speed_density(c, t, lower, upper), counts, times
        )
        fit = fits.fit_shards(side, lower, upper, counts, times, errors, r, free=True)
        # the truth is the theory of r = 0.25, which fit_shards tests jointly
        joint_rejected += fit.joint_p_value < 0.05
        for name, true in zip(names, truth[1:]):
            within_95[name] += abs(fit.parameters[name] - true) <= t95 * fit.errors[name]
            estimates[name].append(fit.parameters[name])
    for name, true in zip(names, truth[1:]):
        # binomial 3-sigma band around the claimed coverage (600 trials: +-0.027)
        assert abs(within_95[name] / trials - 0.95) <= 3 * np.sqrt(0.95 * 0.05 / trials), name
        spread = np.std(estimates[name])
        assert abs(np.mean(estimates[name]) - true) <= 3 * spread / np.sqrt(trials), name
    assert abs(joint_rejected / trials - 0.05) <= 3 * np.sqrt(0.05 * 0.95 / trials)
