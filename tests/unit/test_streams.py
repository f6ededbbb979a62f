"""Random streams: one per (r, shard), reproducible, independent of job order and of how
shards are grouped into jobs."""

import numpy as np
from default_settings import DEFAULT_SETTINGS

from bouncing_ball.estimators import position_moments_summary
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
from bouncing_ball.tallies import tallies_to_frame
from bouncing_ball.workflow.batches import batch_to_frame, simulate_batch
from bouncing_ball.workflow.io import write_table
from bouncing_ball.workflow.shards import read_shards

SETTINGS = DEFAULT_SETTINGS.replace(shard_time=500.0, equilibration_time=10.0, criterion_c=5.0)


def _run(label, shard, seed=11):
    return simulate_shard(float(label), shard_seed_sequence(seed, label, shard), SETTINGS)


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


def _batch_files(folder, batches, seed=11):
    """Batch files of r = 1/2 as rule simulate_shards writes them, one per list of shards."""
    paths = []
    for shards in batches:
        path = folder / f"shards{shards[0]}-{shards[-1]}.parquet"
        batch = dict(simulate_batch(0.5, seed, "0.5", shards, SETTINGS))
        provenance = {"r": "1/2", "r_label": "0.5", "seed": seed, "code": "test"}
        provenance.update(first_shard=shards[0], last_shard=shards[-1], **SETTINGS.as_mapping())
        write_table(batch_to_frame(batch), path, provenance)
        paths.append(path)
    return paths


def test_a_shard_has_the_same_tallies_whatever_batch_it_is_in(tmp_path):
    """Shard k draws from its own stream: one job of shards 0-2 or jobs of 0 and of 1-2 give
    every shard, and so every merged table, bit for bit the same."""
    (tmp_path / "one").mkdir(), (tmp_path / "two").mkdir()
    one, _ = read_shards(_batch_files(tmp_path / "one", [[0, 1, 2]]), "0.5")
    two, provenances = read_shards(_batch_files(tmp_path / "two", [[0], [1, 2]]), "0.5")
    assert [p["shard"] for p in provenances] == [0, 1, 2]
    for k, (ours, theirs) in enumerate(zip(one, two, strict=True)):
        assert tallies_to_frame(ours).equals(tallies_to_frame(theirs))
        assert tallies_to_frame(ours).equals(tallies_to_frame(_run("0.5", k)))  # as if alone
    assert position_moments_summary(one, 0.5).equals(position_moments_summary(two, 0.5))
