"""Rule moments_table: the time averages <x>, Delta x, I of eq. (xandDeltax) for every
simulated r: the paper's value where it gives one, the exact and solver values, the
simulation's with its error, and the z-score against the exact value (or the solver's where
there is none) -> results/tables/moments.csv (one row per r and quantity) and moments.md."""

import logging

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.validation import moment_rows, moments_markdown, moments_table
from bouncing_ball.workflow.io import (
    EXACT_SUMMARY,
    SIMULATED_SUMMARY,
    SOLVER_SUMMARY,
    read_table,
    read_tables_of_one_restitution,
    write_csv_and_markdown,
)
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    exact = {}
    for path in snakemake.input.exact:
        summary, provenance = read_table(path, EXACT_SUMMARY)
        exact[parse_restitution(provenance["r"])] = summary.iloc[0]
    rows = []
    pairs = zip(snakemake.input.simulation, snakemake.input.solver, strict=True)
    for simulation, solver in pairs:
        (simulated, provenance), (solved, _) = read_tables_of_one_restitution(
            simulation, solver, kinds=(SIMULATED_SUMMARY, SOLVER_SUMMARY)
        )
        restitution = parse_restitution(provenance["r"])
        rows += moment_rows(
            provenance["r_label"],
            restitution,
            simulated.iloc[0],
            solved.iloc[0],
            exact.get(restitution),
        )
    table = moments_table(rows)
    write_csv_and_markdown(
        table, snakemake.output.csv, snakemake.output.md, moments_markdown(table)
    )
    for row in table.itertuples():
        logging.info(
            "r=%s %s: simulation %.6g +- %.2g, %s %.10g, z = %+.2f",
            row.r_label,
            row.quantity,
            row.simulation,
            row.simulation_err,
            row.reference,
            getattr(row, row.reference),
            row.z,
        )
