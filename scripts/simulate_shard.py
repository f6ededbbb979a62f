"""Simulate one shard of one r: results/simulation/r{r}/shard{k}.parquet.

Run by Snakemake (rule simulate_shard), or by hand with the settings of a
config file, e.g.
    python scripts/simulate_shard.py --restitution 1/3 --shard 0 out.parquet
    python scripts/simulate_shard.py --restitution 0.5 --shard 2 --shard-time 1e4 \
        --config config/config.yaml out.parquet
"""

import argparse
import logging
import time

import yaml

from bouncing_ball import source_digest
from bouncing_ball.bins import log_bins
from bouncing_ball.config import check_config, shard_settings
from bouncing_ball.io import write_table
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.simulation import SOURCES, shard_seed_sequence, simulate_shard
from bouncing_ball.tallies import tallies_to_frame


def main(output, restitution, shard, seed, settings):
    """Simulate and write one shard; ``settings`` as from ``config.shard_settings``."""
    exact = parse_restitution(restitution)
    label = restitution_label(exact)
    started = time.perf_counter()
    tallies = simulate_shard(
        restitution=float(exact),
        seed_sequence=shard_seed_sequence(seed, label, shard),
        recorded_time=float(settings["shard_time"]),
        equilibration_time=float(settings["equilibration_time"]),
        criterion_c=float(settings["criterion_c"]),
        min_step_divisor=float(settings["min_step_divisor"]),
        min_step_floor=float(settings["min_step_floor"]),
        max_steps=int(settings["max_steps"]),
        speed_bins=log_bins(settings["speed_bins"]),
        position_bins=log_bins(settings["position_bins"]),
    )
    elapsed = time.perf_counter() - started
    provenance = {
        "rule": "simulate_shard",
        "r": exact_string(exact),
        "r_label": label,
        "shard": shard,
        "seed": seed,
        "code": source_digest(SOURCES),
        **settings,
    }
    write_table(tallies_to_frame(tallies), output, provenance)
    logging.info(
        "r=%s shard %d: time %.6g, %d collisions, %d steps, %.1f s%s",
        label,
        shard,
        tallies.time,
        tallies.collisions,
        tallies.steps,
        elapsed,
        " -- STOPPED EARLY: STEP BUDGET EXHAUSTED (simulation.max_steps) or the speed collapsed towards 0"
        " (below or near r_c; see simulation.min_step_floor)"
        if tallies.budget_exhausted
        else "",
    )


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("output")
    parser.add_argument("--restitution", required=True, help='r, e.g. 0.25 or "1/3"')
    parser.add_argument("--shard", type=int, required=True)
    parser.add_argument(
        "--config", default="config/config.yaml", help="settings and seed from here"
    )
    parser.add_argument("--shard-time", type=float, help="override the config's shard_time")
    parser.add_argument("--max-steps", type=int, help="override the config's max_steps")
    parser.add_argument("--min-step-floor", type=float, help="override the config's min_step_floor")
    args = parser.parse_args()
    with open(args.config) as handle:
        config = yaml.safe_load(handle)
    check_config(config)
    settings = shard_settings(config, restitution_label(parse_restitution(args.restitution)))
    for key in ("shard_time", "max_steps", "min_step_floor"):
        if getattr(args, key) is not None:
            settings[key] = getattr(args, key)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.output, args.restitution, args.shard, config["seed"], settings)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        snakemake.output[0],  # noqa: F821
        snakemake.params.restitution,  # noqa: F821
        int(snakemake.wildcards.shard),  # noqa: F821
        snakemake.params.seed,  # noqa: F821
        snakemake.params.settings,  # noqa: F821
    )
elif __name__ == "__main__":
    _command_line()
