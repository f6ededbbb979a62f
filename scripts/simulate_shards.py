"""Rules simulate_shards and study_batch: a batch of shards of one r, the paper's Sec. IV, each
shard on its own random stream -> results/simulation/r{r}/shards{first}-{last}.parquet (or
results/studies/{study}/{run}/shards{first}-{last}.parquet)."""

import logging
import time

from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.settings import ShardSettings
from bouncing_ball.workflow.batches import batch_to_table, simulate_batch
from bouncing_ball.workflow.io import write_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    exact = parse_restitution(snakemake.params.restitution)
    label = restitution_label(exact)
    shards, seed = list(snakemake.params.shards), snakemake.params.seed
    settings = ShardSettings.from_mapping(snakemake.params.settings)
    batch, cpu_seconds = {}, []
    started, started_cpu = time.perf_counter(), time.process_time()
    job_started, job_started_cpu = started, started_cpu
    for shard, tallies in simulate_batch(float(exact), seed, label, shards, settings):
        now, now_cpu = time.perf_counter(), time.process_time()
        batch[shard] = tallies
        cpu_seconds.append(now_cpu - started_cpu)
        logging.info(
            "r=%s c=%g shard %d: time %.6g, %d collisions, %d steps, %.1f s (%.1f CPU s)%s",
            label,
            settings.criterion_c,
            shard,
            tallies.time,
            tallies.collisions,
            tallies.steps,
            now - started,
            now_cpu - started_cpu,
            " -- STOPPED EARLY: STEP BUDGET EXHAUSTED (simulation.max_steps) or the speed "
            "collapsed towards 0 (below or near r_c; see simulation.min_step_floor)"
            if tallies.budget_exhausted
            else "",
        )
        started, started_cpu = now, now_cpu
    provenance = {
        "rule": snakemake.rule,
        "r": exact_string(exact),
        "r_label": label,
        "first_shard": shards[0],
        "last_shard": shards[-1],
        "seed": seed,
        "code": snakemake.params.code,
        **settings.as_mapping(),
    }
    # a study shard records its cost (the studies' efficiency figures), one entry per shard;
    # the pipeline's batches do not, so that the same config makes the same files, provenance
    # included
    if getattr(snakemake.params, "record_cpu_seconds", False):
        provenance["cpu_seconds"] = cpu_seconds
    write_table(batch_to_table(batch), snakemake.output[0], provenance)
    logging.info(
        "r=%s: %d shards (%d-%d) in %.1f s (%.1f CPU s; the first shard includes loading or "
        "compiling the loop)",
        label,
        len(shards),
        shards[0],
        shards[-1],
        time.perf_counter() - job_started,
        time.process_time() - job_started_cpu,
    )
