"""The martingale control-variate estimator of a rate (estimators.control_variate_rate), on
synthetic shards: exact where the control explains everything, the plain estimator where it
explains nothing, and unbiased where an in-sample slope is not."""

from types import SimpleNamespace

import numpy as np
import pytest

from bouncing_ball.estimators import (
    control_variate_adjusted,
    control_variate_rate,
    jackknife,
    moment_controls,
)
from bouncing_ball.tallies import MOMENT_CONTROLS, RATE_CONTROLS, SHARDS_PER_CONTROL


def test_a_control_that_explains_everything_leaves_no_error():
    rng = np.random.default_rng(1)
    times = rng.uniform(1.0, 2.0, 12)
    controls = rng.normal(size=(12, 2)) * np.sqrt(times)[:, None]
    tallies = 0.75 * times + controls @ np.array([-0.4, 2.0])
    value, error, beta = control_variate_rate(tallies, times, controls)
    assert value == pytest.approx(0.75, rel=1e-12)
    assert error == pytest.approx(0.0, abs=1e-12)
    assert beta == pytest.approx([-0.4, 2.0], rel=1e-10)


def test_without_a_usable_control_it_is_the_plain_estimator():
    """A control that is 0 in every shard (e.g. nothing recorded) changes nothing."""
    rng = np.random.default_rng(2)
    times = np.full(10, 3.0)
    tallies = rng.poisson(30.0, size=(10, 4)).astype(float)
    value, error, beta = control_variate_rate(tallies, times, np.zeros((10, 1)))
    plain, plain_error = jackknife(lambda c, t: c / t, tallies, times[:, None])
    assert np.allclose(value, plain) and np.allclose(error, plain_error)
    assert beta.shape == (1, 4) and np.all(beta == 0.0)


def test_histograms_are_corrected_bin_by_bin():
    rng = np.random.default_rng(3)
    noise = rng.normal(size=40)
    tallies = np.column_stack([10.0 + 3.0 * noise, 5.0 - noise + 0.1 * rng.normal(size=40)])
    value, error, beta = control_variate_rate(tallies, np.ones(40), noise)
    assert value.shape == error.shape == (2,) and beta.shape == (1, 2)
    assert beta[0] == pytest.approx([3.0, -1.0], abs=0.05)
    assert error[0] < 1e-12 and error[1] < 0.03 < tallies[:, 1].std() / np.sqrt(40)


def test_cross_fitting_is_unbiased_where_an_in_sample_slope_is_not():
    """tally = 1 + (x^2 - 1) with x of mean 0: x predicts nothing linearly, but a slope fitted
    with shard k picks up x_k^2 x_k and biases the mean by about -2 / shards; the slope
    fitted without shard k does not (its correction has mean exactly 0)."""
    rng = np.random.default_rng(4)
    shards, repeats = 6, 1500
    x = rng.normal(size=(repeats, shards))
    tallies = 1.0 + (x**2 - 1.0)
    times = np.ones(shards)
    cross_fitted = np.array([control_variate_rate(t, times, c)[0] for t, c in zip(tallies, x)])
    in_sample = []
    for t, c in zip(tallies, x):
        slope = np.polyfit(c, t, 1)[0]
        in_sample.append(np.mean(t - slope * c))
    error = np.std(cross_fitted) / np.sqrt(repeats)
    assert abs(cross_fitted.mean() - 1.0) < 4.0 * error
    assert np.mean(in_sample) - 1.0 < -0.15  # about -2 / shards


def test_too_few_shards_for_the_controls_are_refused():
    with pytest.raises(ValueError, match="too few"):
        control_variate_rate(np.ones(4), np.ones(4), np.zeros((4, 2)))


def test_adjusted_tallies_give_the_rate_and_any_function_of_their_sums():
    """control_variate_adjusted: the adjusted tallies over the times are control_variate_rate's
    value; a function of several adjusted sums (a Delta x of int x and int x^2) is exact
    where the controls explain each sum's noise."""
    rng = np.random.default_rng(5)
    n = 16
    times = rng.uniform(1.0, 2.0, n)
    controls = rng.normal(size=(n, 2)) * np.sqrt(times)[:, None]
    int_x = 6.0 * times + controls @ np.array([1.5, -0.5])
    int_x2 = 144.0 * times + controls @ np.array([-20.0, 3.0])
    adjusted_x, beta = control_variate_adjusted(int_x, times, controls)
    assert beta == pytest.approx([1.5, -0.5], rel=1e-10)
    value, _, _ = control_variate_rate(int_x, times, controls)
    assert adjusted_x.sum() / times.sum() == pytest.approx(value, rel=1e-12)
    adjusted_x2, _ = control_variate_adjusted(int_x2, times, controls)
    delta_x, error = jackknife(
        lambda a, b, t: np.sqrt(b / t - (a / t) ** 2), adjusted_x, adjusted_x2, times
    )
    assert delta_x == pytest.approx(np.sqrt(144.0 - 36.0), rel=1e-10)
    assert error == pytest.approx(0.0, abs=1e-9)


