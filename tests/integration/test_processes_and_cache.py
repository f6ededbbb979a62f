"""numba's cache and simulate's worker processes, each in processes of their own: a damaged
cache file is recompiled, a read-only install caches in the temporary folder, and simulate's
numbers do not depend on the number of worker processes (split from tests/unit/test_jit.py
and test_equilibrium.py: each starts Python processes that import and compile)."""

import os
import shutil
import subprocess
import sys

import bouncing_ball as bb
from bouncing_ball import PACKAGE

CACHED_MODULE = """
from bouncing_ball.jit import njit


@njit(cache=True)
def square(x):
    return x * x
"""


def _run_cached(tmp_path):
    environment = dict(
        os.environ, PYTHONPATH=str(tmp_path), NUMBA_CACHE_DIR=str(tmp_path / "cache")
    )
    return subprocess.run(
        [sys.executable, "-c", "import cached_square; print(cached_square.square(3.0))"],
        env=environment,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_damaged_cache_file_is_recompiled_not_raised_in_every_job(tmp_path):
    """A truncated numba cache file made every shard fail with UnpicklingError."""
    (tmp_path / "cached_square.py").write_text(CACHED_MODULE)
    assert _run_cached(tmp_path).stdout.strip() == "9.0"
    files = sorted((tmp_path / "cache").rglob("cached_square.square-*"))
    assert {path.suffix for path in files} == {".nbi", ".nbc"}
    for path in files:
        path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    damaged = _run_cached(tmp_path)
    assert damaged.returncode == 0 and damaged.stdout.strip() == "9.0", damaged.stderr
    assert "cached_square.square" in damaged.stderr and "is damaged" in damaged.stderr
    again = _run_cached(tmp_path)  # recompiled and cached afresh
    assert again.stdout.strip() == "9.0" and "damaged" not in again.stderr


def test_a_read_only_install_with_no_writable_home_caches_in_the_temporary_folder(tmp_path):
    """A container: the package, HOME and XDG_CACHE_HOME cannot be written to.  Tests run as
    root, which ignores permission bits, so each folder is made unwritable by a file standing
    where it (or its parent) would be; the package copy is also made read-only for others."""
    install = tmp_path / "install"
    shutil.copytree(
        PACKAGE, install / "bouncing_ball", ignore=shutil.ignore_patterns("__pycache__")
    )
    (install / "bouncing_ball" / "__pycache__").write_text("a file: no cache folder here")
    (install / "cached_function.py").write_text(
        "from bouncing_ball import jit\n\n@jit.njit(cache=True)\ndef twice(x):\n    return 2 * x\n"
    )
    for path in sorted(install.rglob("*"), reverse=True):
        path.chmod(0o555 if path.is_dir() else 0o444)
    blocker = tmp_path / "blocker"
    blocker.write_text("a file where the home and the user's cache folder would be")
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    environment = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    environment.update(
        HOME=str(blocker / "home"),
        XDG_CACHE_HOME=str(blocker / "cache"),
        TMPDIR=str(temporary),
        PYTHONPATH=str(install),
        PYTHONDONTWRITEBYTECODE="1",
    )
    try:
        run = subprocess.run(
            [sys.executable, "-c", "import cached_function; print(cached_function.twice(21))"],
            cwd=install,
            env=environment,
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        for path in install.rglob("*"):
            path.chmod(0o755 if path.is_dir() else 0o644)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == ["42"]
    warning = run.stderr.strip().splitlines()
    assert len(warning) == 1 and "NUMBA_CACHE_DIR" in warning[0], run.stderr
    cache = temporary / f"bouncing_ball-{os.getuid()}"
    assert str(cache) in warning[0]
    assert list(cache.glob("numba-*/**/*.nbi")), "the compiled function is cached there"


def test_simulate_is_reproducible_whatever_the_processes():
    arguments = {
        "shards": 3,
        "shard_time": 300.0,
        "seed": 11,
        "settings": {"equilibration_time": 20.0},
    }
    one = bb.simulate(0.6, processes=1, progress=False, **arguments)
    two = bb.simulate(0.6, processes=2, progress=False, **arguments)
    assert one.batch_frame().equals(two.batch_frame())
    assert one.summary_table.equals(two.summary_table) and one.pxv_histogram.equals(
        two.pxv_histogram
    )
    again = bb.simulate(0.6, processes=1, progress=False, **{**arguments, "seed": 12})
    assert not again.batch_frame().equals(one.batch_frame())


STDIN_SCRIPT = """
import warnings
import bouncing_ball as bb

with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    two = bb.simulate("1/2", shards=2, shard_time=200.0, seed=3, progress=False, processes=2)
one = bb.simulate("1/2", shards=2, shard_time=200.0, seed=3, progress=False, processes=1)
print(two.mean_x == one.mean_x, two.collision_rate == one.collision_rate)
print([str(w.message) for w in caught if w.category is RuntimeWarning])
"""


def test_simulate_with_workers_from_a_script_on_standard_input_runs_and_says_why():
    """``python - < run.py`` with processes=2 died with BrokenProcessPool: spawned workers
    re-run the main module from its path, '<stdin>'."""
    run = subprocess.run(
        [sys.executable, "-"],
        input=STDIN_SCRIPT,
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(os.environ, PYTHONPATH=str(PACKAGE.parent)),
    )
    assert run.returncode == 0, run.stderr
    same, warned = run.stdout.strip().splitlines()
    assert same == "True True"
    assert "processes=2 runs the shards in this process" in warned and "'<stdin>'" in warned
