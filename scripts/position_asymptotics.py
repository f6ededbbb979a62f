"""Rule position_asymptotics: the exponents of P(x) at small and large x for every r,
measured from the solver's P(x) (eq. (P(x)1)) against their predictions ->
results/tables/position_asymptotics.{csv,md}."""

from bouncing_ball.validation import position_asymptotics_markdown, position_asymptotics_table
from bouncing_ball.workflow.io import SOLVER_SUMMARY, read_table, write_csv_and_markdown
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    summaries = []
    for path, label in zip(snakemake.input, snakemake.params.labels, strict=True):
        summary, _ = read_table(path, SOLVER_SUMMARY, label=label)
        summaries.append((label, summary.iloc[0]))
    table = position_asymptotics_table(summaries)
    write_csv_and_markdown(
        table,
        snakemake.output.csv,
        snakemake.output.md,
        position_asymptotics_markdown(table),
    )
