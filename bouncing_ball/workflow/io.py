"""The workflow's tables: Parquet with provenance (``bouncing_ball.parquet``), each of a kind
(``TableKind``: the rule that writes it and its columns), read with errors that name the file
and say how to make it again.

Provenance (r, the rule's parameters, seed, package version) is stored as
JSON under the key ``bouncing_ball`` of the Parquet key-value metadata.  A table is a pandas
frame or a pyarrow table (a simulation job's batch of shards, written and read without
pandas).
"""

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pyarrow as pa
import pyarrow.parquet as pq

from ..parquet import (
    METADATA_KEY,
    UnreadableFileError,
    atomic_paths,
    provenance_of,
    read_parquet,
    write_table,
    write_tables,
)
from ..restitution import parse_restitution

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "METADATA_KEY",
    "UnreadableFileError",
    "atomic_paths",
    "write_tables",
    "write_table",
    "TableKind",
    "read_provenance",
    "read_arrow_table",
    "read_table",
    "require_columns",
    "read_tables_of_one_restitution",
    "comparison_panels",
    "write_csv_and_markdown",
]


@dataclass(frozen=True)
class TableKind:
    """A kind of table the workflow writes: the rule that writes it and its columns
    (docs/outputs.md); a reader names the kind it expects (``read_table``)."""

    name: str
    rule: str
    columns: tuple[str, ...]


_SUMMARY = ("r", "mean_x", "delta_x", "collision_rate")
SIMULATED_P0V = TableKind(
    "simulated P(0,v)", "merge_shards", ("v_lo", "v_hi", "v", "p0v", "p0v_err", "count")
)
SIMULATED_POSITION = TableKind(
    "simulated P(x)",
    "merge_shards",
    ("x_lo", "x_hi", "x", "px", "px_err", "v2_given_x", "v2_given_x_err"),
)
SIMULATED_SUMMARY = TableKind(
    "simulated summary",
    "merge_shards",
    (*_SUMMARY, "mean_x_err", "delta_x_err", "collision_rate_err"),
)
SIMULATED_DISTRIBUTION = TableKind(
    "simulated P(x,v)", "merge_shards", ("x_lo", "x_hi", "v_lo", "v_hi", "pxv", "pxv_err")
)
SIMULATED_FLIGHT_TIME = TableKind(
    "simulated flight-time", "merge_shards", ("t_lo", "t_hi", "t", "density", "density_err")
)
SIMULATED_RETURN_SPEED = TableKind(
    "simulated return-speed",
    "merge_shards",
    ("u_lo", "u_hi", "v_lo", "v_hi", "probability", "probability_err"),
)
SIMULATED_BOUNCE_CHAIN = TableKind(
    "simulated bounce chain",
    "merge_shards",
    (
        "lag",
        "autocorrelation",
        "autocorrelation_err",
        "principal_correlation",
        "principal_correlation_err",
        "decay_rate",
        "decay_rate_err",
        "relaxation_eigenvalue",
        "relaxation_eigenvalue_err",
        "first_lag",
        "last_lag",
    ),
)
RELAXATION = TableKind(
    "relaxation of the bounce chain",
    "relaxation",
    (
        "r",
        "relaxation_eigenvalue",
        "correlation_bounces",
        "bounce_chain_time",
        "relaxation_time",
        "simulated",
    ),
)
QUASI_ELASTIC_CURVES = TableKind(
    "P(0,v) in the quasi-elastic scaling",
    "quasi_elastic",
    ("r", "epsilon", "w", "scaled_p0v", "limit", "c1_measured", "c1_predicted"),
)
SOLVER_P0V = TableKind("solver P(0,v)", "solve", ("v", "p0v"))
SOLVER_POSITION = TableKind("solver P(x)", "solve", ("x", "px", "v2_given_x"))
SOLVER_DISTRIBUTION = TableKind("solver P(x,v)", "solve", ("x", "v", "pxv"))
SOLVER_FLIGHT_TIME = TableKind(
    "solver flight-time",
    "solve",
    ("t", "density", "rate_density", "short_time_form", "long_time_form"),
)
SOLVER_RETURN_SPEED = TableKind(
    "solver return-speed", "solve", ("u_lo", "u_hi", "v_lo", "v_hi", "probability")
)
EXACT_POSITION = TableKind("exact P(x)", "exact_solution", ("x", "px", "v2_given_x"))
SOLVER_SUMMARY = TableKind("solver summary", "solve", (*_SUMMARY, "small_speed_exponent"))
TIME_AVERAGES = TableKind("solver time averages", "solve_grid", _SUMMARY)
EXACT_P0V = TableKind("exact P(0,v)", "exact_solution", ("v", "p0v"))
EXACT_DISTRIBUTION = TableKind("exact P(x,v)", "exact_solution", ("x", "v", "pxv"))
EXACT_SUMMARY = TableKind("exact summary", "exact_solution", _SUMMARY)
EXPONENTS = TableKind("exponents", "theory", ("r", "beta", "m", "q"))
FITS = TableKind(
    "fits",
    "fit",
    (
        "source",
        "window",
        "fit",
        "parameter",
        "value",
        "error",
        "theory",
        "joint_p_value",
        "chi2_per_dof",
        "dof",
        "v_min",
        "v_max",
    ),
)


