"""The simulation against the solver at r = 0.25 and 0.75, where the paper has no exact solution.

CI-sized runs (16 shards per r, ~10 s on 2 cores each); seeds fixed.  The
solver's error (~1e-11) is negligible against the simulation's, so every
comparison is a z-score with the simulation's standard error alone.
"""

import numpy as np
import pytest
from shard_statistics import outgoing_speed_bins, sign_flip_p_values, simulate_shards

from bouncing_ball import fits, solver
from bouncing_ball.bins import outgoing_speed_bin_average
from bouncing_ball.histograms import outgoing_speed_histogram, position_moments_summary

SHARDS = 16
SHARD_TIME = {0.25: 3.0e5, 0.75: 3.0e6}
SEED = 20061122


@pytest.fixture(scope="module")
def shards():
    return simulate_shards(SHARD_TIME, SHARDS, SEED)


@pytest.fixture(scope="module")
def solutions():
    return {r: solver.solve_outgoing_speed_density(r) for r in SHARD_TIME}


@pytest.mark.parametrize("r", list(SHARD_TIME))
@pytest.mark.parametrize("quantity", ["mean_x", "delta_x", "collision_rate"])
def test_time_averages_agree(shards, solutions, r, quantity):
    summary = position_moments_summary(shards[r], r).iloc[0]
    value, error = summary[quantity], summary[f"{quantity}_err"]
    expected = solver.time_averages(solutions[r])[quantity]
    assert error / expected <= 0.015, "run too short for a sharp test"
    z = (value - expected) / error
    assert abs(z) < 3.0, f"{quantity} = {value} +- {error}, solver {expected}, z = {z:.2f}"


@pytest.mark.parametrize("r", list(SHARD_TIME))
def test_outgoing_speed_density_agrees(shards, solutions, r):
    """P(0, v) in every bin with at least 100 collisions: chi^2 per bin and the worst bin
    against their sign-flip null distributions, at the 1e-3 level."""
    lower, upper, per_shard = outgoing_speed_bins(shards[r])
    predicted = outgoing_speed_bin_average(solutions[r].outgoing_speed_density, lower, upper)
    assert len(lower) >= 30, "too few populated bins for a meaningful chi^2"
    chi2_per_dof, p_chi2, p_worst = sign_flip_p_values(per_shard - predicted)
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/dof = {chi2_per_dof:.3f} (p = {p_chi2:.4f}), worst bin p = {p_worst:.4f}"
    )


@pytest.mark.parametrize("r", list(SHARD_TIME))
def test_detects_a_one_percent_error(shards, solutions, r):
    """The comparison has power: the solver's P(0,v) scaled by 1.01 is rejected."""
    lower, upper, per_shard = outgoing_speed_bins(shards[r])
    wrong = 1.01 * outgoing_speed_bin_average(solutions[r].outgoing_speed_density, lower, upper)
    _, p_chi2, _ = sign_flip_p_values(per_shard - wrong)
    assert p_chi2 < 1e-3


@pytest.mark.parametrize("r", list(SHARD_TIME))
def test_free_exponent_fits_agree_with_theory(shards, solutions, r):
    """beta, and m with q together (they are strongly anticorrelated), fitted with free
    exponents in the default windows: the theory's eqs. (asym2)-(asym6) are not rejected
    at the 1e-3 level (Hotelling's T^2 on the jackknife covariance over shards)."""
    # the fit job's own choice of bins (fits.select_fit_bins), from the solver's tabulated curve
    table = outgoing_speed_histogram(shards[r])
    times = np.array([s.time for s in shards[r]])
    grid = np.geomspace(1e-4, 50.0, 401)
    speeds, density = fits.usable_curve(grid, solutions[r].outgoing_speed_density(grid))
    chosen = fits.select_fit_bins(table, speeds, density, times.sum(), minimum_count=50)
    lower, upper, reference = chosen.lower, chosen.upper, chosen.reference
    counts = np.stack([s.speed_counts[chosen.rows] for s in shards[r]])
    errors = table.p0v_err.to_numpy()[chosen.rows]
    windows = {fits.SMALL_SPEED: "auto", fits.LARGE_SPEED: "auto"}
    table, problems = fits.asymptotic_fits(
        lower, upper, counts, times, errors, reference, r, windows
    )
    assert problems == []
    free = table[
        (table.source == "simulation")
        & (table.fit == "free_exponents")
        & (table.parameter != "prefactor")
    ]
    assert sorted(free.parameter) == ["beta", "m", "q"]
    for _, rows in free.groupby("window"):
        assert rows.joint_p_value.iloc[0] > 1e-3, rows.to_string()
