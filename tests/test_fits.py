"""The fitter on data with known truth: exact recovery without noise, honest intervals with noise."""

import numpy as np
import pytest

from bouncing_ball import fits
from bouncing_ball.histograms import jackknife, outgoing_speed_density

SHARDS = 16
CASES = {
    # side: (r whose theory starts the fit, true log-prefactor and exponents, bin edges, time per shard)
    fits.SMALL_SPEED: (0.25, (np.log(0.47), 1.75), np.geomspace(1e-4, 1e-2, 21), 2.0e5),
    fits.LARGE_SPEED: (0.25, (np.log(0.6), 1.5, 2.0), np.geomspace(0.5, 4.0, 10), 2.0e5),
}


def _bins(edges):
    return edges[:-1], edges[1:]


def synthetic_shards(rng, side, truth, edges, time):
    """Poisson counts per shard and bin, with shard-to-shard fluctuations shared by all bins
    (a common factor and a common tilt), as collision cascades make them."""
    lower, upper = _bins(edges)
    rate = fits.bin_average(fits.FORMS[side], lower, upper, *truth) * 0.5 * (upper**2 - lower**2)
    tilt = np.log(np.sqrt(lower * upper) / np.sqrt(lower[0] * upper[-1]))
    z = rng.standard_normal((SHARDS, 2))
    factor = np.exp(0.05 * z[:, :1] + 0.03 * z[:, 1:] * tilt[None, :])
    counts = rng.poisson(rate[None, :] * time * factor)
    return counts, np.full(SHARDS, time)


@pytest.mark.parametrize("side", list(CASES))
def test_recovers_exact_parameters_without_noise(side):
    r, truth, edges, _ = CASES[side]
    lower, upper = _bins(edges)
    values = fits.bin_average(fits.FORMS[side], lower, upper, *truth)
    fit = fits.fit_asymptotic_form(side, lower, upper, values, 0.01 * values, r, free=True)
    expected = [np.exp(truth[0]), *truth[1:]]
    assert list(fit.parameters.values()) == pytest.approx(expected, rel=1e-7)
    assert fit.chi2 < 1e-10


@pytest.mark.parametrize("side", list(CASES))
def test_intervals_cover_the_truth_as_often_as_they_claim(side):
    r, truth, edges, time = CASES[side]
    lower, upper = _bins(edges)
    rng = np.random.default_rng(20061121)
    names = fits.EXPONENT_NAMES[side]
    within_one, within_95, estimates = {n: 0 for n in names}, {n: 0 for n in names}, {n: [] for n in names}
    trials = 200
    t95 = fits.interval_factor(SHARDS)
    for _ in range(trials):
        counts, times = synthetic_shards(rng, side, truth, edges, time)
        _, errors = jackknife(lambda c, t: outgoing_speed_density(c, t, lower, upper), counts, times)
        fit = fits.fit_shards(side, lower, upper, counts, times, errors, r, free=True)
        for name, true in zip(names, truth[1:]):
            deviation = abs(fit.parameters[name] - true) / fit.errors[name]
            within_one[name] += deviation <= 1.0
            within_95[name] += deviation <= t95
            estimates[name].append(fit.parameters[name])
    one_sigma = 0.667  # P(|t_15| <= 1)
    for name, true in zip(names, truth[1:]):
        # binomial 3-sigma bands around the claimed coverage
        assert abs(within_one[name] / trials - one_sigma) <= 3 * np.sqrt(one_sigma * (1 - one_sigma) / trials), name
        assert abs(within_95[name] / trials - 0.95) <= 3 * np.sqrt(0.95 * 0.05 / trials), name
        spread = np.std(estimates[name])
        assert abs(np.mean(estimates[name]) - true) <= 3 * spread / np.sqrt(trials), name


def test_window_from_range_and_too_few_bins():
    lower, upper = _bins(np.geomspace(1.0, 10.0, 11))
    window = fits.window_from_range(fits.LARGE_SPEED, lower, upper, {"min": 2.0, "max": 8.0})
    assert lower[window][0] >= 2.0 * (1 - 1e-9) and upper[window][-1] <= 8.0 * (1 + 1e-9)
    with pytest.raises(ValueError, match="too few"):
        fits.window_from_range(fits.LARGE_SPEED, lower, upper, {"min": 2.0, "max": 3.0})
