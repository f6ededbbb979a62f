"""Rule simulate_shard: one shard of one r, the paper's Sec. IV -> results/simulation/r{r}/shard{k}.parquet."""

import logging
import time

from bouncing_ball.io import write_table
from bouncing_ball.jobs import job_log
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.settings import ShardSettings
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
from bouncing_ball.tallies import tallies_to_frame

with job_log(snakemake.log[0]):
    exact = parse_restitution(snakemake.params.restitution)
    label = restitution_label(exact)
    shard, seed = int(snakemake.wildcards.shard), snakemake.params.seed
    settings = ShardSettings.from_mapping(snakemake.params.settings)
    started = time.perf_counter()
    tallies = simulate_shard(float(exact), shard_seed_sequence(seed, label, shard), settings)
    elapsed = time.perf_counter() - started
    provenance = {
        "rule": "simulate_shard",
        "r": exact_string(exact),
        "r_label": label,
        "shard": shard,
        "seed": seed,
        "code": snakemake.params.code,
        **settings.as_mapping(),
    }
    write_table(tallies_to_frame(tallies), snakemake.output[0], provenance)
    logging.info(
        "r=%s shard %d: time %.6g, %d collisions, %d steps, %.1f s%s",
        label,
        shard,
        tallies.time,
        tallies.collisions,
        tallies.steps,
        elapsed,
        " -- STOPPED EARLY: STEP BUDGET EXHAUSTED (simulation.max_steps) or the speed collapsed "
        "towards 0 (below or near r_c; see simulation.min_step_floor)"
        if tallies.budget_exhausted
        else "",
    )
