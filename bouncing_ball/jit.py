"""numba for the compiled modules, its cache kept in a folder named after their source, and
the fused multiply-add they use (``fma``).

``cache=True`` checks only the file that holds a compiled function, not the
files it calls into: after an edit of free_flight.py a cached simulation loop
would silently keep the old code.  So the cache folder is keyed on the source
of every module numba compiles (``COMPILED``: an edit of plotting.py
does not recompile), inside numba's own cache folder or, where the user set
NUMBA_CACHE_DIR, inside that one.  Only the compiled
modules import this, so importing the package (as the workflow does to plan a
run) does not load numba.

Every edit of compiled code makes a new folder; the old ones are pruned here,
keeping the ``KEEP_CACHES`` most recently used besides the current one (so
switching between two versions does not recompile) and never one used in the
last ``PRUNE_AFTER_SECONDS`` (a job of another version may still be running).

Two faults are survived rather than passed on to every job: a checkout that
cannot be written to (a shared read-only install) caches under the user's
cache folder instead (``$XDG_CACHE_HOME/bouncing_ball``, else
``~/.cache/bouncing_ball``), where numba would otherwise recompile in every
process, and where that cannot be written either (a container with no home) under
the temporary folder, saying so in one line (``cache_base``); and a damaged cache file (a truncated write, a full disk) is a cache
miss, reported with its folder, removed and recompiled, where numba would raise
``UnpicklingError`` in every job.
"""

import contextlib
import logging
import math
import os
import shutil
import tempfile
import time
from fractions import Fraction
from pathlib import Path

import numba
from numba import types
from numba.core.caching import FunctionCache
from numba.extending import intrinsic, overload

from . import PACKAGE, source_digest

__all__ = [
    "njit",
    "fma",
    "flag_is_set",
    "COMPILED",
    "CACHE",
    "prune_caches",
    "user_cache_folder",
    "writable_cache_base",
    "cache_base",
    "RecoveringFunctionCache",
]

KEEP_CACHES = 3
PRUNE_AFTER_SECONDS = 3600.0


