"""Fig. 4: simulated P(0, v) with the asymptotic forms (prefactors fitted to the
simulation) and the solver's curve, one panel per r of figures.fig4.

Run by Snakemake (rule fig4), or by hand (one file of each kind per panel, in order):
    python scripts/figures/fig4.py --simulation results/simulation/r0.75/p0v.parquet \
        --solver results/solver/r0.75/p0v.parquet --fits results/fits/r0.75.parquet \
        --pdf fig4.pdf --png fig4.png
"""

import argparse
import logging

from bouncing_ball import plotting
from bouncing_ball.io import read_table
from bouncing_ball.restitution import parse_restitution


def main(simulation_paths, solver_paths, fit_paths, pdf, png, dpi):
    panels = []
    for simulation, solver, fits in zip(simulation_paths, solver_paths, fit_paths, strict=True):
        simulated, provenance = read_table(simulation)
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "simulated": simulated,
                "solver": read_table(solver)[0],
                "fits": read_table(fits)[0],
            }
        )
    figure = plotting.asymptotic_forms_figure(panels)
    inputs = [*map(str, simulation_paths), *map(str, solver_paths), *map(str, fit_paths)]
    plotting.save_figure(figure, pdf, png, dpi, {"figure": "fig4", "inputs": inputs})


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        snakemake.input.simulation,
        snakemake.input.solver,
        snakemake.input.fits,  # noqa: F821
        *snakemake.output,
        snakemake.params.dpi,
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
    parser.add_argument("--fits", nargs="+", required=True, help="results/fits/r{r}.parquet")
    args = plotting.figure_arguments(parser).parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.simulation, args.solver, args.fits, args.pdf, args.png, args.dpi)
