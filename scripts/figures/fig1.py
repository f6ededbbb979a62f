"""Rule fig1: the exponents beta(r), eq. (asym2), and m(r), eqs. (asym3)-(asym6)."""

from bouncing_ball.asymptotics import CRITICAL_RESTITUTION
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import EXPONENTS, read_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    exponents, _ = read_table(snakemake.input.exponents, EXPONENTS)
    figure = plotting.exponents_figure(exponents, CRITICAL_RESTITUTION)
    plotting.save_figure(
        figure,
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
