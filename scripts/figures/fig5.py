"""Fig. 5: simulated P(0, v) against the exact solution, eqs. (P(0,v)) and (constants),
with no adjustable parameter, one panel per r of figures.fig5 (1/2, 1/3).

Run by Snakemake (rule fig5), or by hand (one file of each kind per panel, in order):
    python scripts/figures/fig5.py --simulation results/simulation/r0.5/p0v.parquet \
        --exact results/exact/r0.5/p0v.parquet --pdf fig5.pdf --png fig5.png
"""

import argparse
import logging

from bouncing_ball import plotting
from bouncing_ball.io import read_table
from bouncing_ball.restitution import parse_restitution


def main(simulation_paths, exact_paths, pdf, png, dpi):
    panels = []
    for simulation, exact in zip(simulation_paths, exact_paths, strict=True):
        simulated, provenance = read_table(simulation)
        solution, exact_provenance = read_table(exact)
        if parse_restitution(exact_provenance["r"]) != parse_restitution(provenance["r"]):
            raise ValueError(
                f"{simulation} (r = {provenance['r']}) and {exact} "
                f"(r = {exact_provenance['r']}) are not the same r"
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
        pdf,
        png,
        dpi,
        {"figure": "fig5", "inputs": [*map(str, simulation_paths), *map(str, exact_paths)]},
    )


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(snakemake.input.simulation, snakemake.input.exact, *snakemake.output, snakemake.params.dpi)  # noqa: F821
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--simulation", nargs="+", required=True, help="results/simulation/r{r}/p0v.parquet"
    )
    parser.add_argument("--exact", nargs="+", required=True, help="results/exact/r{r}/p0v.parquet")
    args = plotting.figure_arguments(parser).parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.simulation, args.exact, args.pdf, args.png, args.dpi)
