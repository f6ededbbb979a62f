# The simulation stage: the paper's Sec. IV. Per r, one job per batch of shards
# (simulation.shards_per_job), each shard on its own random stream; merged per r.


rule simulate_shards:
    output:
        "results/simulation/r{r}/shards{first}-{last}.parquet",
    log:
        "logs/simulation/r{r}/shards{first}-{last}.log",
    # the batches with the most simulated time first (common.smk)
    priority: batch_priority
    conda:
        "../envs/bouncing-ball.yaml"
    # minutes: the step budget (simulation.max_steps, 10^9 steps) bounds a shard's CPU (the
    # ns per step: python -m benchmarks), so 20 per shard of the batch; raise runtime with max_steps
    resources:
        runtime=lambda wildcards: 20 * len(batch_shards(wildcards)),
        mem_mb=500,
        cpus_per_task=1,
    params:
        restitution=restitution_value,
        shards=batch_shards,
        seed=config["seed"],
        settings=settings,
        code=SHARD_CODE,
    script:
        "../../scripts/simulate_shards.py"


rule merge_shards:
    input:
        batch_files,
    output:
        p0v="results/simulation/r{r}/p0v.parquet",
        position="results/simulation/r{r}/position.parquet",
        distribution="results/simulation/r{r}/distribution.parquet",
        flight_time="results/simulation/r{r}/flight_time.parquet",
        return_speed="results/simulation/r{r}/return_speed.parquet",
        summary="results/simulation/r{r}/summary.parquet",
        bounce_chain="results/simulation/r{r}/bounce_chain.parquet",
    log:
        "logs/simulation/r{r}/merge.log",
    # a second or two, and most figures and tables wait for it: before them
    priority: 1
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        restitution=restitution_value,
        # what every batch file's provenance must record: refused by name otherwise
        batch=lambda wildcards: batch_provenance(wildcards.r),
        code=code(stages.MERGE, "merge_shards.py"),
    script:
        "../../scripts/merge_shards.py"
