"""Parquet tables with provenance, written atomically, read with errors that name the file.

Provenance (r, the seed, the settings, the package version, ...) is stored as JSON under the
key ``bouncing_ball`` of the Parquet key-value metadata.  A table is a pandas frame or a
pyarrow table.  The library's files (``SimulationResult.save``) and the workflow's
(``workflow.io``, which adds the workflow's kinds of table and its remedies) are written and
read here.
"""

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from . import __version__

__all__ = [
    "METADATA_KEY",
    "UnreadableFileError",
    "atomic_paths",
    "with_provenance",
    "write_tables",
    "write_table",
    "read_parquet",
    "provenance_of",
    "read_provenance",
]

METADATA_KEY = b"bouncing_ball"


class UnreadableFileError(RuntimeError):
    """An input file is missing, truncated or not what it should be."""


@contextmanager
def atomic_paths(*paths):
    """Temporary names next to ``paths`` to write to; all are renamed to ``paths`` only
    if the block finishes, all removed otherwise: a reader never sees a half-written
    file, and a rule's outputs appear together or not at all."""
    paths = [Path(path) for path in paths]
    temporaries = []
    try:
        for path in paths:
            path.parent.mkdir(parents=True, exist_ok=True)
            for stale in path.parent.glob(f".{path.stem}.*{path.suffix}"):
                # left by a writer that was killed (SIGKILL skips the cleanup below)
                stale.unlink(missing_ok=True)
            handle, temporary = tempfile.mkstemp(
                prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent
            )
            os.close(handle)
            temporaries.append(temporary)
            # mkstemp makes the file private (0600); a result gets the mode the user's
            # umask gives any new file (0644 under umask 022), so colleagues can read it
            os.chmod(temporary, 0o666 & ~_umask())
        yield temporaries
    except BaseException:
        for temporary in temporaries:
            Path(temporary).unlink(missing_ok=True)
        raise
    renamed = []
    try:
        for temporary, path in zip(temporaries, paths, strict=True):
            os.replace(temporary, path)
            renamed.append(path)
    except BaseException:
        # a rename failed (e.g. a directory where a file should go): take back the new
        # files already in place, so that none of the set is left without the others
        for path in renamed:
            path.unlink(missing_ok=True)
        for temporary in temporaries:
            Path(temporary).unlink(missing_ok=True)
        raise


def _umask() -> int:
    """The process's umask (reading it means setting it; set straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def with_provenance(frame, provenance: dict) -> pa.Table:
    """``frame`` (a pandas frame or a pyarrow table) as a pyarrow table carrying
    ``provenance`` and the package version as JSON under ``METADATA_KEY``."""
    table = (
        frame if isinstance(frame, pa.Table) else pa.Table.from_pandas(frame, preserve_index=False)
    )
    metadata = dict(table.schema.metadata or {})
    metadata[METADATA_KEY] = json.dumps(
        {"package_version": __version__, **provenance}, sort_keys=True, default=str
    ).encode()
    return table.replace_schema_metadata(metadata)


def write_tables(frames: dict, provenance: dict) -> None:
    """Write each frame of ``{path: frame}`` with ``provenance``; all or none of them
    appear (``atomic_paths``), as a rule's outputs should."""
    tables = [with_provenance(frame, provenance) for frame in frames.values()]
    with atomic_paths(*frames) as temporaries:
        for table, temporary in zip(tables, temporaries, strict=True):
            pq.write_table(table, temporary)


def write_table(frame, path, provenance: dict) -> None:
    """Write ``frame`` (a pandas frame or a pyarrow table) to ``path`` with ``provenance``;
    atomic (temp file, then rename)."""
    write_tables({path: frame}, provenance)


def read_parquet(read, path: Path, remedy: str = ""):
    """``read(path)`` (pyarrow's ``read_table`` or ``read_schema``), its failures an
    ``UnreadableFileError`` naming the file, with ``remedy`` (what to do) appended."""
    try:
        return read(path)
    except FileNotFoundError:
        raise UnreadableFileError(f"{path}: file not found") from None
    except (pa.ArrowException, OSError) as error:
        raise UnreadableFileError(
            f"{path}: not a readable Parquet file ({error}){remedy}"
        ) from None


def provenance_of(path, schema, remedy: str = "") -> dict:
    """The provenance in ``schema`` (the schema of the file ``path``); an
    ``UnreadableFileError`` naming the file, with ``remedy`` appended, when it has none."""
    raw = (schema.metadata or {}).get(METADATA_KEY)
    if raw is None:
        raise UnreadableFileError(
            f"{path}: no '{METADATA_KEY.decode()}' provenance metadata: not written by "
            f"bouncing_ball{remedy}"
        )
    try:
        provenance = json.loads(raw)
    except ValueError as error:
        raise UnreadableFileError(f"{path}: its provenance is not JSON ({error}){remedy}") from None
    if not isinstance(provenance, dict):
        raise UnreadableFileError(f"{path}: its provenance is not a JSON object{remedy}")
    return provenance


def read_provenance(path) -> dict:
    """The provenance of a table written by ``write_table``, without reading its data."""
    path = Path(path)
    return provenance_of(path, read_parquet(pq.read_schema, path))
