"""Rule fig5: simulated P(0, v) against the exact solution, eqs. (P(0,v)) and (constants),
with no adjustable parameter, one panel per r of figures.fig5 (1/2, 1/3)."""

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import EXACT_P0V, SIMULATED_P0V, read_tables_of_one_restitution
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    panels = []
    for paths in zip(snakemake.input.simulation, snakemake.input.exact, strict=True):
        (simulated, provenance), (solution, _) = read_tables_of_one_restitution(
            *paths, kinds=(SIMULATED_P0V, EXACT_P0V)
        )
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "simulated": simulated,
                "exact": solution,
            }
        )
    figure = plotting.exact_comparison_figure(panels)
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
