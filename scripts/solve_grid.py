"""Rule solve_grid: <x>, Delta x and I over a grid of r from eq. (inteq), the solver's curves
of Fig. 6 -> results/solver/time_averages.parquet (I is infinite below r_c)."""

import logging
import time

import pandas as pd

from bouncing_ball import solver
from bouncing_ball.bins import linear_grid
from bouncing_ball.workflow.io import write_table
from bouncing_ball.workflow.jobs import job_log

COLUMNS = [
    "r",
    "small_speed_exponent",
    "mean_x",
    "delta_x",
    "collision_rate",
    "energy_balance_residual",
]

with job_log(snakemake.log[0], exit_when_done=True):
    grid, step = snakemake.params.grid, snakemake.params.step
    started = time.perf_counter()
    rows = [
        solver.solution_summary(
            solver.solve_outgoing_speed_density(float(r), step=step), with_accuracy_estimate=False
        )
        for r in linear_grid(grid)
    ]
    table = pd.DataFrame(rows)[COLUMNS]
    provenance = {
        "rule": "solve_grid",
        "restitution_grid": grid,
        "quadrature_step": step,
        "code": snakemake.params.code,
        "normalisation": "momentum balance M_2 = r / (1 + r)",
    }
    write_table(table, snakemake.output[0], provenance)
    worst = table.energy_balance_residual.abs().max()
    logging.info(
        "<x>, Delta x, I at %d values of r in [%g, %g] in %.1f s; largest energy balance residual %.1e",
        len(table),
        table.r.min(),
        table.r.max(),
        time.perf_counter() - started,
        worst,
    )
    if not worst <= solver.ACCURACY_TARGET:
        logging.warning(
            "energy balance residual %.1e misses the %.0e target", worst, solver.ACCURACY_TARGET
        )
