"""Equilibrium statistics of an inelastically bouncing ball (Burkhardt & Kotsev 2006).

The public API:

- ``Equilibrium(r)``: the equilibrium state at any r the solver answers (eq. (inteq)): the
  time averages, the exponents, P(0, v), P(x), <v^2>_x, P(x, v), w(F), the flight times;
- ``ExactEquilibrium(r)``: the paper's exact r = 1/2 and 1/3 solutions; both are
  ``EquilibriumBase``, with the same methods and signatures;
- ``simulate(r, shards=..., shard_time=...)``: the Monte Carlo simulation of the paper's
  Sec. IV, returning a ``SimulationResult`` with the same observables and their errors;
  ``SimulationResult.save(path)`` writes it to a Parquet file and ``load(path)`` reads it back.
- ``compare(equilibrium, result)``: the simulation against the equilibrium, z-scores and
  chi^2 per bin with their sign-flip p-values.

They are loaded on first use, so that ``import bouncing_ball`` (as the workflow does to plan a
run) loads neither numba nor scipy.
"""

import hashlib
from pathlib import Path

__version__ = "0.4.0"

PACKAGE = Path(__file__).parent

__all__ = [
    "EquilibriumBase",
    "Equilibrium",
    "ExactEquilibrium",
    "simulate",
    "SimulationResult",
    "SimulationInterrupted",
    "load",
    "compare",
    "PACKAGE",
    "source_digest",
    "__version__",
]

# public name -> the module that defines it (imported on first access, PEP 562)
_LAZY = {
    "EquilibriumBase": "equilibrium",
    "Equilibrium": "equilibrium",
    "ExactEquilibrium": "equilibrium",
    "simulate": "simulation",
    "SimulationResult": "simulation",
    "SimulationInterrupted": "simulation",
    "load": "simulation",
    "compare": "validation",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))


def _module_files(name) -> list:
    """The source files of a module of this package, dotted below it: its .py file, or every
    .py file of a subpackage (``"distribution"``: its __init__ and each of its modules)."""
    path = PACKAGE.joinpath(*name.split("."))
    return sorted(path.rglob("*.py")) if path.is_dir() else [path.with_suffix(".py")]


def source_digest(modules=None, files=()) -> str:
    """A short hash of the source of the named modules of this package (all if None), dotted
    below it (``"solver"``, ``"workflow.io"``; a subpackage's name, ``"distribution"``, covers
    every file of it), and of ``files`` (a rule's script).

    The workflow passes it to its rules as a parameter, so that editing the
    code behind a stage re-runs that stage and nothing else, and touching a
    file without changing it re-runs nothing.
    """
    paths = (
        sorted(PACKAGE.rglob("*.py"))
        if modules is None
        else [path for name in sorted(modules) for path in _module_files(name)]
    )
    digest = hashlib.sha256()
    for path in paths:
        digest.update(".".join(path.relative_to(PACKAGE).with_suffix("").parts).encode())
        digest.update(path.read_bytes())
    for path in files:
        digest.update(Path(path).name.encode())
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()[:16]
