"""The fitter on data with known truth: exact recovery without noise, and its refusals (the
coverage of its intervals with noise is in tests/statistical/test_fit_coverage.py)."""

import numpy as np
import pandas as pd
import pytest
from fit_support import CASES, _bins, synthetic_shards

from bouncing_ball import fits
from bouncing_ball.bins import outgoing_speed_bin_average
from bouncing_ball.estimators import jackknife, outgoing_speed_density


@pytest.mark.parametrize("side", list(CASES))
def test_recovers_exact_parameters_without_noise(side):
    r, truth, edges, _ = CASES[side]
    lower, upper = _bins(edges)
    values = fits.bin_average(fits.FORMS[side], lower, upper, *truth)
    fit = fits.fit_asymptotic_form(side, lower, upper, values, 0.01 * values, r, free=True)
    expected = [np.exp(truth[0]), *truth[1:]]
    assert list(fit.parameters.values()) == pytest.approx(expected, rel=1e-7)
    assert fit.chi2 < 1e-10


def test_window_from_range_and_too_few_bins():
    lower, upper = _bins(np.geomspace(1.0, 10.0, 11))
    window = fits.window_from_range(fits.LARGE_SPEED, lower, upper, {"min": 2.0, "max": 8.0})
    assert lower[window][0] >= 2.0 * (1 - 1e-9) and upper[window][-1] <= 8.0 * (1 + 1e-9)
    with pytest.raises(ValueError, match="too few"):
        fits.window_from_range(fits.LARGE_SPEED, lower, upper, {"min": 2.0, "max": 3.0})


def test_bin_averages_of_a_curve_match_the_solver():
    from bouncing_ball import solver

    solution = solver.solve_outgoing_speed_density(0.25)
    speeds = np.geomspace(1e-4, 50.0, 401)
    lower, upper = _bins(np.geomspace(1e-4, 10**1.6, 57))
    from_curve = fits.bin_averages_of_curve(
        speeds, solution.outgoing_speed_density(speeds), lower, upper
    )
    np.testing.assert_allclose(
        from_curve,
        outgoing_speed_bin_average(solution.outgoing_speed_density, lower, upper),
        rtol=1e-6,
    )
    with pytest.raises(ValueError, match="beyond the curve"):
        fits.bin_averages_of_curve(speeds, solution.outgoing_speed_density(speeds), [40.0], [60.0])


def test_a_side_without_a_window_gives_nan_rows_and_says_why():
    r, truth, edges, time = CASES[fits.SMALL_SPEED]
    lower, upper = _bins(edges)
    counts, times = synthetic_shards(np.random.default_rng(1), fits.SMALL_SPEED, truth, edges, time)
    _, errors = jackknife(lambda c, t: outgoing_speed_density(c, t, lower, upper), counts, times)
    reference = fits.bin_average(fits.small_speed_form, lower, upper, *truth)
    windows = {
        fits.SMALL_SPEED: "auto",
        fits.LARGE_SPEED: {"min": 1.0, "max": 2.0},
    }  # no bins there
    table, problems = fits.asymptotic_fits(
        lower, upper, counts, times, errors, reference, r, windows
    )
    assert len(problems) == 1 and "large_speed window" in problems[0]
    assert table[table.window == fits.LARGE_SPEED].value.isna().all()
    assert table[table.window == fits.SMALL_SPEED].value.notna().all()


def test_one_shard_is_refused():
    r, truth, edges, time = CASES[fits.SMALL_SPEED]
    lower, upper = _bins(edges)
    counts, times = synthetic_shards(np.random.default_rng(2), fits.SMALL_SPEED, truth, edges, time)
    with pytest.raises(ValueError, match="at least 2"):
        fits.fit_shards(
            fits.SMALL_SPEED, lower, upper, counts[:1], times[:1], np.ones(len(lower)), r, True
        )


