"""Equilibrium statistics of an inelastically bouncing ball (Burkhardt & Kotsev 2006)."""

import hashlib
from pathlib import Path

__version__ = "0.1.0"

PACKAGE = Path(__file__).parent


def source_digest(modules=None) -> str:
    """A short hash of the source of the named modules of this package (all if None).

    The workflow passes it to its rules as a parameter, so that editing the
    code behind a stage re-runs that stage and nothing else.
    """
    names = sorted(path.stem for path in PACKAGE.glob("*.py")) if modules is None else sorted(modules)
    digest = hashlib.sha256()
    for name in names:
        digest.update(name.encode())
        digest.update((PACKAGE / f"{name}.py").read_bytes())
    return digest.hexdigest()[:16]


def _use_source_keyed_numba_cache():
    """Keep numba's compiled code in a folder named after the package's source.

    ``cache=True`` checks only the file that holds a compiled function, not
    the files it calls into: after an edit of free_flight.py a cached
    simulation loop would silently keep the old code.  A user's
    NUMBA_CACHE_DIR is respected.
    """
    import numba

    if not numba.config.CACHE_DIR:
        numba.config.CACHE_DIR = str(PACKAGE / "__pycache__" / f"numba-{source_digest()}")


_use_source_keyed_numba_cache()
