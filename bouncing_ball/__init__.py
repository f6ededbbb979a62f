"""Equilibrium statistics of an inelastically bouncing ball (Burkhardt & Kotsev 2006)."""

import hashlib
import os
import sys
from pathlib import Path

__version__ = "0.1.0"


def _numba_cache_directory() -> str:
    """A numba cache folder named after a hash of this package's source.

    numba's ``cache=True`` checks only the timestamp of the file that holds a
    compiled function, not of the files it calls into: after an edit of
    free_flight.py the cached simulation loop would silently keep the old
    code.  Keying the folder on all sources makes any edit a fresh compile.
    """
    digest = hashlib.sha256()
    for source in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(source.read_bytes())
    return str(Path(__file__).parent / "__pycache__" / f"numba-{digest.hexdigest()[:16]}")


if "NUMBA_CACHE_DIR" not in os.environ and "numba" not in sys.modules:
    os.environ["NUMBA_CACHE_DIR"] = _numba_cache_directory()
