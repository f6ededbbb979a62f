"""Fig. 3: the exact P(x, v) against v at the heights of exact.positions, one panel per r
(1/2, 1/3), eqs. (fpsol), (psi), (weightfunc2), (constants).

Run by Snakemake (rule fig3), or by hand:
    python scripts/figures/fig3.py results/exact/r0.5/distribution.parquet \
        results/exact/r0.333333/distribution.parquet --pdf fig3.pdf --png fig3.png
"""

import argparse
import logging

from bouncing_ball import plotting
from bouncing_ball.io import read_table
from bouncing_ball.restitution import parse_restitution


def main(distribution_paths, pdf, png, dpi):
    panels = []
    for path in distribution_paths:
        distribution, provenance = read_table(path)
        panels.append((parse_restitution(provenance["r"]), distribution))
    figure = plotting.exact_distribution_figure(panels)
    plotting.save_figure(
        figure, pdf, png, dpi, {"figure": "fig3", "inputs": list(map(str, distribution_paths))}
    )


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(list(snakemake.input), *snakemake.output, snakemake.params.dpi)  # noqa: F821
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "distributions", nargs="+", help="results/exact/r{r}/distribution.parquet, one per panel"
    )
    args = plotting.figure_arguments(parser).parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.distributions, args.pdf, args.png, args.dpi)
