"""beta(r), m(r), q(r) of eqs. (asym2)-(asym6) on the config's r grid.

Writes results/theory/exponents.parquet (r, beta, m, q).  Run by Snakemake
(rule theory), or by hand:
    python scripts/theory.py results/theory/exponents.parquet [--config config/config.yaml]
"""

import argparse
import logging

from bouncing_ball import source_digest
from bouncing_ball.asymptotics import CRITICAL_RESTITUTION, SOURCES, exponents_table
from bouncing_ball.bins import linear_grid
from bouncing_ball.config import read_config
from bouncing_ball.io import write_table


def main(grid_spec, output):
    table = exponents_table(linear_grid(grid_spec))
    provenance = {
        "rule": "theory",
        "restitution_grid": grid_spec,
        "critical_restitution": CRITICAL_RESTITUTION,
        "code": source_digest(SOURCES),
    }
    write_table(table, output, provenance)
    logging.info(
        "beta, m, q at %d values of r in [%g, %g]; r_c = %.12g",
        len(table),
        table.r.min(),
        table.r.max(),
        CRITICAL_RESTITUTION,
    )


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("output")
    parser.add_argument("--config", default="config/config.yaml", help="the r grid from here")
    args = parser.parse_args()
    config = read_config(args.config)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(config["theory"]["restitution_grid"], args.output)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(snakemake.params.grid, snakemake.output[0])  # noqa: F821
elif __name__ == "__main__":
    _command_line()