def prune_caches(
    base: Path, current: Path, keep: int = KEEP_CACHES, older_than: float = PRUNE_AFTER_SECONDS
):
    """Remove the ``numba-*`` folders under ``base`` other than ``current``, but the newest.

    Failures (a folder removed by another process at the same time, no permission) are
    ignored: pruning is tidying.

    Parameters
    ----------
    base : pathlib.Path
        The folder holding the cache folders.
    current : pathlib.Path
        The cache folder in use, never removed.
    keep : int
        How many of the others are kept, the most recently used.
    older_than : float
        Seconds: a folder used more recently than that is kept (a job of another version
        may still be running).

    Returns
    -------
    list of pathlib.Path
        The folders removed.

    Examples
    --------
    >>> import os, tempfile, time
    >>> from pathlib import Path
    >>> from bouncing_ball.jit import prune_caches
    >>> base = Path(tempfile.mkdtemp())
    >>> for age, name in enumerate(["numba-a", "numba-b", "numba-c"]):
    ...     (base / name).mkdir()
    ...     os.utime(base / name, (time.time() - 7200 * (age + 1),) * 2)
    >>> [path.name for path in prune_caches(base, base / "numba-a", keep=1)]
    ['numba-c']
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


def user_cache_folder() -> Path | None:
    """Where the cache goes when the checkout cannot be written to.

    Returns
    -------
    pathlib.Path or None
        ``$XDG_CACHE_HOME/bouncing_ball``, else ``~/.cache/bouncing_ball``; None with
        neither a ``XDG_CACHE_HOME`` nor a home folder.
    """
    root = os.environ.get("XDG_CACHE_HOME")
    if not root:
        try:
            root = Path.home() / ".cache"
        except (RuntimeError, KeyError):  # no HOME and no entry in the password database
            return None
    return Path(root) / "bouncing_ball"


def _is_writable(folder: Path | None) -> bool:
    """Whether a cache folder can be made and written in ``folder``."""
    if folder is None:
        return False
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
        return True
    except OSError:
        return False


def writable_cache_base(preferred: Path, fallback: Path) -> Path:
    """``preferred`` if a cache folder can be made and written in it, else ``fallback``.

    Parameters
    ----------
    preferred, fallback : pathlib.Path
        The folder wanted, and the one to use where it cannot be written to.

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from bouncing_ball.jit import writable_cache_base
    >>> folder = Path(tempfile.mkdtemp())
    >>> writable_cache_base(folder / "cache", folder / "other") == folder / "cache"
    True
    """
    return preferred if _is_writable(preferred) else fallback


def _temporary_cache_folder() -> Path | None:
    """``bouncing_ball-<user id>`` in the temporary folder, made private to this user; a
    fresh folder where that name is another user's (who could plant compiled code in it);
    None with no writable temporary folder."""
    try:
        user = os.getuid()
        folder = Path(tempfile.gettempdir()) / f"bouncing_ball-{user}"
        folder.mkdir(mode=0o700, exist_ok=True)
        if folder.is_symlink() or folder.stat().st_uid != user:
            folder = Path(tempfile.mkdtemp(prefix="bouncing_ball-"))
        return folder
    except (OSError, AttributeError):  # no temporary folder; no getuid (Windows)
        try:
            return Path(tempfile.mkdtemp(prefix="bouncing_ball-"))
        except OSError:
            return None


def cache_base(preferred: Path) -> Path:
    """The first writable folder for numba's cache folders, warning if it is a temporary one.

    ``preferred`` (NUMBA_CACHE_DIR, else the package's ``__pycache__``), else the user's
    cache folder (``user_cache_folder``), else, with a one-line warning,
    ``bouncing_ball-<user id>`` in the temporary folder (a container with a read-only install
    and no home: compiled code then lasts as long as that folder).

    Parameters
    ----------
    preferred : pathlib.Path
        The folder wanted.

    Returns
    -------
    pathlib.Path
        The first of them that can be written to.

    Raises
    ------
    RuntimeError
        Saying to set NUMBA_CACHE_DIR, where none of them can be written to.
    """
    fallback = user_cache_folder()
    for folder in (preferred, fallback):
        if _is_writable(folder):
            return folder
    temporary = _temporary_cache_folder()
    if not _is_writable(temporary):
        raise RuntimeError(
            f"no folder for numba's cache can be written to ({preferred}, {fallback}, the "
            "temporary folder): set NUMBA_CACHE_DIR to a writable folder"
        )
    logging.getLogger(__name__).warning(
        "bouncing_ball: %s and %s cannot be written to; numba caches compiled code in %s "
        "(set NUMBA_CACHE_DIR to a writable folder to keep it)",
        preferred,
        fallback if fallback is not None else "the user's cache folder (no HOME)",
        temporary,
    )
    return temporary


class RecoveringFunctionCache(FunctionCache):
    """numba's cache of one function, with a damaged cache file taken as a cache miss.

    ``njit`` gives every cached function this class.  A damaged index (a truncated write, a
    full disk) is reported with its folder and removed, and the function recompiled, where
    numba would raise ``UnpicklingError`` in every job.

    Parameters
    ----------
    py_func : function
        The Python function compiled (as for ``numba.core.caching.FunctionCache``).
    """

    def load_overload(self, sig, target_context):
        """The cached overload of ``sig``, or None (a cache miss) where the cache is damaged."""
        try:
            return super().load_overload(sig, target_context)
        except Exception as error:  # a damaged pickle raises almost anything
            index = Path(self._cache_file._index_path)
            logging.getLogger(__name__).warning(
                "numba's cache of %s in %s is damaged (%s: %s): removing its index and "
                "recompiling (if this repeats, delete that folder)",
                f"{self._py_func.__module__}.{self._py_func.__qualname__}",
                self._cache_path,
                type(error).__name__,
                error,
            )
            index.unlink(missing_ok=True)
            return None


def njit(*args, **options):
    """``numba.njit`` with IEEE division and a cache that survives a damaged file.

    IEEE division gives inf or NaN instead of a Python ZeroDivisionError check on every
    division: the compiled code tests its own denominators, as the C reference of the loop
    does.  The compiled function keeps the Python function's docstring.

    Parameters
    ----------
    *args
        The function, when used as ``@njit`` without options.
    **options
        Options of ``numba.njit`` (e.g. ``cache=True``, ``inline="always"``).

    Returns
    -------
    numba dispatcher, or a decorator that makes one
        Compiled on its first call.

    Raises
    ------
    TypeError
        If options are given other than by keyword.
    """

    def compile_lazily(function):
        dispatcher = numba.njit(error_model="numpy", **options)(function)
        if isinstance(getattr(dispatcher, "_cache", None), FunctionCache):
            dispatcher._cache.__class__ = RecoveringFunctionCache
        return dispatcher

    if len(args) == 1 and callable(args[0]):
        return compile_lazily(args[0])
    if args:
        raise TypeError("bouncing_ball.jit.njit takes keyword options only")
    return compile_lazily


def fma(a, b, c):
    """a b + c rounded once: the fused multiply-add of IEEE 754, the same on every machine.

    Compiled code gets LLVM's ``llvm.fma.f64``: the processor's fused multiply-add
    instruction, or the C library's correctly rounded ``fma`` where it has none.  Being
    correctly rounded, it gives the same double everywhere, unlike a compiler's choice to
    contract a b + c (fast-math or ``contract`` flags, never used here): the shard loop
    writes each fused multiply-add where it wants one, and its C reference calls ``fma()``
    at the same places.  Called from Python (the ``py_func`` of a compiled function), it
    rounds the exact rational a b + c once.

    Parameters
    ----------
    a, b, c : float
        The factors and the addend.

    Returns
    -------
    float
        a b + c, rounded to the nearest double (ties to even).

    Examples
    --------
    (1 + 2^-52)(1 - 2^-52) = 1 - 2^-104 exactly: the product rounded first is 1, fused it is
    not.

    >>> from bouncing_ball.jit import fma
    >>> a, b = 1.0 + 2.0**-52, 1.0 - 2.0**-52
    >>> a * b - 1.0, fma(a, b, -1.0) == -(2.0**-104)
    (0.0, True)
    """
    a, b, c = float(a), float(b), float(c)
    if not (math.isfinite(a) and math.isfinite(b)):
        return a * b + c  # the product is an infinity or a NaN: so is a b + c
    if not math.isfinite(c):
        return c  # a finite product (however large) added to an infinity or a NaN
    exact = Fraction(a) * Fraction(b) + Fraction(c)
    if exact == 0:
        return a * b + c  # a b = -c exactly: IEEE 754's sign of a zero sum
    try:
        return float(exact)  # int / int: correctly rounded
    except OverflowError:
        return math.inf if exact > 0 else -math.inf


@intrinsic
def _llvm_fma(typingctx, a, b, c):
    """``llvm.fma.f64`` on three doubles."""
    if not all(isinstance(value, types.Float) and value.bitwidth == 64 for value in (a, b, c)):
        return None
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, sig, args):
        return builder.fma(*args)

    return signature, codegen


@overload(fma, jit_options={"error_model": "numpy"})
def _fma_compiled(a, b, c):
    if all(isinstance(value, types.Float) and value.bitwidth == 64 for value in (a, b, c)):
        return lambda a, b, c: _llvm_fma(a, b, c)
    return None


def flag_is_set(flag):
    """Whether ``flag[0]`` is nonzero, read afresh however often compiled code asks.

    ``flag`` is a one-element int64 array that another thread may set while compiled code
    runs (a request to stop, ``simulation.ShardStop``).  Compiled code reads it at every call
    by an atomic (monotonic) load: a plain read of memory that nothing in a loop writes may
    be made once, before the loop, by the optimiser.

    Parameters
    ----------
    flag : numpy.ndarray
        One-element int64 array.

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.jit import flag_is_set
    >>> flag = np.zeros(1, dtype=np.int64)
    >>> flag_is_set(flag), flag_is_set(flag + 1)
    (False, True)
    """
    return bool(flag[0])


@intrinsic
def _atomic_first_element(typingctx, flag):
    """The first element of an int64 array, by an atomic load of monotonic ordering."""
    if not (isinstance(flag, types.Array) and flag.dtype == types.int64):
        return None
    signature = types.int64(flag)

    def codegen(context, builder, sig, args):
        array = context.make_array(sig.args[0])(context, builder, args[0])
        return builder.load_atomic(array.data, ordering="monotonic", align=8)

    return signature, codegen


@overload(flag_is_set)
def _flag_is_set_compiled(flag):
    if isinstance(flag, types.Array) and flag.dtype == types.int64:
        return lambda flag: _atomic_first_element(flag) != 0
    return None


#: What numba compiles: the modules with compiled functions and what those call into or read
#: constants from (the key of numba's cache folder), each a file (a module of a subpackage by
#: its dotted name); an edit elsewhere does not recompile.
COMPILED = (
    "distribution.complex_kernel",
    "distribution.ray_density",
    "free_flight",
    "jit",
    "kernel",
    "pcg64",
    "simulation.loop",
    "simulation.step_tallies",
    "solver",
    "tallies",
)

_preferred = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else PACKAGE / "__pycache__"
_base = cache_base(_preferred)
#: numba's cache folder, named after the source of the modules of ``COMPILED``.
CACHE = _base / f"numba-{source_digest(COMPILED)}"
numba.config.CACHE_DIR = str(CACHE)
with contextlib.suppress(OSError):  # not there yet, or not ours to touch (a read-only cache)
    os.utime(CACHE)  # in use: the newest to keep
prune_caches(_base, CACHE)
prange = numba.prange
