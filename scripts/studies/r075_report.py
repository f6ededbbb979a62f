"""Rule r075_report: <x>, Delta x, I of the r075 study's runs, alone and pooled, against the
solver, and checks of their errors -> results/studies/r075.{csv,md}."""

import logging

import pandas as pd

from bouncing_ball.workflow.io import (
    SOLVER_SUMMARY,
    UnreadableFileError,
    read_table,
    write_csv_and_markdown,
)
from bouncing_ball.workflow.jobs import job_log
from bouncing_ball.workflow.studies import r075_markdown, r075_rows, read_runs

with job_log(snakemake.log[0], exit_when_done=True):
    runs = snakemake.params.runs
    solved, provenance = read_table(snakemake.input.solver, SOLVER_SUMMARY)
    label = runs[0]["r_label"]
    if provenance.get("r_label") != label:
        raise UnreadableFileError(
            f"{snakemake.input.solver}: solved for r = {provenance.get('r_label')}, not r = {label}"
        )
    reference = solved.iloc[0]
    shards = read_runs(snakemake.input.shards, runs)
    sizes = snakemake.params.batch_size, snakemake.params.group_size
    rows = []
    for run in runs:
        rows += r075_rows(run["run"], run, *shards[run["run"]], reference, *sizes)
    if len(runs) > 1:
        pooled = [shards[run["run"]] for run in runs]
        rows += r075_rows(
            "all",
            None,
            [shard for tallies, _ in pooled for shard in tallies],
            [p for _, provenances in pooled for p in provenances],
            reference,
            *sizes,
        )
    table = pd.DataFrame(rows)
    markdown = r075_markdown(table, label)
    write_csv_and_markdown(table, snakemake.output.csv, snakemake.output.md, markdown)
    for row in table.itertuples():
        logging.info(
            "%s (%d shards) %s: %.8g +- %.2g, solver %.10g, %+.4f +- %.4f%%, z = %+.2f",
            row.run,
            row.shards,
            row.quantity,
            row.value,
            row.error,
            row.solver,
            100 * row.rel_deviation,
            100 * row.rel_error,
            row.z,
        )
