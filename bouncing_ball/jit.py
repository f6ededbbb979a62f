"""numba for the compiled modules, its cache kept in a folder named after the package's source.

``cache=True`` checks only the file that holds a compiled function, not the
files it calls into: after an edit of free_flight.py a cached simulation loop
would silently keep the old code.  So the cache folder is keyed on the whole
package's source, inside numba's own cache folder or, where the user set
NUMBA_CACHE_DIR, inside that one.  Only the compiled
modules import this, so importing the package (as the workflow does to plan a
run) does not load numba.
"""

from pathlib import Path

import numba

from . import PACKAGE, source_digest

_base = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else PACKAGE / "__pycache__"
numba.config.CACHE_DIR = str(_base / f"numba-{source_digest()}")

njit = numba.njit
prange = numba.prange
