"""numba for the compiled modules, its cache kept in a folder named after their source.

``cache=True`` checks only the file that holds a compiled function, not the
files it calls into: after an edit of free_flight.py a cached simulation loop
would silently keep the old code.  So the cache folder is keyed on the source
of every module numba compiles (``stages.COMPILED``: an edit of plotting.py
does not recompile), inside numba's own cache folder or, where the user set
NUMBA_CACHE_DIR, inside that one.  Only the compiled
modules import this, so importing the package (as the workflow does to plan a
run) does not load numba.

Every edit of compiled code makes a new folder; the old ones are pruned here,
keeping the ``KEEP_CACHES`` most recently used besides the current one (so
switching between two versions does not recompile) and never one used in the
last ``PRUNE_AFTER_SECONDS`` (a job of another version may still be running).
"""

import contextlib
import functools
import os
import shutil
import time
from pathlib import Path

import numba

from . import PACKAGE, source_digest, stages

KEEP_CACHES = 3
PRUNE_AFTER_SECONDS = 3600.0


def prune_caches(
    base: Path, current: Path, keep: int = KEEP_CACHES, older_than: float = PRUNE_AFTER_SECONDS
):
    """Remove ``numba-*`` folders under ``base`` other than ``current``, keeping the ``keep`` newest.

    Returns the folders removed.  Failures (a folder removed by another
    process at the same time, no permission) are ignored: pruning is tidying.
    """
    try:
        others = [path for path in base.glob("numba-*") if path.is_dir() and path != current]
        others.sort(key=lambda path: path.stat().st_mtime, reverse=True)
    except OSError:
        return []
    now = time.time()
    removed = []
    for path in others[keep:]:
        try:
            if now - path.stat().st_mtime < older_than:
                continue
            shutil.rmtree(path)
            removed.append(path)
        except OSError:
            continue
    return removed


_base = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else PACKAGE / "__pycache__"
CACHE = _base / f"numba-{source_digest(stages.COMPILED)}"
numba.config.CACHE_DIR = str(CACHE)
with contextlib.suppress(OSError):  # not there yet, or not ours to touch (a read-only cache)
    os.utime(CACHE)  # in use: the newest to keep
prune_caches(_base, CACHE)

# IEEE division (inf or NaN) instead of a Python ZeroDivisionError check on every division:
# the compiled code tests its own denominators, and the C reference of the loop does the same
njit = functools.partial(numba.njit, error_model="numpy")
prange = numba.prange
