"""Rule criterion_bias_report: each (r, c) run of the criterion_bias study against the exact
r = 1/2 and 1/3 results, with its cost -> results/studies/criterion_bias.{csv,md}."""

import logging

from bouncing_ball.workflow.io import write_csv_and_markdown
from bouncing_ball.workflow.jobs import job_log
from bouncing_ball.workflow.studies import (
    criterion_bias_markdown,
    criterion_bias_row,
    criterion_bias_table,
    read_runs,
)

with job_log(snakemake.log[0], exit_when_done=True):
    runs = snakemake.params.runs
    shards = read_runs(snakemake.input.shards, runs)
    table = criterion_bias_table(
        [
            criterion_bias_row(run, *shards[run["run"]], snakemake.params.minimum_count)
            for run in runs
        ]
    )
    write_csv_and_markdown(
        table, snakemake.output.csv, snakemake.output.md, criterion_bias_markdown(table)
    )
    for row in table.itertuples():
        logging.info(
            "r=%s c=%g, %d shards: <x> z = %+.2f, Delta x z = %+.2f, I z = %+.2f; "
            "P(0,v) chi^2/n = %.2f over %d bins",
            row.r_label,
            row.criterion_c,
            row.shards,
            row.mean_x_z,
            row.delta_x_z,
            row.collision_rate_z,
            row.p0v_chi2_per_bin,
            row.p0v_bins,
        )