def test_bins_without_a_jackknife_error_are_weighted_by_their_poisson_error():
    reference = np.array([2.0, 1.0, 0.5, 0.25])
    expected = np.array([400.0, 100.0, 25.0, 16.0])
    errors = fits.fit_errors([0.1, 0.0, np.nan, 0.07], reference, expected)
    np.testing.assert_allclose(errors, [0.1, 0.1, 0.1, 0.07])
    assert np.all(errors > 0)


def test_fit_bins_are_chosen_by_the_collisions_they_should_hold_not_by_their_counts():
    """fits.select_fit_bins: finite bins inside the curve, expected count >= minimum_count;
    a bin's own count does not matter, and populated bins past the curve are counted."""
    edges = np.array([1e-3, 1e-2, 1e-1, 1.0, 10.0])
    table = pd.DataFrame(
        {
            "v_lo": np.concatenate([[0.0], edges]),
            "v_hi": np.concatenate([edges, [np.inf]]),
            "count": [5, 0, 9, 0, 3, 1],  # the underflow, four finite bins, the overflow
        }
    )
    speeds = np.geomspace(1e-3, 5.0, 200)  # the curve ends inside the last finite bin
    density = np.exp(-speeds)
    total_time = 1.0e3
    chosen = fits.select_fit_bins(table, speeds, density, total_time, minimum_count=10)
    # should hold: [1e-3, 1e-2) 0.05 collisions (out), [1e-2, 1e-1) about 5 (out, though it
    # holds 9), [1e-1, 1) about 300 (in, though it holds none)
    np.testing.assert_array_equal(chosen.rows, [3])
    np.testing.assert_allclose(chosen.lower, [0.1]) and np.testing.assert_allclose(
        chosen.upper, [1.0]
    )
    expected = fits.expected_collisions(chosen.reference, chosen.lower, chosen.upper, total_time)
    np.testing.assert_allclose(chosen.expected, expected)
    assert np.all(chosen.expected >= 10)
    assert chosen.beyond == 1  # [1, 10) reaches past v = 5 and holds 3 collisions
    exact = outgoing_speed_bin_average(lambda v: np.exp(-v), chosen.lower, chosen.upper)
    np.testing.assert_allclose(chosen.reference, exact, rtol=1e-6)


def _no_optimum(*args, **kwargs):
    raise RuntimeError("Optimal parameters not found: maxfev = 20000")


@pytest.mark.parametrize("window", ["auto", {"min": 1e-4, "max": 1e-2}])
def test_a_free_fit_without_optimum_gives_nan_rows_and_says_why(monkeypatch, window):
    """At r = 0.999 curve_fit gave up (maxfev) inside asymptotic_window and the fit job
    crashed; the free-exponent rows are NaN instead, with the reason, and the rest stands."""
    r, truth, edges, time = CASES[fits.SMALL_SPEED]
    lower, upper = _bins(edges)
    counts, times = synthetic_shards(np.random.default_rng(1), fits.SMALL_SPEED, truth, edges, time)
    _, errors = jackknife(lambda c, t: outgoing_speed_density(c, t, lower, upper), counts, times)
    reference = fits.bin_average(fits.small_speed_form, lower, upper, *truth)
    monkeypatch.setattr(fits.optimize, "curve_fit", _no_optimum)
    windows = {fits.SMALL_SPEED: window, fits.LARGE_SPEED: {"min": 1.0, "max": 2.0}}
    table, problems = fits.asymptotic_fits(
        lower, upper, counts, times, errors, reference, r, windows
    )
    small = table[table.window == fits.SMALL_SPEED]
    assert any(
        "small_speed fit of free exponents" in p and "finds no optimum" in p for p in problems
    )
    assert small[small.fit == "free_exponents"].value.isna().all()
    if window == "auto":  # no window can be chosen without a free fit
        assert small.value.isna().all()
    else:  # the theory's exponents are fitted as before
        fixed = small[small.fit == "fixed_exponents"]
        assert fixed.value.notna().all() and (fixed.v_min == lower[0]).all()
    with pytest.raises(fits.FitError, match=r"small_speed fit .* finds no optimum"):
        fits.fit_asymptotic_form(fits.SMALL_SPEED, lower, upper, reference, errors, r, True)
