"""numba's cache folders: keyed on the source, old ones pruned."""

import os
import subprocess
import sys
import time

from bouncing_ball import PACKAGE, jit, source_digest


def _folder(base, name, age_seconds):
    path = base / name
    path.mkdir()
    (path / "entry.nbi").write_text("x")
    stamp = time.time() - age_seconds
    os.utime(path, (stamp, stamp))
    return path


def test_the_cache_folder_is_named_after_the_compiled_source_only():
    """An edit of plotting.py (not compiled) keeps the cache; one of free_flight.py does not."""
    assert jit.CACHE.name == f"numba-{source_digest(jit.COMPILED)}"
    assert "plotting" not in jit.COMPILED and "free_flight" in jit.COMPILED


def test_old_cache_folders_are_pruned_keeping_the_newest_and_the_recent(tmp_path):
    current = _folder(tmp_path, "numba-current", 10 * 86400)  # never removed, however old
    recent = _folder(tmp_path, "numba-recent", 60)  # used a minute ago: a job may be running
    kept = [_folder(tmp_path, f"numba-kept{k}", 7200 + k) for k in range(2)]
    stale = [_folder(tmp_path, f"numba-stale{k}", 86400 + k) for k in range(3)]
    unrelated = _folder(tmp_path, "something-else", 86400 * 30)

    removed = jit.prune_caches(tmp_path, current, keep=3, older_than=3600)

    assert sorted(removed) == sorted(stale)
    for path in (current, recent, *kept, unrelated):
        assert path.is_dir()
    for path in stale:
        assert not path.exists()


def test_pruning_keeps_a_recently_used_folder_beyond_the_count(tmp_path):
    current = _folder(tmp_path, "numba-current", 0)
    folders = [_folder(tmp_path, f"numba-v{k}", 30 + k) for k in range(5)]
    assert jit.prune_caches(tmp_path, current, keep=1, older_than=3600) == []
    assert all(path.is_dir() for path in folders)


def test_every_module_with_compiled_code_keys_the_cache():
    """A module that numba compiles (an @njit function) must be in jit.COMPILED, else an
    edit of it would be served stale code from the cache."""
    compiled = {
        path.stem
        for path in PACKAGE.glob("*.py")
        if "@njit" in path.read_text() or "njit(" in path.read_text()
    }
    assert compiled - {"jit"} and compiled <= set(jit.COMPILED)


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


def test_a_checkout_that_cannot_be_written_caches_in_the_users_folder(tmp_path):
    """A read-only checkout recompiled in every shard (11.8 s against 0.5 s)."""
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the package's __pycache__ would be")
    fallback = tmp_path / "user-cache"
    assert jit.writable_cache_base(blocker / "__pycache__", fallback) == fallback
    assert jit.writable_cache_base(tmp_path / "writable", fallback) == tmp_path / "writable"
    assert jit.user_cache_folder().name == "bouncing_ball"
