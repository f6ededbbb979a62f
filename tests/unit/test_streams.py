"""Random streams: one per (r, shard), reproducible, independent of job order."""

import numpy as np

from bouncing_ball.bins import LogBins
from bouncing_ball.settings import ShardSettings
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
from bouncing_ball.tallies import tallies_to_frame


def _run(label, shard, seed=11):
    settings = ShardSettings(
        shard_time=500.0,
        equilibration_time=10.0,
        criterion_c=5.0,
        min_step_divisor=500.0,
        max_steps=10**9,
        speed_bins=LogBins(1e-4, 1e2, 10),
        position_bins=LogBins(1e-3, 1e3, 5),
    )
    return simulate_shard(float(label), shard_seed_sequence(seed, label, shard), settings)


def test_same_seed_gives_an_identical_shard():
    first, second = _run("0.5", 3), _run("0.5", 3)
    assert tallies_to_frame(first).equals(tallies_to_frame(second))


def test_different_shards_and_r_get_different_streams():
    draws = {
        key: np.random.Generator(np.random.PCG64(shard_seed_sequence(11, *key))).random(4)
        for key in [("0.5", 0), ("0.5", 1), ("0.333333", 0), ("0.333333", 1)]
    }
    values = [tuple(v) for v in draws.values()]
    assert len(set(values)) == len(values)
    assert not tallies_to_frame(_run("0.5", 0)).equals(tallies_to_frame(_run("0.5", 1)))


def test_other_seed_other_stream():
    assert not tallies_to_frame(_run("0.5", 0, seed=1)).equals(
        tallies_to_frame(_run("0.5", 0, seed=2))
    )
