"""Equilibrium statistics of an inelastically bouncing ball (Burkhardt & Kotsev 2006)."""

import hashlib
from pathlib import Path

__version__ = "0.2.0"

PACKAGE = Path(__file__).parent


def source_digest(modules=None, files=()) -> str:
    """A short hash of the source of the named modules of this package (all if None),
    and of ``files`` (a rule's script).

    The workflow passes it to its rules as a parameter, so that editing the
    code behind a stage re-runs that stage and nothing else, and touching a
    file without changing it re-runs nothing.
    """
    names = (
        sorted(path.stem for path in PACKAGE.glob("*.py")) if modules is None else sorted(modules)
    )
    digest = hashlib.sha256()
    for name in names:
        digest.update(name.encode())
        digest.update((PACKAGE / f"{name}.py").read_bytes())
    for path in files:
        digest.update(Path(path).name.encode())
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()[:16]