def _remake(path) -> str:
    """What to do about a workflow file that cannot be read: make it again."""
    return f"; make it again with  snakemake --cores 2 --forcerun {path}"


def _read_parquet(read, path: Path):
    """``parquet.read_parquet`` with the workflow's remedy: the file is made again."""
    return read_parquet(
        read,
        path,
        remedy=(
            ". It is probably truncated or corrupt: make it again with  snakemake --cores 2 "
            f"--forcerun {path}  (plus your targets)"
        ),
    )


def _provenance(path, schema) -> dict:
    return provenance_of(path, schema, remedy=_remake(path))


def read_provenance(path) -> dict:
    """The provenance of a table written by ``write_table``, without reading its data."""
    path = Path(path)
    return _provenance(path, _read_parquet(pq.read_schema, path))


def read_arrow_table(
    path, kind: TableKind | None = None, label: str | None = None
) -> tuple[pa.Table, dict]:
    """The pyarrow table and provenance of a table written by ``write_table``; with ``kind``,
    refused (naming the file) unless that kind's rule wrote it with its columns; with
    ``label``, unless it was made for the r of that label (``restitution_label``)."""
    path = Path(path)
    table = _read_parquet(pq.read_table, path)
    provenance = _provenance(path, table.schema)
    if kind is not None:
        if provenance.get("rule") != kind.rule:
            raise UnreadableFileError(
                f"{path}: not a {kind.name} table: written by rule {provenance.get('rule')}, "
                f"not {kind.rule}"
            )
        require_columns(table, path, kind.columns)
    if label is not None and provenance.get("r_label") != label:
        raise UnreadableFileError(
            f"{path}: made for r = {provenance.get('r_label')}, not r = {label}"
        )
    return table, provenance


def read_table(
    path, kind: TableKind | None = None, label: str | None = None
) -> tuple["pd.DataFrame", dict]:
    """``read_arrow_table`` as a pandas frame: the frame and provenance of a table written by
    ``write_table``, checked as there."""
    table, provenance = read_arrow_table(path, kind, label)
    return table.to_pandas(), provenance


def require_columns(frame, path, columns):
    """``frame`` (a pandas frame or a pyarrow table) if it has ``columns``; otherwise an error
    naming the file and what is missing."""
    names = frame.column_names if isinstance(frame, pa.Table) else frame.columns
    missing = [column for column in columns if column not in names]
    if missing:
        raise UnreadableFileError(
            f"{path}: not the expected table, it lacks the columns {', '.join(missing)}"
        )
    return frame


def read_tables_of_one_restitution(*paths, kinds=None) -> list[tuple["pd.DataFrame", dict]]:
    """``read_table`` of each path (with its kind of ``kinds``), refused unless all were
    made for the same r (e.g. the simulation, solver and fits one figure panel compares)."""
    kinds = [None] * len(paths) if kinds is None else kinds
    tables = [read_table(path, kind) for path, kind in zip(paths, kinds, strict=True)]
    values = [provenance.get("r") for _, provenance in tables]
    if len(set(values)) > 1:
        which = ", ".join(
            f"{path} (r = {value})" for path, value in zip(paths, values, strict=True)
        )
        raise UnreadableFileError(f"not the same r: {which}")
    return tables


def comparison_panels(solver_paths, simulation_paths, exact_paths, kinds) -> list[dict]:
    """One dict per r of a figure that compares the solver with the simulation, and with the
    exact solution where r has one: ``restitution`` (the exact r), ``solver``, ``simulated``,
    ``exact`` (None where r has no exact solution) and ``outside`` (the simulated tables'
    ``outside`` provenance, {} where it has none).
    ``kinds``: the (solver, simulated, exact) ``TableKind``; each solver table is paired with
    the simulation table of the same position and refused unless both are of one r."""
    solver_kind, simulated_kind, exact_kind = kinds
    exact = {}
    for path in exact_paths:
        table, provenance = read_table(path, exact_kind)
        exact[provenance["r"]] = table
    panels = []
    for paths in zip(solver_paths, simulation_paths, strict=True):
        (solved, provenance), (simulated, simulated_provenance) = read_tables_of_one_restitution(
            *paths, kinds=(solver_kind, simulated_kind)
        )
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "solver": solved,
                "simulated": simulated,
                "exact": exact.get(provenance["r"]),
                # how much of each distribution the simulated tables leave outside their bins
                "outside": simulated_provenance.get("outside", {}),
            }
        )
    return panels


def write_csv_and_markdown(table: "pd.DataFrame", csv_path, markdown_path, markdown: str) -> None:
    """A results table as CSV (12 significant digits) and its Markdown rendering, each atomic."""
    with atomic_paths(csv_path, markdown_path) as (csv_temporary, markdown_temporary):
        table.to_csv(csv_temporary, index=False, float_format="%.12g")
        Path(markdown_temporary).write_text(markdown)
