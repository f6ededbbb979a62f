"""numba for the compiled modules, its cache kept in a folder named after the package's source.

``cache=True`` checks only the file that holds a compiled function, not the
files it calls into: after an edit of free_flight.py a cached simulation loop
would silently keep the old code.  So the cache folder is keyed on the whole
package's source.  A user's NUMBA_CACHE_DIR is respected.  Only the compiled
modules import this, so importing the package (as the workflow does to plan a
run) does not load numba.
"""

import numba

from . import PACKAGE, source_digest

if not numba.config.CACHE_DIR:
    numba.config.CACHE_DIR = str(PACKAGE / "__pycache__" / f"numba-{source_digest()}")

njit = numba.njit
prange = numba.prange
