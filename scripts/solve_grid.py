"""<x>, Delta x and I over a grid of r from eq. (inteq): the solver's curves of Fig. 6.

Writes results/solver/time_averages.parquet (r, small_speed_exponent, mean_x,
delta_x, collision_rate, energy_balance_residual); I is infinite below r_c.
Run by Snakemake (rule solve_grid), or by hand:
    python scripts/solve_grid.py time_averages.parquet [--config config/config.yaml]
"""

import argparse
import logging
import time

import pandas as pd

from bouncing_ball import solver, source_digest
from bouncing_ball.bins import linear_grid
from bouncing_ball.config import read_config
from bouncing_ball.io import write_table


def main(grid_spec, step, output):
    started = time.perf_counter()
    rows = []
    for r in linear_grid(grid_spec):
        solution = solver.solve_outgoing_speed_density(float(r), step=step)
        rows.append(
            {
                "r": float(r),
                "small_speed_exponent": solution.small_speed_exponent,
                **solver.time_averages(solution),
                "energy_balance_residual": solver.energy_balance_residual(solution),
            }
        )
    table = pd.DataFrame(rows)
    provenance = {
        "rule": "solve_grid",
        "restitution_grid": grid_spec,
        "quadrature_step": step,
        "code": source_digest(solver.SOURCES),
        "normalisation": "momentum balance M_2 = r / (1 + r)",
    }
    write_table(table, output, provenance)
    worst = table.energy_balance_residual.abs().max()
    logging.info(
        "<x>, Delta x, I at %d values of r in [%g, %g] in %.1f s; largest energy balance residual %.1e",
        len(table),
        table.r.min(),
        table.r.max(),
        time.perf_counter() - started,
        worst,
    )
    if not worst <= 1e-8:
        logging.warning("energy balance residual %.1e misses the 1e-8 target", worst)


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("output")
    parser.add_argument(
        "--config", default="config/config.yaml", help="the r grid and step from here"
    )
    args = parser.parse_args()
    config = read_config(args.config)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(config["solver"]["restitution_grid"], config["solver"]["quadrature_step"], args.output)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(snakemake.params.grid, snakemake.params.step, snakemake.output[0])  # noqa: F821
elif __name__ == "__main__":
    _command_line()
