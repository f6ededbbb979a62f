"""numba's cache folders: keyed on the source, old ones pruned; the fused multiply-add."""

import os
import platform
import subprocess
import sys
import time

import numpy as np
import pytest

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
    """A module that numba compiles (an @njit function), a subpackage's included by its dotted
    name, must be in jit.COMPILED, else an edit of it would be served stale code from the cache."""
    compiled = {
        ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
        for path in PACKAGE.rglob("*.py")
        if "@njit" in path.read_text() or "njit(" in path.read_text()
    }
    assert {"kernel", "distribution.complex_kernel", "distribution.ray_density"} <= compiled
    assert compiled <= set(jit.COMPILED)


def test_a_checkout_that_cannot_be_written_caches_in_the_users_folder(tmp_path):
    """A read-only checkout recompiled in every shard (11.8 s against 0.5 s)."""
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the package's __pycache__ would be")
    fallback = tmp_path / "user-cache"
    assert jit.writable_cache_base(blocker / "__pycache__", fallback) == fallback
    assert jit.writable_cache_base(tmp_path / "writable", fallback) == tmp_path / "writable"
    assert jit.user_cache_folder().name == "bouncing_ball"


def _fma_cases():
    """(a, b, c) where a fused and an unfused multiply-add differ, where the sum cancels to
    zero, under- and overflows, and infinities and NaNs; and random doubles over 600 decades."""
    rng = np.random.default_rng(27)
    a = rng.uniform(-1.0, 1.0, 3000) * 10.0 ** rng.integers(-300, 300, 3000)
    b = rng.uniform(-1.0, 1.0, 3000) * 10.0 ** rng.integers(-8, 8, 3000)
    c = -(a * b) * (1.0 + rng.uniform(-1e-12, 1e-12, 3000))  # heavy cancellation
    c[::3] = rng.normal(size=1000)  # and ordinary addends
    c[1::3] = -(a[1::3] * b[1::3])  # and a b rounded: fused leaves its rounding error
    special = [
        (1.0 + 2.0**-52, 1.0 - 2.0**-52, -1.0),  # fused -2^-104, unfused 0
        (0.1, 10.0, -1.0),  # 0.1 * 10 rounds to 1
        (-0.0, 1.0, -0.0),  # a negative zero sum stays negative
        (0.0, -1.0, 0.0),
        (1e-200, 1e-200, 0.0),  # underflows to 0
        (1e-160, 1e-160, 0.0),  # subnormal
        (1e200, 1e200, -np.inf),
        (1e200, 1e200, 0.0),  # overflows to inf
        (np.inf, 0.0, 1.0),
        (np.inf, 1.0, -np.inf),
        (np.nan, 1.0, 1.0),
    ]
    a, b, c = (
        np.concatenate([column, [case[k] for case in special]])
        for k, column in enumerate((a, b, c))
    )
    return a, b, c


@jit.njit
def _compiled_fma(a, b, c):
    out = np.empty_like(a)
    for i in range(a.shape[0]):
        out[i] = jit.fma(a[i], b[i], c[i])
    return out


def _same_doubles(first, second):
    """Bit for bit, a NaN for any NaN."""
    both_nan = np.isnan(first) & np.isnan(second)
    return np.array_equal(first.view(np.int64)[~both_nan], second.view(np.int64)[~both_nan])


def test_fma_rounds_once():
    a, b = 1.0 + 2.0**-52, 1.0 - 2.0**-52
    assert a * b - 1.0 == 0.0
    assert jit.fma(a, b, -1.0) == -(2.0**-104)
    assert _compiled_fma(np.array([a]), np.array([b]), np.array([-1.0]))[0] == -(2.0**-104)


def test_compiled_fma_is_the_python_fma_bit_for_bit():
    """llvm.fma.f64 and the exact rational rounded once (the py_func path) agree everywhere,
    and differ from the unfused a b + c where that rounds twice."""
    a, b, c = _fma_cases()
    compiled = _compiled_fma(a, b, c)
    in_python = np.array([jit.fma(*case) for case in zip(a, b, c)])
    assert _same_doubles(compiled, in_python)
    assert np.signbit(compiled[-9]) and not np.signbit(compiled[-8])  # -0 + -0, 0 + 0
    assert np.count_nonzero(compiled[:-11] != a[:-11] * b[:-11] + c[:-11]) > 1000


FMA_ON_A_GENERIC_CPU = """
import sys
import numpy as np
from bouncing_ball import jit

@jit.njit
def fused(a, b, c):
    out = np.empty_like(a)
    for i in range(a.shape[0]):
        out[i] = jit.fma(a[i], b[i], c[i])
    return out

a, b, c = (np.load(sys.argv[1])[k] for k in range(3))
np.save(sys.argv[2], fused(a, b, c))
print(fused.inspect_asm(fused.signatures[0]).count("vfmadd"))
"""


@pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64"), reason="an x86-64 CPU name")
def test_fma_gives_the_same_doubles_on_a_cpu_without_fused_multiply_add(tmp_path):
    """Compiled for the baseline x86-64 (no FMA instruction) LLVM calls the C library's fma:
    the same doubles as this machine's instruction, so results do not depend on the CPU."""
    cases = tmp_path / "cases.npy"
    np.save(cases, np.stack(_fma_cases()))
    environment = dict(
        os.environ,
        NUMBA_CPU_NAME="generic",
        NUMBA_CACHE_DIR=str(tmp_path / "cache"),
        PYTHONPATH=os.pathsep.join([str(PACKAGE.parent), os.environ.get("PYTHONPATH", "")]),
    )
    result = subprocess.run(
        [sys.executable, "-c", FMA_ON_A_GENERIC_CPU, str(cases), str(tmp_path / "out.npy")],
        env=environment,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "0"  # no FMA instruction: the library's fma
    assert _same_doubles(np.load(tmp_path / "out.npy"), _compiled_fma(*_fma_cases()))
