"""Merge the shards of one r into P(0,v), P(x) and the summary.

Writes results/simulation/r{r}/{p0v,position,summary}.parquet.  Run by
Snakemake (rule merge_shards), or by hand:
    python scripts/merge_shards.py --restitution 1/3 --p0v p0v.parquet \
        --position position.parquet --summary summary.parquet shard*.parquet
"""

import argparse
import logging

from bouncing_ball import source_digest
from bouncing_ball.config import SHARD_SETTINGS
from bouncing_ball.histograms import (
    SOURCES,
    outgoing_speed_histogram,
    position_histogram,
    position_moments_summary,
)
from bouncing_ball.io import write_table
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.shards import read_shards


def main(shard_paths, restitution, p0v_path, position_path, summary_path):
    exact = parse_restitution(restitution)
    label = restitution_label(exact)
    shards, provenances = read_shards(shard_paths, label)
    first = provenances[0]
    provenance = {
        "rule": "merge_shards",
        "r": exact_string(exact),
        "r_label": label,
        "shards": len(shards),
        "code": source_digest(SOURCES),
        "simulation_code": first["code"],
        **{key: first[key] for key in ("seed", *SHARD_SETTINGS)},
    }
    summary = position_moments_summary(shards, float(exact))
    write_table(outgoing_speed_histogram(shards), p0v_path, provenance)
    write_table(position_histogram(shards), position_path, provenance)
    write_table(summary, summary_path, provenance)
    row = summary.iloc[0]
    logging.info(
        "r=%s: %d shards, time %.6g, <x> = %.5g +- %.2g, Delta x = %.5g +- %.2g, I = %.5g +- %.2g",
        label,
        len(shards),
        row.total_time,
        row.mean_x,
        row.mean_x_err,
        row.delta_x,
        row.delta_x_err,
        row.collision_rate,
        row.collision_rate_err,
    )
    if row.shards_out_of_budget:
        logging.warning(
            "r=%s: %d of %d shards stopped before shard_time (step budget simulation.max_steps exhausted, "
            "or below/near r_c a speed collapse: see simulation.min_step_floor); the estimates weight "
            "every shard by the time it recorded",
            label,
            row.shards_out_of_budget,
            len(shards),
        )


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("shards", nargs="+")
    parser.add_argument("--restitution", required=True)
    parser.add_argument("--p0v", required=True)
    parser.add_argument("--position", required=True)
    parser.add_argument("--summary", required=True)
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.shards, args.restitution, args.p0v, args.position, args.summary)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        list(snakemake.input),  # noqa: F821
        snakemake.params.restitution,  # noqa: F821
        snakemake.output.p0v,  # noqa: F821
        snakemake.output.position,  # noqa: F821
        snakemake.output.summary,  # noqa: F821
    )
elif __name__ == "__main__":
    _command_line()
