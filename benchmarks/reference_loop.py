"""A plain C reference of the shard loop: build it, run one shard with it.

``reference/shard_loop.c`` translates the compiled loop ``simulation.loop._run``
and the free-flight functions it calls, operation for operation, and draws its
normals with numpy's own C ziggurat (``random_standard_normal`` of
libnpyrandom.a) from the same PCG64 stream as ``simulate_shard``; so on the
same seed sequence ``reference_shard`` returns the same tallies.  It records
every tally, as ``simulate_shard`` does by default (``parts=EVERY_TALLY``; the
C loop has no ``parts`` mask).  It is the yardstick of the performance target
(numba at >= 90 % of a plain C loop) and a cross-check of the compiled code;
the workflow does not use it.

``build`` compiles it with gcc (-O3 -march=native, and -ffp-contract=off:
numba fuses a multiply-add only where the Python calls ``jit.fma``, and the C calls
``fma()`` at the same places, so gcc must fuse no other; the scalars' layout of
``tallies.SCALARS`` as -D flags, ``scalar_layout_flags``) into a folder
keyed on the hash of the C source and the whole compiler command, compiling
only when that folder lacks the library and writing it atomically.  This
module imports numpy and the library's light modules only, never numba.
"""

import ctypes
import functools
import hashlib
import os
import shutil
import subprocess
import sysconfig
import tempfile
from dataclasses import fields
from pathlib import Path

import numpy as np

from bouncing_ball.settings import ShardSettings, return_law_speed_bins
from bouncing_ball.tallies import (
    BINS,
    EARLY_FRACTION,
    SCALARS,
    ShardTallies,
    tally_seed_sequence,
)

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "reference" / "shard_loop.c"
COMPILER = "gcc"
FLAGS = ("-O3", "-march=native", "-ffp-contract=off", "-fPIC", "-shared", "-std=c99")
LIBRARY_NAME = "shard_loop.so"
FUNCTION = "bouncing_ball_shard_loop"


def npyrandom_library() -> Path:
    """numpy's static library of C distributions (random_standard_normal and co.)."""
    path = Path(os.path.dirname(np.__file__)) / "random" / "lib" / "libnpyrandom.a"
    if not path.is_file():
        raise RuntimeError(f"numpy's C random library is missing: {path}")
    return path


def scalar_layout_flags() -> list[str]:
    """``-DSCALAR_<NAME>=<index>`` for each scalar of ``tallies.SCALARS``, and
    ``-DEARLY_FRACTION``: the C reference reads the layout of its scalar array from these, so
    it has one definition (``float.hex``: the same double)."""
    return [
        *(f"-DSCALAR_{name.upper()}={index}" for index, name in enumerate(SCALARS)),
        f"-DEARLY_FRACTION={EARLY_FRACTION.hex()}",
    ]


def compile_command(source: Path, output: Path) -> list[str]:
    """The gcc command that builds ``source`` into the shared library ``output``."""
    return [
        COMPILER,
        *FLAGS,
        *scalar_layout_flags(),
        f"-I{np.get_include()}",
        f"-I{sysconfig.get_paths()['include']}",  # numpy's headers include Python.h
        str(source),
        str(npyrandom_library()),
        "-lm",
        "-o",
        str(output),
    ]


def cache_key(source_text: bytes, command: list[str]) -> str:
    """Hash of the C source and of the compiler command (flags, include and library paths)."""
    digest = hashlib.sha256()
    digest.update(source_text)
    digest.update(b"\0")
    digest.update("\0".join(command).encode())
    return digest.hexdigest()[:16]


def build_shared_library(source: Path, compile_command, prefix: str, directory=None) -> Path:
    """Compile ``source`` with ``compile_command(source, output)`` (if not cached yet) and
    return the shared library's path: ``<directory>/<prefix>-<key>/<LIBRARY_NAME>``,
    ``directory`` defaulting to this folder's __pycache__ and ``<key>`` hashing the source
    and the compiler command, so an edit of the C file builds into a new folder.  Raises
    RuntimeError where the compiler is missing or the compile fails."""
    base = Path(directory) if directory is not None else HERE / "__pycache__"
    if shutil.which(COMPILER) is None:
        raise RuntimeError(
            f"the C compiler '{COMPILER}' was not found on PATH; it is needed to build {source.name}"
        )
    text = source.read_bytes()
    # the key is computed on a placeholder output name, so that it does not depend on itself
    key = cache_key(text, compile_command(Path(source.name), Path(LIBRARY_NAME)))
    folder = base / f"{prefix}-{key}"
    library = folder / LIBRARY_NAME
    if library.is_file():
        return library
    folder.mkdir(parents=True, exist_ok=True)
    # compile a snapshot of the text that was hashed, to a temporary name, then rename
    with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as scratch:
        snapshot = Path(scratch) / source.name
        snapshot.write_bytes(text)
        temporary = Path(scratch) / LIBRARY_NAME
        result = subprocess.run(
            compile_command(snapshot, temporary), capture_output=True, text=True
        )
        if result.returncode != 0:
            raise RuntimeError(f"compiling {source} failed:\n{result.stderr}")
        os.replace(temporary, library)
    return library


