"""numba's cache folders: keyed on the source, old ones pruned."""

import os
import time

from bouncing_ball import PACKAGE, jit, source_digest, stages


def _folder(base, name, age_seconds):
    path = base / name
    path.mkdir()
    (path / "entry.nbi").write_text("x")
    stamp = time.time() - age_seconds
    os.utime(path, (stamp, stamp))
    return path


def test_the_cache_folder_is_named_after_the_compiled_source_only():
    """An edit of plotting.py (not compiled) keeps the cache; one of free_flight.py does not."""
    assert jit.CACHE.name == f"numba-{source_digest(stages.COMPILED)}"
    assert "plotting" not in stages.COMPILED and "free_flight" in stages.COMPILED


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
    """A module that numba compiles (an @njit function) must be in stages.COMPILED, else an
    edit of it would be served stale code from the cache."""
    compiled = {
        path.stem
        for path in PACKAGE.glob("*.py")
        if "@njit" in path.read_text() or "njit(" in path.read_text()
    }
    assert compiled - {"jit"} and compiled <= set(stages.COMPILED)
