# The exact solutions at r = 1/2 and 1/3: P(0,v), P(x,v) of Fig. 3, P(x), <v^2>_x and the moments.


rule exact_solution:
    output:
        p0v="results/exact/r{r}/p0v.parquet",
        distribution="results/exact/r{r}/distribution.parquet",
        position="results/exact/r{r}/position.parquet",
        summary="results/exact/r{r}/summary.parquet",
    log:
        "logs/exact/r{r}.log",
    # started with the solver jobs, on the cores the first batch leaves while it compiles the
    # shard loop (common.smk, batch_priority)
    priority: 10
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=500,
        cpus_per_task=1,
    params:
        restitution=exact_value,
        settings=lambda wildcards: exact_settings(config, wildcards.r),
        code=code(stages.EXACT, "exact_solution.py"),
    script:
        "../../scripts/exact_solution.py"
