"""A shard's work is bounded by its step budget; its tallies add up."""

import pytest
from default_settings import DEFAULT_SETTINGS

from bouncing_ball.simulation import shard_seed_sequence, simulate_shard


def _run(recorded_time, equilibration_time, max_steps, r=0.5):
    settings = DEFAULT_SETTINGS.replace(
        shard_time=recorded_time,
        equilibration_time=equilibration_time,
        criterion_c=5.0,
        max_steps=max_steps,
    )
    return simulate_shard(r, shard_seed_sequence(2, str(r), 0), settings)


def test_budget_stops_a_shard_and_says_so():
    full = _run(2000.0, 10.0, 10**9)
    assert full.budget_exhausted == 0 and full.time == pytest.approx(2000.0)
    cut = _run(2000.0, 10.0, full.steps // 2)
    assert cut.budget_exhausted == 1
    assert 0.0 < cut.time < 2000.0
    assert cut.steps < full.steps // 2  # the budget counts equilibration steps too


def test_position_tallies_cover_the_recorded_time():
    shard = _run(5000.0, 10.0, 10**9, r=0.75)
    # the bridge correction moves time between bins and adds none (a bin's total may dip
    # below 0 where the assignment gave it little; in expectation every bin is >= 0)
    assert shard.position_time.sum() == pytest.approx(shard.time, rel=1e-12)
    visited = shard.position_time > 0.05 * shard.time
    assert visited.sum() >= 3 and (shard.position_v2_time[visited] > 0.0).all()
    assert shard.speed_counts.sum() == shard.collisions
