"""The plain C reference of the shard loop (benchmarks/reference/shard_loop.c).

It translates the numba loop operation for operation, is compiled without
FMA contraction and draws its normals with numpy's C ziggurat from the same
PCG64 stream, so on the same seed sequence it must give bit-identical
tallies: any difference means the two codes no longer do the same arithmetic
(e.g. simulation/loop.py or free_flight.py was changed and shard_loop.c was not).
"""

import shutil
import subprocess
import sys

import numpy as np
import pytest
from workflow_support import REPOSITORY

from benchmarks import reference_loop
from benchmarks.reference_loop import build, reference_shard
from bouncing_ball.bins import LogBins
from bouncing_ball.settings import ShardSettings
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

needs_gcc = pytest.mark.skipif(
    shutil.which(reference_loop.COMPILER) is None,
    reason=f"the C compiler '{reference_loop.COMPILER}' is not installed",
)

SPEED_BINS = LogBins(1e-4, 1e2, 10)
POSITION_BINS = LogBins(1e-3, 1e3, 5)
FIELDS = reference_loop.TALLY_FIELDS


@pytest.fixture(scope="module")
def library():
    try:
        return build()
    except (RuntimeError, OSError) as error:  # e.g. no Python headers to compile against
        pytest.skip(f"the C reference cannot be built here: {str(error).splitlines()[0]}")


def _both(
    library,
    r,
    seed=3,
    recorded_time=2e3,
    equilibration_time=100.0,
    max_steps=10**9,
    min_step_floor=0.0,
    criterion_c=5.0,
):
    settings = ShardSettings(
        shard_time=recorded_time,
        equilibration_time=equilibration_time,
        criterion_c=criterion_c,
        min_step_divisor=500.0,
        max_steps=max_steps,
        speed_bins=SPEED_BINS,
        position_bins=POSITION_BINS,
        min_step_floor=min_step_floor,
    )
    stream = shard_seed_sequence(seed, str(r), 0)
    numba_tallies = simulate_shard(r, stream, settings)
    c_tallies = reference_shard(r, stream, settings, library=library)
    return numba_tallies, c_tallies


def _assert_identical(numba_tallies, c_tallies):
    for name in FIELDS:
        ours, theirs = getattr(numba_tallies, name), getattr(c_tallies, name)
        if isinstance(ours, np.ndarray):
            assert ours.dtype == theirs.dtype and np.array_equal(ours, theirs), name
        else:
            assert type(ours) is type(theirs) and ours == theirs, name


@needs_gcc
@pytest.mark.parametrize("criterion_c", [3.0, 5.0])
@pytest.mark.parametrize("r", [0.5, 0.25, 0.75])
def test_c_reference_gives_bit_identical_tallies(library, r, criterion_c):
    numba_tallies, c_tallies = _both(library, r, criterion_c=criterion_c)
    assert numba_tallies.collisions > 100 and numba_tallies.budget_exhausted == 0
    assert numba_tallies.position_time[1:-1].sum() > 0.0  # the x bins were walked
    _assert_identical(numba_tallies, c_tallies)


@needs_gcc
def test_identical_with_a_floor_on_delta_below_r_c(library):
    numba_tallies, c_tallies = _both(
        library, 0.05, recorded_time=500.0, equilibration_time=10.0, min_step_floor=1e-10
    )
    assert numba_tallies.budget_exhausted == 0 and numba_tallies.time == pytest.approx(500.0)
    _assert_identical(numba_tallies, c_tallies)


@needs_gcc
def test_identical_when_the_step_budget_runs_out(library):
    numba_tallies, c_tallies = _both(library, 0.5, max_steps=3000)
    assert numba_tallies.budget_exhausted == 1 and 0.0 < numba_tallies.time < 2e3
    _assert_identical(numba_tallies, c_tallies)


@needs_gcc
def test_identical_through_a_collapse_without_a_floor(library):
    # below r_c with the paper's rule alone: speeds fall to ~1e-37 and the shard stops early
    numba_tallies, c_tallies = _both(
        library, 0.05, recorded_time=1e3, equilibration_time=0.0, max_steps=2_000_000
    )
    assert numba_tallies.budget_exhausted == 1 and numba_tallies.collisions > 10
    assert numba_tallies.steps < 2_000_000  # stopped by COLLAPSED_STEP, not by the budget
    _assert_identical(numba_tallies, c_tallies)


@needs_gcc
def test_everything_as_equilibration(library):
    # tallies off: only the stepping, and the time of a shard that never records
    numba_tallies, c_tallies = _both(library, 0.5, recorded_time=1e-9, equilibration_time=2e3)
    assert numba_tallies.steps <= 1
    _assert_identical(numba_tallies, c_tallies)


@needs_gcc
def test_edited_source_builds_into_a_new_cache_folder(tmp_path):
    source = tmp_path / "shard_loop.c"
    source.write_bytes(reference_loop.SOURCE.read_bytes())
    cache = tmp_path / "cache"
    first = build(cache, source)
    assert first.parent.parent == cache and first.parent.name.startswith("reference-")
    built_at = first.stat().st_mtime_ns
    assert build(cache, source) == first and first.stat().st_mtime_ns == built_at  # cached
    source.write_bytes(source.read_bytes() + b"\n/* edited */\n")
    second = build(cache, source)
    assert second.parent != first.parent and first.is_file() and second.is_file()
    assert not list(cache.rglob(".build-*"))  # no scratch left behind
    # and the edited library still works
    stream = shard_seed_sequence(1, "0.5", 0)
    settings = ShardSettings(
        shard_time=100.0,
        equilibration_time=10.0,
        criterion_c=5.0,
        min_step_divisor=500.0,
        max_steps=10**9,
        speed_bins=SPEED_BINS,
        position_bins=POSITION_BINS,
    )
    _assert_identical(
        reference_shard(0.5, stream, settings, library=first),
        reference_shard(0.5, stream, settings, library=second),
    )


def test_cache_key_covers_source_and_flags():
    command = ["gcc", "-O3", "x.c"]
    assert reference_loop.cache_key(b"a", command) != reference_loop.cache_key(b"b", command)
    assert reference_loop.cache_key(b"a", command) != reference_loop.cache_key(
        b"a", command + ["-g"]
    )


def test_missing_compiler_is_named(monkeypatch, tmp_path):
    monkeypatch.setattr(reference_loop, "COMPILER", "no-such-cc-for-the-test")
    with pytest.raises(RuntimeError, match="no-such-cc-for-the-test"):
        build(tmp_path)


def test_module_does_not_import_numba():
    code = "import sys, benchmarks.reference_loop; sys.exit('numba' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], cwd=REPOSITORY).returncode == 0
