# The tables: the time averages of eq. (xandDeltax) at every simulated r, against the
# paper, the exact solutions and the solver.


rule moments_table:
    input:
        simulation=expand("results/simulation/r{r}/summary.parquet", r=RESTITUTION),
        solver=expand("results/solver/r{r}/summary.parquet", r=RESTITUTION),
        exact=expand(
            "results/exact/r{r}/summary.parquet",
            r=[label for label in EXACT_LABELS if label in RESTITUTION],
        ),
    output:
        csv=report(
            "results/tables/moments.csv",
            caption="../report/moments.rst",
            category="Tables",
        ),
        md="results/tables/moments.md",
    log:
        "logs/tables/moments.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=500,
        cpus_per_task=1,
    params:
        code=TABLE_CODE,
    script:
        "../../scripts/moments_table.py"
