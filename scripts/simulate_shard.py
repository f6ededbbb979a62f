"""Simulate one shard of one r: results/simulation/r{r}/shard{k}.parquet.

Run by Snakemake (rule simulate_shard), or by hand, e.g.
    python scripts/simulate_shard.py --restitution 1/3 --shard 0 --seed 1 \
        --shard-time 1e4 out.parquet
"""

import argparse
import logging
import time

from bouncing_ball.config import log_bins
from bouncing_ball.io import write_table
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
from bouncing_ball.tallies import tallies_to_frame

DEFAULTS = {
    "equilibration_time": 1.0e3,
    "criterion_c": 5.0,
    "min_step_divisor": 500.0,
    "max_steps": 1.0e11,
    "speed_bins": {"lo": 1.0e-4, "hi": 1.0e2, "per_decade": 10},
    "position_bins": {"lo": 1.0e-3, "hi": 1.0e3, "per_decade": 5},
}


def main(output, restitution, shard, seed, settings):
    """Simulate and write one shard; ``settings`` as in config key ``simulation``."""
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
        **{key: settings[key] for key in DEFAULTS | {"shard_time": None}},
    }
    write_table(tallies_to_frame(tallies), output, provenance)
    logging.info(
        "r=%s shard %d: time %.6g, %d collisions, %d steps, %.1f s%s",
        label, shard, tallies.time, tallies.collisions, tallies.steps, elapsed,
        " -- STEP BUDGET EXHAUSTED" if tallies.budget_exhausted else "",
    )


def _command_line():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("output")
    parser.add_argument("--restitution", required=True, help='r, e.g. 0.25 or "1/3"')
    parser.add_argument("--shard", type=int, required=True)
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--shard-time", type=float, required=True)
    parser.add_argument("--equilibration-time", type=float, default=DEFAULTS["equilibration_time"])
    parser.add_argument("--criterion-c", type=float, default=DEFAULTS["criterion_c"])
    parser.add_argument("--min-step-divisor", type=float, default=DEFAULTS["min_step_divisor"])
    parser.add_argument("--max-steps", type=float, default=DEFAULTS["max_steps"])
    args = parser.parse_args()
    settings = {**DEFAULTS, **{k: v for k, v in vars(args).items() if k in DEFAULTS or k == "shard_time"}}
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.output, args.restitution, args.shard, args.seed, settings)


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
