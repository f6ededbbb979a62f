"""Rule coverage_report: every run of the coverage study against the exact r = 1/2 and 1/3
results, and the scatter of the runs' z per moment and estimator against Student's t ->
results/studies/coverage.{csv,md}."""

import logging

import pandas as pd

from bouncing_ball.estimators import position_moments_summary
from bouncing_ball.restitution import parse_restitution
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.workflow.io import write_csv_and_markdown
from bouncing_ball.workflow.jobs import job_log
from bouncing_ball.workflow.studies import (
    coverage_markdown,
    coverage_rows,
    exact_moments,
    iter_runs,
    run_z_scores,
)

with job_log(snakemake.log[0], exit_when_done=True):
    runs = snakemake.params.runs
    references, scores, counts = {}, [], {}
    for run, (shards, _) in iter_runs(snakemake.input.shards, runs):
        label = run["r_label"]
        if label not in references:
            references[label] = exact_moments(run["r"])
        exact = parse_restitution(run["r"])
        # the controlled estimates lean on the solver's P(0, u) (the estimators never solve)
        summary = position_moments_summary(shards, exact, solved_outgoing_density(exact)).iloc[0]
        counts[label] = counts.get(label, 0) + 1
        for (moment, estimator), z in run_z_scores(summary, references[label]).items():
            scores.append(
                {
                    "r_label": label,
                    "run": run["run"],
                    "moment": moment,
                    "estimator": estimator,
                    "z": z,
                }
            )
        logging.info("%s: %d shards read", run["run"], len(shards))
    table = coverage_rows(pd.DataFrame(scores), runs[0]["shards"])
    write_csv_and_markdown(
        table, snakemake.output.csv, snakemake.output.md, coverage_markdown(table, counts)
    )
    for row in table.itertuples():
        logging.info(
            "r=%s %s %s: %d runs, mean z %+.2f, mean z^2 %.2f +- %.2f (t: %.3f), "
            "abs z > 2 in %.3f +- %.3f (t: %.3f)",
            row.r_label,
            row.moment,
            row.estimator,
            row.runs,
            row.mean_z,
            row.mean_z2,
            row.mean_z2_err,
            row.expected_mean_z2,
            row.miss,
            row.miss_err,
            row.expected_miss,
        )
