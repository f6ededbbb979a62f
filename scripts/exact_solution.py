"""The exact solution at r = 1/2 or 1/3: P(0,v), P(x,v) (Fig. 3), P(x), <v^2>_x, <x>, Delta x, I.

Writes results/exact/r{r}/{p0v,distribution,position,summary}.parquet.
Run by Snakemake (rule exact_solution), or by hand with the settings of a config file:
    python scripts/exact_solution.py --restitution 1/2 --outdir results/exact/r0.5 [--config config/config.yaml]
"""

import argparse
import logging
from pathlib import Path

import numpy as np
import pandas as pd

from bouncing_ball import exact, source_digest
from bouncing_ball.bins import linear_grid, log_grid
from bouncing_ball.config import exact_settings, read_config
from bouncing_ball.io import write_table
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label


def distribution_table(positions, speeds, r):
    """P(x, v) for every x in ``positions`` and v in ``speeds`` (long format), and the
    largest relative error quad estimates for it."""
    x, v = np.meshgrid(np.asarray(positions, dtype=float), speeds, indexing="ij")
    pxv, error = exact.distribution_with_error(x, v, r)
    finite = np.isfinite(pxv) & (pxv > 0.0)
    worst = float(np.max(error[finite] / pxv[finite])) if finite.any() else 0.0
    return pd.DataFrame({"x": x.ravel(), "v": v.ravel(), "pxv": pxv.ravel()}), worst


def main(restitution, settings, outputs):
    value = parse_restitution(restitution)
    label = restitution_label(value)
    r = float(value)
    output_speeds = log_grid(settings["output_speeds"])
    heights = log_grid(settings["position_grid"])
    moments = exact.position_moments(r)
    provenance = {
        "rule": "exact_solution",
        "r": exact_string(value),
        "r_label": label,
        "settings": settings,
        "code": source_digest(("exact",)),
    }
    write_table(
        pd.DataFrame({"v": output_speeds, "p0v": exact.outgoing_speed_density(output_speeds, r)}),
        outputs["p0v"],
        provenance,
    )
    write_table(
        pd.DataFrame(
            {
                "x": heights,
                "px": exact.position_density(heights, r),
                "v2_given_x": exact.mean_speed_squared_given_position(heights, r),
            }
        ),
        outputs["position"],
        provenance,
    )
    write_table(
        pd.DataFrame(
            [
                {
                    "r": r,
                    "normalization_constant": exact.normalization_constant(r),
                    "mean_x": moments["mean_x"],
                    "delta_x": moments["delta_x"],
                    "collision_rate": moments["collision_rate"],
                }
            ]
        ),
        outputs["summary"],
        provenance,
    )
    table, worst = distribution_table(settings["positions"], linear_grid(settings["speeds"]), r)
    write_table(table, outputs["distribution"], provenance)
    logging.info(
        "r=%s: P(x,v) at %d points, largest estimated relative error %.1e", label, len(table), worst
    )
    if worst > 1e-6:
        logging.warning("r=%s: P(x,v) is less accurate than 1e-6 somewhere (%.1e)", label, worst)
    logging.info(
        "r=%s: A = %.12g, <x> = %.12g, Delta x = %.12g, I = %.12g",
        label,
        exact.normalization_constant(r),
        moments["mean_x"],
        moments["delta_x"],
        moments["collision_rate"],
    )


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--restitution", required=True, help="1/2 or 1/3")
    parser.add_argument("--outdir", required=True, type=Path)
    parser.add_argument("--config", default="config/config.yaml", help="grids from here")
    args = parser.parse_args()
    config = read_config(args.config)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    args.outdir.mkdir(parents=True, exist_ok=True)
    outputs = {
        name: args.outdir / f"{name}.parquet"
        for name in ("p0v", "distribution", "position", "summary")
    }
    main(args.restitution, exact_settings(config), outputs)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(snakemake.params.restitution, snakemake.params.settings, dict(snakemake.output))  # noqa: F821
elif __name__ == "__main__":
    _command_line()
