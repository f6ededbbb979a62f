"""Rule fig3: the exact P(x, v) against v at the heights of exact.positions, one panel per
r (1/2, 1/3), eqs. (fpsol), (psi), (weightfunc2), (constants)."""

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import EXACT_DISTRIBUTION, read_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    panels = []
    for path in snakemake.input.distributions:
        distribution, provenance = read_table(path, EXACT_DISTRIBUTION)
        panels.append((parse_restitution(provenance["r"]), distribution))
    figure = plotting.exact_distribution_figure(panels)
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
