"""Parquet tables with provenance, written atomically, read with errors that name the file.

Provenance (r, the seed, the settings, the package version, ...) is stored as JSON under the
key ``bouncing_ball`` of the Parquet key-value metadata.  A table is a pandas frame or a
pyarrow table.  The library's files (``SimulationResult.save``) and the workflow's
(``workflow.io``, which adds the workflow's kinds of table and its remedies) are written and
read here.

Examples
--------
A table written with its provenance, read back with it:

>>> import tempfile, pathlib
>>> import pandas as pd
>>> import pyarrow.parquet as pq
>>> from bouncing_ball.parquet import read_parquet, read_provenance, write_table
>>> path = pathlib.Path(tempfile.mkdtemp()) / "table.parquet"
>>> write_table(pd.DataFrame({"v": [0.5, 1.0]}), path, {"r": "1/2"})
>>> read_provenance(path)["r"], read_parquet(pq.read_table, path).num_rows
('1/2', 2)
"""

import glob
import hashlib
import json
import os
import re
import socket
import tempfile
import time
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
    """Temporary names next to ``paths`` to write to, renamed to ``paths`` at the end.

    All are renamed to ``paths`` only if the block finishes, all removed otherwise: a reader
    never sees a half-written file, and a rule's outputs appear together or not at all.

    Parameters
    ----------
    *paths : str or os.PathLike
        The files to write; their folders are made if missing.

    Returns
    -------
    contextmanager
        Yields the list of temporary paths (str), one per path, in order.
    """
    paths = [Path(path) for path in paths]
    temporaries = []
    try:
        for path in paths:
            path.parent.mkdir(parents=True, exist_ok=True)
            _remove_stale_temporaries(path)
            handle, temporary = tempfile.mkstemp(
                prefix=_temporary_prefix(path),
                suffix=f"{TEMPORARY_MARK}{path.suffix}",
                dir=path.parent,
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


#: What ends a temporary's name before the target's suffix: ``.{name}.{host}.{pid}.{random}.tmp``
#: followed by the suffix (kept, so that a writer that goes by it, e.g. matplotlib, sees it).
TEMPORARY_MARK = ".tmp"
#: Seconds after which a temporary of another host's writer counts as stale (its pid means
#: nothing here): no write of one file takes that long.
STALE_AGE = 86400.0


def _host_tag() -> str:
    """8 hex digits of this machine's name: which host a temporary's pid belongs to."""
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


def _temporary_prefix(path: Path) -> str:
    return f".{path.name}.{_host_tag()}.{os.getpid()}."


def _temporary_pattern(path: Path):
    """The names of ``path``'s temporaries and of no other target's: the whole name of the
    target, then host, pid and mkstemp's random part (letters, digits, '_': no dot)."""
    return re.compile(
        rf"\.{re.escape(path.name)}\.([0-9a-f]{{8}})\.([0-9]+)\.[A-Za-z0-9_]+"
        rf"{re.escape(TEMPORARY_MARK + path.suffix)}"
    )


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. another user's process: alive
        return True
    return True


def _remove_stale_temporaries(path: Path) -> None:
    """Remove the temporaries of ``path`` left by a writer that was killed (SIGKILL skips the
    cleanup of ``atomic_paths``): only ``path``'s own (never another target's, whatever its
    name), and only those whose writer is gone: on this host a pid that no longer runs, of
    another host one older than ``STALE_AGE``.  A writer of the same file still at work keeps
    its temporary."""
    pattern, host = _temporary_pattern(path), _host_tag()
    for candidate in path.parent.glob(f".{glob.escape(path.name)}.*"):
        match = pattern.fullmatch(candidate.name)
        if match is None:
            continue
        if match.group(1) == host:
            gone = int(match.group(2)) != os.getpid() and not _process_alive(int(match.group(2)))
        else:
            try:
                gone = time.time() - candidate.stat().st_mtime > STALE_AGE
            except FileNotFoundError:
                continue
        if gone:
            candidate.unlink(missing_ok=True)


def _umask() -> int:
    """The process's umask (reading it means setting it; set straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def with_provenance(frame, provenance: dict) -> pa.Table:
    """A table carrying its provenance and the package version under ``METADATA_KEY``.

    Parameters
    ----------
    frame : pandas.DataFrame or pyarrow.Table
        The table (a frame's index is dropped).
    provenance : dict
        JSON-ready; a value JSON does not know is written as its ``str``.

    Returns
    -------
    pyarrow.Table
    """
    table = (
        frame if isinstance(frame, pa.Table) else pa.Table.from_pandas(frame, preserve_index=False)
    )
    metadata = dict(table.schema.metadata or {})
    metadata[METADATA_KEY] = json.dumps(
        {"package_version": __version__, **provenance}, sort_keys=True, default=str
    ).encode()
    return table.replace_schema_metadata(metadata)


def write_tables(frames: dict, provenance: dict) -> None:
    """Write each frame of ``{path: frame}`` with ``provenance``; all or none appear.

    Parameters
    ----------
    frames : dict
        ``{path: frame}``, each frame a pandas frame or a pyarrow table.
    provenance : dict
        As for ``with_provenance``.

    Returns
    -------
    None
    """
    tables = [with_provenance(frame, provenance) for frame in frames.values()]
    with atomic_paths(*frames) as temporaries:
        for table, temporary in zip(tables, temporaries, strict=True):
            pq.write_table(table, temporary)


def write_table(frame, path, provenance: dict) -> None:
    """Write ``frame`` to ``path`` with ``provenance``, atomically (temp file, then rename).

    Parameters
    ----------
    frame : pandas.DataFrame or pyarrow.Table
    path : str or os.PathLike
    provenance : dict
        As for ``with_provenance``.

    Returns
    -------
    None

    Examples
    --------
    See the module's example.
    """
    write_tables({path: frame}, provenance)


def read_parquet(read, path: Path, remedy: str = ""):
    """``read(path)``, its failures an ``UnreadableFileError`` naming the file.

    Parameters
    ----------
    read : callable
        ``pyarrow.parquet.read_table`` or ``read_schema``.
    path : pathlib.Path
    remedy : str, optional
        What to do about it, appended to the message.

    Returns
    -------
    pyarrow.Table or pyarrow.Schema
        What ``read`` returns.
    """
    try:
        return read(path)
    except FileNotFoundError:
        raise UnreadableFileError(f"{path}: file not found") from None
    except (pa.ArrowException, OSError) as error:
        raise UnreadableFileError(
            f"{path}: not a readable Parquet file ({error}){remedy}"
        ) from None


def provenance_of(path, schema, remedy: str = "") -> dict:
    """The provenance in ``schema``, the schema of the file ``path``.

    Parameters
    ----------
    path : pathlib.Path
        The file, named in the error.
    schema : pyarrow.Schema
    remedy : str, optional
        Appended to the error's message.

    Returns
    -------
    dict
        The provenance; ``UnreadableFileError`` naming the file when there is none, or it
        is not a JSON object.
    """
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
    """The provenance of a table written by ``write_table``, without reading its data.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    dict

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import pandas as pd
    >>> from bouncing_ball.parquet import read_provenance, write_table
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "table.parquet"
    >>> write_table(pd.DataFrame({"v": [0.5]}), path, {"r": "1/2"})
    >>> read_provenance(path)["r"]
    '1/2'
    """
    path = Path(path)
    return provenance_of(path, read_parquet(pq.read_schema, path))