def build(directory=None, source=None) -> Path:
    """Compile the C reference (if not cached yet) and return the shared library's path,
    ``<directory>/reference-<key>/shard_loop.so`` (``build_shared_library``).
    ``source`` defaults to reference/shard_loop.c beside this module.
    """
    source = Path(source) if source is not None else SOURCE
    return build_shared_library(source, compile_command, "reference", directory)


_double_array = np.ctypeslib.ndpointer(dtype=np.float64, ndim=1, flags="C_CONTIGUOUS")
_int64_array = np.ctypeslib.ndpointer(dtype=np.int64, ndim=1, flags="C_CONTIGUOUS")


@functools.cache
def _load(library: str):
    function = getattr(ctypes.CDLL(library), FUNCTION)
    function.restype = ctypes.c_int
    function.argtypes = [
        ctypes.c_void_p,  # bitgen_t *
        ctypes.c_void_p,  # bitgen_t * of the P(x, v) draws
        ctypes.c_double,  # restitution
        ctypes.c_double,  # c
        ctypes.c_double,  # min_step_divisor
        ctypes.c_double,  # min_step_floor
        ctypes.c_double,  # equilibration_time
        ctypes.c_double,  # recorded_time
        ctypes.c_int64,  # max_steps
        _double_array,  # v_edges
        ctypes.c_int64,  # nv
        _double_array,  # x_edges
        ctypes.c_int64,  # nx
        _double_array,  # u_edges (velocities of P(x, v))
        ctypes.c_int64,  # nu
        _double_array,  # f_edges (flight times)
        ctypes.c_int64,  # nf
        _double_array,  # w_edges (outgoing speeds, fine)
        ctypes.c_int64,  # nw
        _int64_array,  # speed_counts
        _double_array,  # position_time
        _double_array,  # position_v2_time
        _int64_array,  # flight_time_counts
        _double_array,  # position_velocity_time, row-major
        _int64_array,  # return_speed_counts, row-major
        _int64_array,  # return_law_speed_counts
        _double_array,  # bounce_lag_sums, row-major
        ctypes.c_int64,  # lags 0 .. BOUNCE_LAGS: their number
        _double_array,  # scalars
    ]
    return function


def reference_shard(
    restitution: float,
    seed_sequence: np.random.SeedSequence,
    settings: ShardSettings,
    library=None,
) -> ShardTallies:
    """``simulation.simulate_shard`` with every tally (its default ``parts``), run by the C
    reference (``library``: a built shared library, by default ``build()``)."""
    if not 0.0 < restitution < 1.0:
        raise ValueError(f"restitution must lie in (0, 1), got {restitution}")
    function = _load(str(library if library is not None else build()))
    # both kept alive across the call
    bit_generator = np.random.PCG64(seed_sequence)
    tally_bit_generator = np.random.PCG64(tally_seed_sequence(seed_sequence))
    edges = {
        name: np.ascontiguousarray(getattr(settings, name).edges, dtype=np.float64) for name in BINS
    }
    arrays = ShardTallies.loop_arrays(settings)
    status = function(
        bit_generator.ctypes.bit_generator,
        tally_bit_generator.ctypes.bit_generator,
        float(restitution),
        settings.criterion_c,
        settings.min_step_divisor,
        settings.min_step_floor,
        settings.equilibration_time,
        settings.shard_time,
        settings.max_steps,
        edges["speed_bins"],
        settings.speed_bins.n,
        edges["position_bins"],
        settings.position_bins.n,
        edges["velocity_bins"],
        settings.velocity_bins.n,
        edges["flight_time_bins"],
        settings.flight_time_bins.n,
        np.ascontiguousarray(return_law_speed_bins(settings.speed_bins).edges, dtype=np.float64),
        return_law_speed_bins(settings.speed_bins).n,
        arrays["speed_counts"],
        arrays["position_time"],
        arrays["position_v2_time"],
        arrays["flight_time_counts"],
        arrays["position_velocity_time"].ravel(),  # C-contiguous: a view
        arrays["return_speed_counts"].ravel(),
        arrays["return_law_speed_counts"],
        arrays["bounce_lag_sums"].ravel(),  # C-contiguous: a view
        arrays["bounce_lag_sums"].shape[1],
        arrays["scalars"],
    )
    if status != 0:
        raise MemoryError("the C reference could not allocate its bin bounds")
    return ShardTallies.from_loop(settings, arrays)


# what a shard records (its bins aside): every one must agree bit for bit
TALLY_FIELDS = tuple(field.name for field in fields(ShardTallies) if field.name not in BINS)


def differing_tallies(first: ShardTallies, second: ShardTallies) -> list[str]:
    """The tally fields in which two shards' results differ (bit for bit); [] if none."""
    return [
        name
        for name in TALLY_FIELDS
        if not np.array_equal(getattr(first, name), getattr(second, name))
    ]
