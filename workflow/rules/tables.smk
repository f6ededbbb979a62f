# The tables: the time averages of eq. (xandDeltax) at every simulated r, against the
# paper, the exact solutions and the solver (moments); the run's validation checks.
from types import SimpleNamespace


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
        code=code(stages.COMPARISON, "moments_table.py"),
    script:
        "../../scripts/moments_table.py"


# The run's own validation: the simulated P(0,v), P(x) and <v^2>_x against the exact
# solutions (r = 1/2, 1/3) or the solver, and the free-exponent fits against the theory;
# the shards' batch files give each chi^2/n its sign-flip p-value.
rule validation_table:
    input:
        shards=[
            path
            for label in RESTITUTION
            for path in batch_files(SimpleNamespace(r=label))
        ],
        p0v=expand("results/simulation/r{r}/p0v.parquet", r=RESTITUTION),
        position=expand("results/simulation/r{r}/position.parquet", r=RESTITUTION),
        solver=expand("results/solver/r{r}/p0v.parquet", r=RESTITUTION),
        fits=expand("results/fits/r{r}.parquet", r=RESTITUTION),
    output:
        csv=report(
            "results/tables/validation.csv",
            caption="../report/validation.rst",
            category="Tables",
        ),
        md="results/tables/validation.md",
    log:
        "logs/tables/validation.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=500,
        cpus_per_task=1,
    params:
        code=code(stages.VALIDATION, "validation_table.py"),
    script:
        "../../scripts/validation_table.py"


# The asymptotics of P(x) at every r: measured from the solver's P(x), and predicted.
rule position_asymptotics:
    input:
        expand("results/solver/r{r}/summary.parquet", r=RESTITUTION),
    output:
        csv=report(
            "results/tables/position_asymptotics.csv",
            caption="../report/position_asymptotics.rst",
            category="Tables",
        ),
        md="results/tables/position_asymptotics.md",
    log:
        "logs/tables/position_asymptotics.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=500,
        cpus_per_task=1,
    params:
        labels=list(RESTITUTION),  # of the inputs, in their order
        code=code(stages.COMPARISON, "position_asymptotics.py"),
    script:
        "../../scripts/position_asymptotics.py"
