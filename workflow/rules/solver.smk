# The solver stage: eq. (inteq) solved for P(0,v) at any r, one job per r.


rule solve:
    output:
        p0v="results/solver/r{r}/p0v.parquet",
        summary="results/solver/r{r}/summary.parquet",
    log:
        "logs/solver/r{r}.log",
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        restitution=restitution_value,
        settings=config["solver"],
        code=SOLVER_CODE,
    script:
        "../../scripts/solve.py"
