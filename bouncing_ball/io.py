"""Parquet tables with provenance, written atomically, read with clear errors.

Provenance (r, the rule's parameters, seed, package version) is stored as
JSON under the key ``bouncing_ball`` of the Parquet key-value metadata.
"""

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from . import __version__

METADATA_KEY = b"bouncing_ball"


class UnreadableFileError(RuntimeError):
    """An input file is missing, truncated or not what it should be."""


@contextmanager
def atomic_path(path):
    """A temporary name next to ``path`` to write to; renamed to ``path`` only if the
    block finishes, removed otherwise, so a reader never sees a half-written file."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in path.parent.glob(f".{path.stem}.*{path.suffix}"):
        stale.unlink(
            missing_ok=True
        )  # left by a writer that was killed (SIGKILL skips the cleanup below)
    handle, temporary = tempfile.mkstemp(
        prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent
    )
    os.close(handle)
    try:
        yield temporary
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def write_table(frame: pd.DataFrame, path, provenance: dict) -> None:
    """Write ``frame`` to ``path`` with ``provenance``; atomic (temp file, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pandas(frame, preserve_index=False)
    metadata = dict(table.schema.metadata or {})
    metadata[METADATA_KEY] = json.dumps(
        {"package_version": __version__, **provenance}, sort_keys=True, default=str
    ).encode()
    table = table.replace_schema_metadata(metadata)
    with atomic_path(path) as temporary:
        pq.write_table(table, temporary)


def read_table(path) -> tuple[pd.DataFrame, dict]:
    """The frame and provenance of a table written by ``write_table``."""
    path = Path(path)
    try:
        table = pq.read_table(path)
    except FileNotFoundError:
        raise UnreadableFileError(f"{path}: file not found") from None
    except (pa.ArrowException, OSError) as error:
        raise UnreadableFileError(
            f"{path}: not a readable Parquet file ({error}). It is probably truncated or "
            f"corrupt: make it again with  snakemake --cores 2 --forcerun {path}  (plus your targets)"
        ) from None
    raw = (table.schema.metadata or {}).get(METADATA_KEY)
    if raw is None:
        raise UnreadableFileError(
            f"{path}: no '{METADATA_KEY.decode()}' provenance metadata: not written by this workflow; "
            f"make it again with  snakemake --cores 2 --forcerun {path}"
        )
    return table.to_pandas(), json.loads(raw)


def require_columns(frame: pd.DataFrame, path, columns) -> pd.DataFrame:
    """``frame`` if it has ``columns``; otherwise an error naming the file and what is missing."""
    missing = [column for column in columns if column not in frame.columns]
    if missing:
        raise UnreadableFileError(
            f"{path}: not the expected table, it lacks the columns {', '.join(missing)}"
        )
    return frame


def read_tables_of_one_restitution(*paths) -> list[tuple[pd.DataFrame, dict]]:
    """``read_table`` of each path, refused unless all were made for the same r
    (e.g. the simulation, solver and fits that one figure panel compares)."""
    tables = [read_table(path) for path in paths]
    values = [provenance.get("r") for _, provenance in tables]
    if len(set(values)) > 1:
        which = ", ".join(
            f"{path} (r = {value})" for path, value in zip(paths, values, strict=True)
        )
        raise UnreadableFileError(f"not the same r: {which}")
    return tables


def write_csv_and_markdown(table: pd.DataFrame, csv_path, markdown_path, markdown: str) -> None:
    """A results table as CSV (12 significant digits) and its Markdown rendering, each atomic."""
    with atomic_path(csv_path) as path:
        table.to_csv(path, index=False, float_format="%.12g")
    with atomic_path(markdown_path) as path:
        Path(path).write_text(markdown)
