"""Merging shards is a sum; shards survive a round trip through Parquet."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks import reference_loop
from bouncing_ball.bins import LinearBins, LogBins
from bouncing_ball.estimators import (
    distribution_histogram,
    flight_time_histogram,
    jackknife,
    outgoing_speed_histogram,
    position_moments_summary,
    return_speed_table,
)
from bouncing_ball.settings import ShardSettings
from bouncing_ball.tallies import (
    BOUNCE_LAG_SUMS,
    BOUNCE_LAGS,
    EARLY_FRACTION,
    ShardTallies,
    merge_shards,
    tallies_from_frame,
    tallies_to_frame,
)
from bouncing_ball.tallies import (
    CONTROL_VARIATE_SUMS as CONTROL_VARIATES,
)
from bouncing_ball.workflow.batches import (
    batch_from_frame,
    batch_from_table,
    batch_to_frame,
    batch_to_table,
)
from bouncing_ball.workflow.io import UnreadableFileError, read_table, write_table
from bouncing_ball.workflow.shards import read_shards

SPEED_BINS = LogBins(1e-2, 1e1, 2)
POSITION_BINS = LogBins(1e-1, 1e2, 1)
VELOCITY_BINS = LinearBins(-1.0, 2.0, 1.0)
FLIGHT_TIME_BINS = LogBins(1e-2, 1e1, 1)
LAG_SHAPE = (len(BOUNCE_LAG_SUMS), BOUNCE_LAGS + 1)
LAG_SIZE = LAG_SHAPE[0] * LAG_SHAPE[1]
BIN_SET = SimpleNamespace(
    speed_bins=SPEED_BINS,
    position_bins=POSITION_BINS,
    velocity_bins=VELOCITY_BINS,
    flight_time_bins=FLIGHT_TIME_BINS,
)


def _shard(**changes):
    """A shard on BIN_SET with nothing recorded, ``changes`` applied."""
    return replace(ShardTallies.from_loop(BIN_SET, ShardTallies.loop_arrays(BIN_SET)), **changes)


@st.composite
def shard_tallies(draw):
    nv, nx = SPEED_BINS.n + 2, POSITION_BINS.n + 2
    nu, nf = VELOCITY_BINS.n + 2, FLIGHT_TIME_BINS.n + 2
    counts = st.integers(0, 10**6)
    times = st.floats(0.0, 1e6, allow_nan=False)
    noise = st.floats(-1e6, 1e6, allow_nan=False)  # the control variates: sums of mean 0

    def array(elements, size, dtype=float, shape=None):
        values = np.array(draw(st.lists(elements, min_size=size, max_size=size)), dtype=dtype)
        return values.reshape(shape) if shape else values

    return _shard(
        speed_counts=array(counts, nv, np.int64),
        position_time=array(times, nx),
        position_v2_time=array(times, nx),
        flight_time_counts=array(counts, nf, np.int64),
        position_velocity_time=array(times, nx * nu, shape=(nx, nu)),
        return_speed_counts=array(counts, nv * nv, np.int64, shape=(nv, nv)),
        bounce_lag_sums=array(noise, len(BOUNCE_LAG_SUMS) * (BOUNCE_LAGS + 1), shape=LAG_SHAPE),
        time=draw(st.floats(1.0, 1e6)),
        collisions=draw(counts),
        steps=draw(counts),
        int_x=draw(times),
        int_x2=draw(times),
        budget_exhausted=draw(st.integers(0, 1)),
        flights=draw(counts),
        flight_time_sum=draw(times),
        flight_time_squared_sum=draw(times),
        **{name: draw(noise) for name in CONTROL_VARIATES},
        early_time=draw(times),
        early_collisions=draw(counts),
        early_int_x=draw(times),
        early_int_x2=draw(times),
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
    # the new tallies are sums too: 2-D ones cell by cell
    assert np.array_equal(merged.flight_time_counts, sum(s.flight_time_counts for s in shards))
    assert np.array_equal(merged.return_speed_counts, sum(s.return_speed_counts for s in shards))
    assert merged.return_speed_counts.shape == (SPEED_BINS.n + 2,) * 2
    np.testing.assert_allclose(
        merged.position_velocity_time, sum(s.position_velocity_time for s in shards), rtol=1e-12
    )
    assert merged.flights == sum(s.flights for s in shards)
    assert merged.flight_time_sum == pytest.approx(again.flight_time_sum, rel=1e-12)
    assert merged.flight_time_squared_sum == pytest.approx(
        sum(s.flight_time_squared_sum for s in shards), rel=1e-12
    )
    assert merged.time == pytest.approx(sum(s.time for s in shards), rel=1e-12)
    assert merged.int_x2 == pytest.approx(again.int_x2, rel=1e-12)


@settings(max_examples=20, deadline=None)
@given(shard_tallies())
def test_frame_round_trip(shard):
    _same_tallies(shard, tallies_from_frame(tallies_to_frame(shard), BIN_SET))


def test_a_table_without_the_bounce_lag_sums_is_refused():
    # a shard table of a layout without them: refused by name, as a tally off its bins is
    frame = tallies_to_frame(_shard())
    old_layout = frame[~frame.tally.isin(BOUNCE_LAG_SUMS)]
    with pytest.raises(ValueError, match="'lag_pairs' is not on the lags 0 .. 16.*re-run"):
        tallies_from_frame(old_layout, BIN_SET)


def test_the_bounce_lag_sums_merge_lag_by_lag():
    one = _shard(bounce_lag_sums=np.arange(LAG_SIZE, dtype=float).reshape(LAG_SHAPE))
    merged = merge_shards([one, one])
    assert np.array_equal(merged.bounce_lag_sums, 2.0 * one.bounce_lag_sums)
    _same_tallies(merged, tallies_from_frame(tallies_to_frame(merged), BIN_SET))


def _same_tallies(ours, theirs):
    for name in reference_loop.TALLY_FIELDS:  # every field, bit for bit and of the same type
        mine, back = getattr(ours, name), getattr(theirs, name)
        if isinstance(mine, np.ndarray):
            assert mine.dtype == back.dtype and np.array_equal(mine, back), name
        else:
            assert type(mine) is type(back) and mine == back, name


@settings(max_examples=10, deadline=None)
@given(st.lists(shard_tallies(), min_size=2, max_size=4))
def test_a_batch_table_round_trips_with_its_shards_rows_interleaved(shards):
    batch = dict(enumerate(shards))
    table = batch_to_table(batch)
    shard = table.column("shard").to_numpy()
    place = np.arange(shard.size) - np.searchsorted(shard, shard)  # the row within its shard
    interleaved = table.take(np.lexsort((shard, place)))  # shard 0's first row, shard 1's, ...
    assert not np.array_equal(interleaved.column("shard").to_numpy(), shard)
    for back in (
        batch_from_table(interleaved, BIN_SET),
        batch_from_frame(batch_to_frame(batch), BIN_SET),
    ):
        assert list(back) == list(batch)
        for k in batch:
            _same_tallies(batch[k], back[k])


def test_parquet_round_trip_keeps_provenance(tmp_path):
    shard = _shard(
        speed_counts=np.arange(SPEED_BINS.n + 2),
        position_time=np.ones(POSITION_BINS.n + 2),
        position_v2_time=np.ones(POSITION_BINS.n + 2),
        time=10.0,
        collisions=5,
        steps=50,
        int_x=1.0,
        int_x2=2.0,
    )
    path = tmp_path / "shard0.parquet"
    write_table(tallies_to_frame(shard), path, {"r": "1/3", "seed": 7})
    frame, provenance = read_table(path)
    assert provenance["r"] == "1/3" and provenance["seed"] == 7 and "package_version" in provenance
    assert np.array_equal(tallies_from_frame(frame, BIN_SET).speed_counts, shard.speed_counts)
    assert [p.name for p in tmp_path.iterdir()] == ["shard0.parquet"]  # no temporary left


def _empty_shard():
    """A shard that recorded one time unit and nothing else."""
    return _shard(time=1.0)


def test_shards_on_other_bins_are_refused():
    shard = _empty_shard()
    with pytest.raises(ValueError, match="not on the configured bins"):
        tallies_from_frame(tallies_to_frame(shard), replace_bins(speed_bins=LogBins(1e-2, 1e1, 3)))
    # the 2-D tallies are checked on both variables
    with pytest.raises(ValueError, match="'position_velocity_time' is not on the configured"):
        tallies_from_frame(
            tallies_to_frame(shard), replace_bins(velocity_bins=LinearBins(-1.0, 2.0, 0.5))
        )


def replace_bins(**bins):
    return SimpleNamespace(**{**vars(BIN_SET), **bins})


def test_jackknife_of_a_mean_is_the_standard_error():
    rng = np.random.default_rng(3)
    samples = rng.normal(size=12)
    value, error = jackknife(lambda total, count: total / count, samples, np.ones(12))
    assert value == pytest.approx(samples.mean())
    assert error == pytest.approx(samples.std(ddof=1) / np.sqrt(12))


def test_jackknife_error_of_shards_that_agree_is_exactly_zero():
    """n shards with the same count and time: every delete-one estimate is the same, so the
    error is exactly 0 (fits.fit_errors and the comparison's ``error > 0`` rely on it), for
    counts and times where the plain mean of the equal estimates is off in its last bit."""
    rng = np.random.default_rng(4)
    for _ in range(200):
        n, count, time = int(rng.integers(3, 12)), float(rng.integers(1, 50)), rng.uniform(10, 100)
        _, error = jackknife(lambda c, t: c / t, np.full((n, 2), count), np.full((n, 1), time))
        assert np.all(error == 0.0), (n, count, time, error)


def test_outgoing_speed_density_counts_rate_over_bin():
    # one shard, 10 collisions in [1, 10) over time 2: p0v = 10 / (2 * (100 - 1) / 2)
    bins = LogBins(1.0, 10.0, 1)
    shard = ShardTallies.from_loop(
        replace_bins(speed_bins=bins), ShardTallies.loop_arrays(replace_bins(speed_bins=bins))
    )
    shard = replace(shard, speed_counts=np.array([0, 10, 0]), time=2.0, collisions=10, steps=100)
    table = outgoing_speed_histogram([shard])
    assert table.p0v.iloc[1] == pytest.approx(10.0 / 99.0)
    assert table["count"].sum() == 10


def test_truncated_file_gives_an_error_that_names_it(tmp_path):
    from bouncing_ball.workflow.io import UnreadableFileError

    path = tmp_path / "shard3.parquet"
    write_table(
        tallies_to_frame(_empty_shard()),
        path,
        {},
    )
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(UnreadableFileError, match="shard3.parquet"):
        read_table(path)


def test_the_compiled_loop_fills_each_scalar_by_its_name_in_SCALARS():
    """The scalars' layout has one definition, tallies.SCALARS: each scalar of a short shard
    (stopped by its step budget past the middle of its recording, so that none is 0)
    holds what its name says."""
    from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

    settings = ShardSettings(400.0, 50.0, 3.0, 500.0, 2000, LogBins(1e-4, 1e2, 10), POSITION_BINS)
    shard = simulate_shard(0.5, shard_seed_sequence(1, "0.5", 0), settings)
    assert shard.budget_exhausted == 1 and 200.0 < shard.time < 400.0
    assert 0 < shard.steps < 2000 and 0 < shard.collisions < shard.steps
    assert shard.flights == shard.collisions  # every recorded collision has an earlier one
    # the first flight may start in equilibration
    assert 0.0 < shard.flight_time_sum < shard.time + settings.equilibration_time
    assert shard.flight_time_sum**2 < shard.flights * shard.flight_time_squared_sum
    mean_x = shard.int_x / shard.time
    assert 0.0 < mean_x**2 < shard.int_x2 / shard.time < 1e3
    assert shard.position_time.sum() == pytest.approx(shard.time, rel=1e-9)
    assert shard.speed_counts.sum() == shard.collisions
    # the noise sums: of mean 0, with standard deviations about sqrt(steps) for the normals
    assert 0.0 < abs(shard.normal_sum) < 5.0 * shard.steps**0.5
    for name in ("noise_sum", "noise_v_sum", "noise_scaled_sum"):
        assert getattr(shard, name) != 0.0
    assert shard.noise_sum != shard.normal_sum
    # the early part: the steps that start before 400 EARLY_FRACTION, so it ends within a
    # step of that
    assert EARLY_FRACTION * 400.0 <= shard.early_time < EARLY_FRACTION * 400.0 + 1.0
    assert 0 < shard.early_collisions < shard.collisions
    assert 0.0 < shard.early_int_x < shard.int_x
    assert 0.0 < shard.early_int_x2 < shard.int_x2


def test_the_C_reference_reads_the_scalar_layout_of_SCALARS():
    """reference_loop passes SCALARS' layout and EARLY_FRACTION to gcc as -D flags; the C
    source writes every scalar through them and defines no index of its own."""
    import re

    from bouncing_ball.tallies import SCALARS

    flags = reference_loop.scalar_layout_flags()
    assert flags == [
        *(f"-DSCALAR_{name.upper()}={k}" for k, name in enumerate(SCALARS)),
        f"-DEARLY_FRACTION={EARLY_FRACTION.hex()}",
    ]
    command = reference_loop.compile_command(reference_loop.SOURCE, reference_loop.SOURCE)
    assert set(flags) <= set(command)
    source = reference_loop.SOURCE.read_text()
    written = set(re.findall(r"scalars\[SCALAR_([A-Z0-9_]+)\]", source))
    assert written == {name.upper() for name in SCALARS}
    assert not re.search(r"#define\s+SCALAR_|enum\s*{", source)


def _batch_file(path, shards, named=None):
    """A batch file of r = 1/2 holding ``shards`` (empty ones of one time unit), saying it
    holds ``named`` (default: those)."""
    named = shards if named is None else named
    provenance = {"r": "1/2", "r_label": "0.5", "first_shard": named[0], "last_shard": named[-1]}
    settings = ShardSettings(1.0, 0.0, 3.0, 500.0, 10, **vars(BIN_SET))
    provenance.update(settings.as_mapping())
    write_table(batch_to_frame(dict.fromkeys(shards, _empty_shard())), path, provenance)
    return path


def test_a_single_shard_is_refused_by_every_reader_of_shards(tmp_path):
    """merge_shards wrote NaN errors from one shard: refused, saying errors need two."""
    path = _batch_file(tmp_path / "shards0-0.parquet", [0])
    with pytest.raises(UnreadableFileError, match=r"r = 0.5: 1 shard .*need two or more"):
        read_shards([path], "0.5")


def test_batch_files_are_refused_where_a_shard_is_missing_or_counted_twice(tmp_path):
    shards, provenances = read_shards([_batch_file(tmp_path / "a.parquet", [0, 1, 2])], "0.5")
    assert len(shards) == 3 and [p["shard"] for p in provenances] == [0, 1, 2]
    lying = _batch_file(tmp_path / "b.parquet", [0, 1], named=[0, 1, 2])
    with pytest.raises(
        UnreadableFileError, match=r"b.parquet: holds shards \[0, 1\], not shards 0-2"
    ):
        read_shards([lying], "0.5")
    twice = [_batch_file(tmp_path / "c.parquet", [0, 1]), _batch_file(tmp_path / "d.parquet", [1])]
    with pytest.raises(UnreadableFileError, match="d.parquet: shard 1 is also in .*c.parquet"):
        read_shards(twice, "0.5")


def test_new_merged_tables_on_hand_computed_shards():
    # two shards of time 2 and 4; P(x, v): 1 time unit in cell (x bin 1, v bin 1) of each
    cell = np.zeros((POSITION_BINS.n + 2, VELOCITY_BINS.n + 2))
    cell[1, 1] = 1.0
    flight_counts = np.zeros(FLIGHT_TIME_BINS.n + 2, dtype=np.int64)
    flight_counts[2] = 3  # [0.1, 1)
    returns = np.zeros((SPEED_BINS.n + 2,) * 2, dtype=np.int64)
    returns[1, 1], returns[1, 2] = 1, 2  # u in [0.01, 0.0316): v there once, one bin up twice
    shards = [
        _shard(
            time=t,
            position_velocity_time=cell * k,
            flight_time_counts=flight_counts,
            return_speed_counts=returns,
            flights=3,
            flight_time_sum=s,
            flight_time_squared_sum=q,
        )
        for t, k, s, q in ((2.0, 1.0, 1.5, 1.0), (4.0, 2.0, 1.5, 2.0))
    ]
    table = distribution_histogram(shards)
    assert list(table.columns) == ["x_lo", "x_hi", "v_lo", "v_hi", "pxv", "pxv_err"]
    assert len(table) == (POSITION_BINS.n + 2) * (VELOCITY_BINS.n + 2)
    row = table[(table.x_lo == 0.1) & (table.v_lo == -1.0)].iloc[0]
    # 3 time units of 6 in a cell of 0.9 x 1
    assert row.pxv == pytest.approx(3.0 / 6.0 / 0.9) and row.x_hi == pytest.approx(1.0)
    # jackknife of the ratio: leave-one-out 2/4/0.9 and 1/2/0.9 -> sqrt(1/2) * 0
    assert row.pxv_err == pytest.approx(0.0, abs=1e-15)
    assert table.pxv[~np.isfinite(table.v_lo)].isna().all()
    flights = flight_time_histogram(shards)
    assert list(flights.columns) == ["t_lo", "t_hi", "t", "density", "density_err"]
    assert flights.density.iloc[2] == pytest.approx(6.0 / 6.0 / 0.9)
    assert np.isnan(flights.density.iloc[-1])
    returned = return_speed_table(shards)
    assert list(returned.columns) == [
        "u_lo",
        "u_hi",
        "v_lo",
        "v_hi",
        "probability",
        "probability_err",
    ]
    n = SPEED_BINS.n + 2
    assert returned.probability.iloc[n + 1] == pytest.approx(1.0 / 3.0)
    assert returned.probability.iloc[n + 2] == pytest.approx(2.0 / 3.0)
    assert returned.probability.iloc[:n].isna().all()  # no flight left at those u
    summary = position_moments_summary(shards, 0.5)
    assert summary.mean_flight_time.iloc[0] == pytest.approx(3.0 / 6.0)
    assert summary.flight_time_second_moment.iloc[0] == pytest.approx(3.0 / 6.0)
    # leave-one-out means 0.5 and 0.5: no scatter
    assert summary.mean_flight_time_err.iloc[0] == pytest.approx(0.0, abs=1e-15)
    # leave-one-out second moments 2/3 and 1/3: sqrt(1/2 * 2 * (1/6)^2) = 1/6
    assert summary.flight_time_second_moment_err.iloc[0] == pytest.approx(1.0 / 6.0)
