# The solver stage: eq. (inteq) solved for P(0,v) at any r, one job per r.


rule solve:
    output:
        p0v="results/solver/r{r}/p0v.parquet",
        summary="results/solver/r{r}/summary.parquet",
        flight_time="results/solver/r{r}/flight_time.parquet",
        return_speed="results/solver/r{r}/return_speed.parquet",
        position="results/solver/r{r}/position.parquet",
        distribution="results/solver/r{r}/distribution.parquet",
        weight="results/solver/r{r}/weight.parquet",
    log:
        "logs/solver/r{r}.log",
    # longer where r > 1/2 (w(F) on narrower panels, bouncing_ball/distribution/): first;
    # the others after the exact solutions and the longest batches of shards, so that they
    # do not compile the solver at the same time
    priority: solve_priority
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        restitution=solver_restitution_value,
        settings=lambda wildcards: solver_settings(config, wildcards.r),
        # the simulation's speed bins, on which the return-speed law is averaged
        speed_bins=lambda wildcards: settings(wildcards)["speed_bins"],
        code=code(stages.SOLVER, "solve.py"),
    script:
        "../../scripts/solve.py"


rule solve_grid:
    output:
        "results/solver/time_averages.parquet",
    log:
        "logs/solver/time_averages.log",
    # two seconds, and Fig. 6 waits for it: before the figures
    priority: 1
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        grid=config["solver"]["restitution_grid"],
        step=config["solver"]["quadrature_step"],
        code=code(stages.SOLVER, "solve_grid.py"),
    script:
        "../../scripts/solve_grid.py"
