"""Rule fig13 (past the paper): the solver's P(0, v) in the quasi-elastic scaling at each r of
figures.fig13 collapsing onto its limit (27/32) e^(-3w/2), and its departure from the limit
against the predicted first correction (results/theory/quasi_elastic.parquet)."""

from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import QUASI_ELASTIC_CURVES, read_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    curves, _ = read_table(snakemake.input[0], QUASI_ELASTIC_CURVES)
    plotting.save_figure(
        plotting.quasi_elastic_figure(curves),
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
