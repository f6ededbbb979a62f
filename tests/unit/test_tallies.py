"""Merging shards is a sum; shards survive a round trip through Parquet."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bouncing_ball.bins import LogBins
from bouncing_ball.histograms import jackknife, outgoing_speed_histogram
from bouncing_ball.io import UnreadableFileError, read_table, write_table
from bouncing_ball.shards import read_shards
from bouncing_ball.tallies import (
    ShardTallies,
    merge_shards,
    tallies_from_frame,
    tallies_to_frame,
)

SPEED_BINS = LogBins(1e-2, 1e1, 2)
POSITION_BINS = LogBins(1e-1, 1e2, 1)


@st.composite
def shard_tallies(draw):
    nv, nx = SPEED_BINS.n + 2, POSITION_BINS.n + 2
    counts = st.integers(0, 10**6)
    times = st.floats(0.0, 1e6, allow_nan=False)
    return ShardTallies(
        speed_bins=SPEED_BINS,
        position_bins=POSITION_BINS,
        speed_counts=np.array(draw(st.lists(counts, min_size=nv, max_size=nv)), dtype=np.int64),
        position_time=np.array(draw(st.lists(times, min_size=nx, max_size=nx))),
        position_v2_time=np.array(draw(st.lists(times, min_size=nx, max_size=nx))),
        time=draw(st.floats(1.0, 1e6)),
        collisions=draw(counts),
        steps=draw(counts),
        int_x=draw(times),
        int_x2=draw(times),
        budget_exhausted=draw(st.integers(0, 1)),
    )


@settings(max_examples=50, deadline=None)
@given(st.lists(shard_tallies(), min_size=1, max_size=6), st.randoms())
def test_merge_is_an_order_independent_sum(shards, random):
    merged = merge_shards(shards)
    shuffled = list(shards)
    random.shuffle(shuffled)
    again = merge_shards(shuffled)
    # integer tallies are conserved exactly
    assert np.array_equal(merged.speed_counts, sum(s.speed_counts for s in shards))
    assert np.array_equal(merged.speed_counts, again.speed_counts)
    assert merged.collisions == sum(s.collisions for s in shards) == again.collisions
    assert merged.steps == sum(s.steps for s in shards)
    assert merged.budget_exhausted == sum(s.budget_exhausted for s in shards)
    # floating-point sums agree to rounding, in any order
    np.testing.assert_allclose(merged.position_time, again.position_time, rtol=1e-12)
    assert merged.time == pytest.approx(sum(s.time for s in shards), rel=1e-12)
    assert merged.int_x2 == pytest.approx(again.int_x2, rel=1e-12)


@settings(max_examples=20, deadline=None)
@given(shard_tallies())
def test_frame_round_trip(shard):
    back = tallies_from_frame(tallies_to_frame(shard), SPEED_BINS, POSITION_BINS)
    assert np.array_equal(back.speed_counts, shard.speed_counts)
    assert np.array_equal(back.position_time, shard.position_time)
    assert (back.time, back.collisions, back.int_x) == (shard.time, shard.collisions, shard.int_x)


def test_parquet_round_trip_keeps_provenance(tmp_path):
    shard = ShardTallies(
        SPEED_BINS,
        POSITION_BINS,
        np.arange(SPEED_BINS.n + 2),
        np.ones(POSITION_BINS.n + 2),
        np.ones(POSITION_BINS.n + 2),
        10.0,
        5,
        50,
        1.0,
        2.0,
        0,
    )
    path = tmp_path / "shard0.parquet"
    write_table(tallies_to_frame(shard), path, {"r": "1/3", "seed": 7})
    frame, provenance = read_table(path)
    assert provenance["r"] == "1/3" and provenance["seed"] == 7 and "package_version" in provenance
    assert np.array_equal(
        tallies_from_frame(frame, SPEED_BINS, POSITION_BINS).speed_counts, shard.speed_counts
    )
    assert [p.name for p in tmp_path.iterdir()] == ["shard0.parquet"]  # no temporary left


def _empty_shard():
    """A shard that recorded one time unit and nothing else."""
    return ShardTallies(
        SPEED_BINS,
        POSITION_BINS,
        np.zeros(SPEED_BINS.n + 2, dtype=np.int64),
        np.zeros(POSITION_BINS.n + 2),
        np.zeros(POSITION_BINS.n + 2),
        1.0,
        0,
        0,
        0.0,
        0.0,
        0,
    )


def test_shards_on_other_bins_are_refused():
    shard = _empty_shard()
    with pytest.raises(ValueError, match="not on the configured bins"):
        tallies_from_frame(tallies_to_frame(shard), LogBins(1e-2, 1e1, 3), POSITION_BINS)


def test_jackknife_of_a_mean_is_the_standard_error():
    rng = np.random.default_rng(3)
    samples = rng.normal(size=12)
    value, error = jackknife(lambda total, count: total / count, samples, np.ones(12))
    assert value == pytest.approx(samples.mean())
    assert error == pytest.approx(samples.std(ddof=1) / np.sqrt(12))


def test_outgoing_speed_density_counts_rate_over_bin():
    # one shard, 10 collisions in [1, 10) over time 2: p0v = 10 / (2 * (100 - 1) / 2)
    bins = LogBins(1.0, 10.0, 1)
    shard = ShardTallies(
        bins,
        POSITION_BINS,
        np.array([0, 10, 0]),
        np.zeros(POSITION_BINS.n + 2),
        np.zeros(POSITION_BINS.n + 2),
        2.0,
        10,
        100,
        0.0,
        0.0,
        0,
    )
    table = outgoing_speed_histogram([shard])
    assert table.p0v.iloc[1] == pytest.approx(10.0 / 99.0)
    assert table["count"].sum() == 10


def test_truncated_file_gives_an_error_that_names_it(tmp_path):
    from bouncing_ball.io import UnreadableFileError

    path = tmp_path / "shard3.parquet"
    write_table(
        tallies_to_frame(_empty_shard()),
        path,
        {},
    )
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(UnreadableFileError, match="shard3.parquet"):
        read_table(path)


def test_the_compiled_loop_fills_its_scalars_in_the_order_of_SCALARS():
    from bouncing_ball import simulation
    from bouncing_ball.tallies import SCALARS

    indices = (
        simulation._TIME,
        simulation._COLLISIONS,
        simulation._STEPS,
        simulation._INT_X,
        simulation._INT_X2,
        simulation._EXHAUSTED,
    )
    assert [SCALARS[k] for k in indices] == [
        "time",
        "collisions",
        "steps",
        "int_x",
        "int_x2",
        "budget_exhausted",
    ]


def test_a_single_shard_is_refused_by_every_reader_of_shards(tmp_path):
    """merge_shards wrote NaN errors from one shard: refused, saying errors need two."""
    path = tmp_path / "shard0.parquet"
    write_table(tallies_to_frame(_empty_shard()), path, {"r": "1/2", "r_label": "0.5"})
    with pytest.raises(UnreadableFileError, match=r"r = 0.5: 1 shard .*need two or more"):
        read_shards([path], "0.5")
