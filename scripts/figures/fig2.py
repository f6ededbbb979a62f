"""Fig. 2: the decay rate q(r), eqs. (asym4) and (asym6).

Run by Snakemake (rule fig2), or by hand:
    python scripts/figures/fig2.py results/theory/exponents.parquet --pdf fig2.pdf --png fig2.png
"""

import argparse
import logging

from bouncing_ball import plotting
from bouncing_ball.io import read_table


def main(exponents_path, pdf, png, dpi):
    exponents, _ = read_table(exponents_path)
    figure = plotting.decay_rate_figure(exponents)
    plotting.save_figure(figure, pdf, png, dpi, {"figure": "fig2", "inputs": [str(exponents_path)]})


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(snakemake.input[0], *snakemake.output, snakemake.params.dpi)  # noqa: F821
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("exponents", help="results/theory/exponents.parquet")
    args = plotting.figure_arguments(parser).parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.exponents, args.pdf, args.png, args.dpi)
