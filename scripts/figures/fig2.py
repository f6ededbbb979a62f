"""Rule fig2: the decay rate q(r), eqs. (asym4) and (asym6)."""

from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import EXPONENTS, read_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    exponents, _ = read_table(snakemake.input.exponents, EXPONENTS)
    figure = plotting.decay_rate_figure(exponents)
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
