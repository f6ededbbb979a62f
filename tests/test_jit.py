"""numba's cache folders: keyed on the source, old ones pruned."""

import os
import time

from bouncing_ball import jit, source_digest


def _folder(base, name, age_seconds):
    path = base / name
    path.mkdir()
    (path / "entry.nbi").write_text("x")
    stamp = time.time() - age_seconds
    os.utime(path, (stamp, stamp))
    return path


def test_the_cache_folder_is_named_after_the_source():
    assert jit.CACHE.name == f"numba-{source_digest()}"


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
