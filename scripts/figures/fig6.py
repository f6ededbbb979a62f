"""Fig. 6 (past the paper): <x>, Delta x and I against r, the solver's curves over
solver.restitution_grid with the simulation's points at every simulated r and the exact
values at r = 1/2, 1/3.

Run by Snakemake (rule fig6), or by hand:
    python scripts/figures/fig6.py results/solver/time_averages.parquet \
        --simulation results/simulation/r*/summary.parquet \
        --exact results/exact/r*/summary.parquet --pdf fig6.pdf --png fig6.png
"""

import argparse
import logging

import pandas as pd

from bouncing_ball import plotting
from bouncing_ball.asymptotics import CRITICAL_RESTITUTION
from bouncing_ball.io import read_table


def _rows(paths):
    frames = [read_table(path)[0] for path in paths]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def main(grid_path, simulation_paths, exact_paths, pdf, png, dpi):
    solved, _ = read_table(grid_path)
    figure = plotting.time_averages_figure(
        solved, _rows(simulation_paths), _rows(exact_paths), CRITICAL_RESTITUTION
    )
    inputs = [str(grid_path), *map(str, simulation_paths), *map(str, exact_paths)]
    plotting.save_figure(figure, pdf, png, dpi, {"figure": "fig6", "inputs": inputs})


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        snakemake.input.grid,
        snakemake.input.simulation,
        snakemake.input.exact,  # noqa: F821
        *snakemake.output,
        snakemake.params.dpi,
    )  # noqa: F821
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("grid", help="results/solver/time_averages.parquet")
    parser.add_argument(
        "--simulation", nargs="*", default=[], help="results/simulation/r{r}/summary.parquet"
    )
    parser.add_argument("--exact", nargs="*", default=[], help="results/exact/r{r}/summary.parquet")
    args = plotting.figure_arguments(parser).parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.grid, args.simulation, args.exact, args.pdf, args.png, args.dpi)