def _fake_shards(n):
    rng = np.random.default_rng(n)
    return [SimpleNamespace(**{name: rng.normal() for name in MOMENT_CONTROLS}) for _ in range(n)]


def test_the_moments_use_every_control_the_shards_can_fit():
    """All of MOMENT_CONTROLS from SHARDS_PER_CONTROL shards per control, else RATE_CONTROLS
    from as many per control, else none."""
    enough = SHARDS_PER_CONTROL * len(MOMENT_CONTROLS)
    assert moment_controls(_fake_shards(enough)).shape == (enough, len(MOMENT_CONTROLS))
    fewer = moment_controls(_fake_shards(enough - 1))
    assert fewer.shape == (enough - 1, len(RATE_CONTROLS))
    shards = _fake_shards(SHARDS_PER_CONTROL * len(RATE_CONTROLS))
    assert np.array_equal(
        moment_controls(shards), [[getattr(s, name) for name in RATE_CONTROLS] for s in shards]
    )
    assert moment_controls(_fake_shards(SHARDS_PER_CONTROL * len(RATE_CONTROLS) - 1)) is None


def _z_scores(shards, controls, repeats, rng):
    """z of the corrected rate against the truth over ``repeats`` synthetic runs whose
    tallies are the rate 1 plus the controls' share (heavy-tailed, Student-t) and noise."""
    z = []
    for _ in range(repeats):
        times = np.ones(shards)
        sums = rng.standard_t(5, size=(shards, controls))
        tallies = times + sums @ (0.3 * rng.normal(size=controls)) + 0.2 * rng.normal(size=shards)
        value, error, _ = control_variate_rate(tallies, times, sums)
        z.append((value - 1.0) / error)
    return np.array(z)


def test_the_error_is_honest_with_SHARDS_PER_CONTROL_shards_per_control():
    """With three shards per control the jackknife error holds the slopes' noise: z has a
    spread near 1; with the least the fit allows (p + 3) it is far too
    small, which is why shard_controls asks for SHARDS_PER_CONTROL per control."""
    rng = np.random.default_rng(6)
    controls = len(RATE_CONTROLS)
    honest = _z_scores(SHARDS_PER_CONTROL * controls, controls, 400, rng)
    assert 0.9 < honest.std() < 1.2
    fewest = _z_scores(controls + 3, controls, 400, rng)
    assert fewest.std() > 1.5


@pytest.mark.parametrize("distribution", ["normal", "student_t"])
def test_the_held_slope_jackknife_variance_is_unbiased_at_three_shards_per_control(distribution):
    """The jackknife of the cross-fitted adjusted tallies does not refit the slopes in each
    leave-one-out sample, and needs no correction for it: on synthetic shards where the
    truth is known, the mean of error^2 over many runs is the variance of the estimate
    (ratio 1 within 0.2, about 4 of the ratio's standard errors over 1000 runs), at the
    fewest shards shard_controls allows (p / n = 1/3)."""
    rng = np.random.default_rng(7)
    controls = len(RATE_CONTROLS)
    shards, repeats = SHARDS_PER_CONTROL * controls, 1000
    times = np.ones(shards)
    values, errors = [], []
    for _ in range(repeats):
        if distribution == "normal":
            sums = rng.normal(size=(shards, controls))
        else:
            sums = rng.standard_t(5, size=(shards, controls))
        tallies = times + sums @ (0.3 * rng.normal(size=controls)) + 0.2 * rng.normal(size=shards)
        value, error, _ = control_variate_rate(tallies, times, sums)
        values.append(value)
        errors.append(error)
    variance = np.mean((np.array(values) - 1.0) ** 2)
    assert 0.8 < np.mean(np.square(errors)) / variance < 1.2
