"""Rule study_shard: one shard of one run of a study (config/studies.yaml), as rule
simulate_shard's, with its CPU time -> results/studies/{study}/{run}/shard{k}.parquet."""

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
    # process time: the efficiency figures of the criterion_bias report (includes loading
    # the compiled loop from numba's cache, a fraction of a second)
    started = time.process_time()
    tallies = simulate_shard(float(exact), shard_seed_sequence(seed, label, shard), settings)
    cpu_seconds = time.process_time() - started
    provenance = {
        "rule": "study_shard",
        "study": snakemake.wildcards.study,
        "run": snakemake.wildcards.run,
        "r": exact_string(exact),
        "r_label": label,
        "shard": shard,
        "seed": seed,
        "code": snakemake.params.code,
        "cpu_seconds": cpu_seconds,
        **settings.as_mapping(),
    }
    write_table(tallies_to_frame(tallies), snakemake.output[0], provenance)
    logging.info(
        "%s/%s r=%s c=%g shard %d: time %.6g, %d collisions, %d steps, %.1f CPU s%s",
        snakemake.wildcards.study,
        snakemake.wildcards.run,
        label,
        settings.criterion_c,
        shard,
        tallies.time,
        tallies.collisions,
        tallies.steps,
        cpu_seconds,
        " -- STOPPED EARLY: STEP BUDGET EXHAUSTED (max_steps)" if tallies.budget_exhausted else "",
    )
