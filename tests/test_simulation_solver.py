"""The simulation against the solver at r = 0.25 and 0.75, where the paper has no exact solution.

CI-sized runs (16 shards per r, ~10 s on 2 cores each); seeds fixed.  The
solver's error (~1e-11) is negligible against the simulation's, so every
comparison is a z-score with the simulation's standard error alone.
"""

from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest
from sign_flip import sign_flip_p_values

from bouncing_ball import solver
from bouncing_ball.bins import LogBins
from bouncing_ball.histograms import outgoing_speed_density, outgoing_speed_histogram, position_moments_summary
from bouncing_ball.restitution import restitution_label
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

SHARDS = 16
SHARD_TIME = {0.25: 3.0e5, 0.75: 3.0e6}
SEED = 20061122


def _shard(arguments):
    r, shard = arguments
    return simulate_shard(
        restitution=r,
        seed_sequence=shard_seed_sequence(SEED, restitution_label(r), shard),
        recorded_time=SHARD_TIME[r],
        equilibration_time=200.0,
        criterion_c=5.0,
        min_step_divisor=500.0,
        max_steps=10**12,
        speed_bins=LogBins(1e-4, 1e2, 10),
        position_bins=LogBins(1e-3, 1e3, 5),
    )


@pytest.fixture(scope="module")
def shards():
    jobs = [(r, k) for r in SHARD_TIME for k in range(SHARDS)]
    with ProcessPoolExecutor(2) as pool:
        results = list(pool.map(_shard, jobs))
    return {r: [s for (rr, _), s in zip(jobs, results) if rr == r] for r in SHARD_TIME}


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
    table = outgoing_speed_histogram(shards[r])
    usable = ((table["count"] >= 100) & np.isfinite(table.v_hi) & (table.v_lo > 0)).to_numpy()
    lower, upper = table.v_lo.to_numpy()[usable], table.v_hi.to_numpy()[usable]
    per_shard = np.stack(
        [outgoing_speed_density(s.speed_counts[usable], s.time, lower, upper) for s in shards[r]]
    )
    predicted = solver.outgoing_speed_bin_average(solutions[r], lower, upper)
    assert usable.sum() >= 30, "too few populated bins for a meaningful chi^2"
    chi2_per_dof, p_chi2, p_worst = sign_flip_p_values(per_shard - predicted)
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/dof = {chi2_per_dof:.3f} (p = {p_chi2:.4f}), worst bin p = {p_worst:.4f}"
    )


@pytest.mark.parametrize("r", list(SHARD_TIME))
def test_detects_a_one_percent_error(shards, solutions, r):
    """The comparison has power: the solver's P(0,v) scaled by 1.01 is rejected."""
    table = outgoing_speed_histogram(shards[r])
    usable = ((table["count"] >= 100) & np.isfinite(table.v_hi) & (table.v_lo > 0)).to_numpy()
    lower, upper = table.v_lo.to_numpy()[usable], table.v_hi.to_numpy()[usable]
    per_shard = np.stack(
        [outgoing_speed_density(s.speed_counts[usable], s.time, lower, upper) for s in shards[r]]
    )
    wrong = 1.01 * solver.outgoing_speed_bin_average(solutions[r], lower, upper)
    _, p_chi2, _ = sign_flip_p_values(per_shard - wrong)
    assert p_chi2 < 1e-3
