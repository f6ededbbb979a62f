"""Rule fig7 (past the paper): (simulation - solver) / sigma of every simulated P(0, v) bin,
one row per simulated r; the solver enters as its average over each bin."""

import logging

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.validation import outgoing_speed_residuals
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import SIMULATED_P0V, SOLVER_P0V, read_tables_of_one_restitution
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    panels = []
    for paths in zip(snakemake.input.simulation, snakemake.input.solver, strict=True):
        (simulated, provenance), (solved, _) = read_tables_of_one_restitution(
            *paths, kinds=(SIMULATED_P0V, SOLVER_P0V)
        )
        residuals = outgoing_speed_residuals(simulated, solved)
        panels.append((parse_restitution(provenance["r"]), residuals))
        logging.info(
            "r=%s: %d bins, mean squared residual %.3f, largest |residual| %.2f",
            provenance["r_label"],
            len(residuals),
            (residuals.residual**2).mean(),
            residuals.residual.abs().max(),
        )
    figure = plotting.residuals_figure(panels)
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
