"""Fig. 7 (past the paper): (simulation - solver) / sigma of every simulated P(0, v) bin,
one row per simulated r; the solver enters as its average over each bin.

Run by Snakemake (rule fig7), or by hand (one file of each kind per row, in order):
    python scripts/figures/fig7.py --simulation results/simulation/r0.5/p0v.parquet \
        --solver results/solver/r0.5/p0v.parquet --pdf fig7.pdf --png fig7.png
"""

import argparse
import logging

from bouncing_ball import plotting
from bouncing_ball.comparison import outgoing_speed_residuals
from bouncing_ball.io import read_table
from bouncing_ball.restitution import parse_restitution


def main(simulation_paths, solver_paths, pdf, png, dpi):
    panels = []
    for simulation, solver in zip(simulation_paths, solver_paths, strict=True):
        simulated, provenance = read_table(simulation)
        residuals = outgoing_speed_residuals(simulated, read_table(solver)[0])
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
        pdf,
        png,
        dpi,
        {"figure": "fig7", "inputs": [*map(str, simulation_paths), *map(str, solver_paths)]},
    )


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        snakemake.input.simulation, snakemake.input.solver, *snakemake.output, snakemake.params.dpi
    )  # noqa: F821
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--simulation", nargs="+", required=True, help="results/simulation/r{r}/p0v.parquet"
    )
    parser.add_argument(
        "--solver", nargs="+", required=True, help="results/solver/r{r}/p0v.parquet"
    )
    args = plotting.figure_arguments(parser).parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.simulation, args.solver, args.pdf, args.png, args.dpi)
