"""Rule fig6 (past the paper): <x>, Delta x and I against r, the solver's curves over
solver.restitution_grid and at every simulated r (rule solve), against 1 - r, with the
quasi-elastic forms near r = 1, the simulation's points and the exact values at r = 1/2, 1/3."""

import pandas as pd

from bouncing_ball.asymptotics import CRITICAL_RESTITUTION
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import (
    EXACT_SUMMARY,
    SIMULATED_SUMMARY,
    SOLVER_SUMMARY,
    TIME_AVERAGES,
    read_table,
)
from bouncing_ball.workflow.jobs import job_log


def rows(paths, kind):
    frames = [read_table(path, kind)[0] for path in paths]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


with job_log(snakemake.log[0], exit_when_done=True):
    solved, _ = read_table(snakemake.input.grid, TIME_AVERAGES)
    simulated, exact = (
        rows(snakemake.input.simulation, SIMULATED_SUMMARY),
        rows(snakemake.input.exact, EXACT_SUMMARY),
    )
    per_restitution = rows(snakemake.input.solver, SOLVER_SUMMARY)
    figure = plotting.time_averages_figure(
        solved, simulated, exact, CRITICAL_RESTITUTION, per_restitution
    )
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
