# The simulation stage: the paper's Sec. IV, one job per (r, shard), merged per r.


rule simulate_shard:
    output:
        "results/simulation/r{r}/shard{shard}.parquet",
    log:
        "logs/simulation/r{r}/shard{shard}.log",
    # one SLURM job runs several shards (profiles/slurm: group-components);
    # local runs are unaffected
    group:
        "shards"
    conda:
        "../envs/bouncing-ball.yaml"
    # minutes: the step budget (simulation.max_steps, 10^9 steps) stops a shard after
    # about 2-4 CPU minutes; raise runtime with max_steps
    resources:
        runtime=20,
        mem_mb=500,
        cpus_per_task=1,
    params:
        restitution=restitution_value,
        seed=config["seed"],
        settings=settings,
        code=SHARD_CODE,
    script:
        "../../scripts/simulate_shard.py"


rule merge_shards:
    input:
        shard_files,
    output:
        p0v="results/simulation/r{r}/p0v.parquet",
        position="results/simulation/r{r}/position.parquet",
        distribution="results/simulation/r{r}/distribution.parquet",
        flight_time="results/simulation/r{r}/flight_time.parquet",
        return_speed="results/simulation/r{r}/return_speed.parquet",
        summary="results/simulation/r{r}/summary.parquet",
    log:
        "logs/simulation/r{r}/merge.log",
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        restitution=restitution_value,
        code=code(stages.MERGE, "merge_shards.py"),
    script:
        "../../scripts/merge_shards.py"
