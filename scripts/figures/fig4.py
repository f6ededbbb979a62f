"""Rule fig4: simulated P(0, v) with the asymptotic forms (prefactors fitted to the
simulation) and the solver's curve, one panel per r of figures.fig4."""

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import (
    FITS,
    SIMULATED_P0V,
    SOLVER_P0V,
    read_tables_of_one_restitution,
)
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    panels = []
    inputs = snakemake.input
    for paths in zip(inputs.simulation, inputs.solver, inputs.fits, strict=True):
        (simulated, provenance), (solved, _), (fitted, _) = read_tables_of_one_restitution(
            *paths, kinds=(SIMULATED_P0V, SOLVER_P0V, FITS)
        )
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "simulated": simulated,
                "solver": solved,
                "fits": fitted,
            }
        )
    figure = plotting.asymptotic_forms_figure(panels)
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
