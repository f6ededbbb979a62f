"""Rules simulate_shard and study_shard: one shard of one r, the paper's Sec. IV
-> results/simulation/r{r}/shard{k}.parquet (or results/studies/{study}/{run}/shard{k}.parquet)."""

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
    started, started_cpu = time.perf_counter(), time.process_time()
    tallies = simulate_shard(float(exact), shard_seed_sequence(seed, label, shard), settings)
    elapsed, cpu_seconds = time.perf_counter() - started, time.process_time() - started_cpu
    provenance = {
        "rule": snakemake.rule,
        "r": exact_string(exact),
        "r_label": label,
        "shard": shard,
        "seed": seed,
        "code": snakemake.params.code,
        **settings.as_mapping(),
    }
    # a study shard records its cost (the studies' efficiency figures); the pipeline's shards
    # do not, so that the same config makes the same files, provenance included
    if getattr(snakemake.params, "record_cpu_seconds", False):
        provenance["cpu_seconds"] = cpu_seconds
    write_table(tallies_to_frame(tallies), snakemake.output[0], provenance)
    logging.info(
        "r=%s c=%g shard %d: time %.6g, %d collisions, %d steps, %.1f s (%.1f CPU s)%s",
        label,
        settings.criterion_c,
        shard,
        tallies.time,
        tallies.collisions,
        tallies.steps,
        elapsed,
        cpu_seconds,
        " -- STOPPED EARLY: STEP BUDGET EXHAUSTED (simulation.max_steps) or the speed collapsed "
        "towards 0 (below or near r_c; see simulation.min_step_floor)"
        if tallies.budget_exhausted
        else "",
    )
