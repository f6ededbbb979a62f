# The asymptotic theory and fits: beta, m, q over r (one job), and per r the fits of Fig. 4.


rule theory:
    output:
        "results/theory/exponents.parquet",
    log:
        "logs/theory/exponents.log",
    # a second, and Figs. 1 and 2 wait for it: before them
    priority: 1
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=500,
        cpus_per_task=1,
    params:
        grid=config["theory"]["restitution_grid"],
        code=code(stages.THEORY, "theory.py"),
    script:
        "../../scripts/theory.py"


rule fit:
    input:
        shards=batch_files,
        solver="results/solver/r{r}/p0v.parquet",
    output:
        "results/fits/r{r}.parquet",
    log:
        "logs/fits/r{r}.log",
    # a second or two, and Fig. 4 and the tables wait for it: before them
    priority: 1
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        restitution=restitution_value,
        settings=config["fits"],
        # what every batch file's provenance must record (common.smk)
        batch=lambda wildcards: batch_provenance(wildcards.r),
        code=code(stages.FITS, "fit.py"),
    script:
        "../../scripts/fit.py"


# The relaxation of the bounce chain, lambda_2 and n_c = -1 / ln lambda_2, from the solver's
# matrix, n_c <T>, and the slowest time of the process 1 / gamma from the tilted matrix, over
# r = 1 - eps on the log grid figures.fig12_inelasticity and at every simulated r (Fig. 12).
rule relaxation:
    output:
        "results/theory/relaxation.parquet",
    log:
        "logs/theory/relaxation.log",
    # a minute of eigenvalue searches that only Fig. 12 waits for: beside the simulation, not
    # after it (with the solves, common.smk's solve_priority)
    priority: 9
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=60,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        inelasticity=config["figures"]["fig12_inelasticity"],
        time_inelasticity=config["figures"]["fig12_time_inelasticity"],
        simulated=[exact_string(value) for value in RESTITUTION.values()],
        code=code(stages.SOLVER, "relaxation.py"),
    script:
        "../../scripts/relaxation.py"


# The quasi-elastic limit r -> 1: the solver's P(0,v) in the scaling (1 - r)^-3 P(0, w / (1 - r))
# at every r of figures.fig13 (Fig. 13), and the scaled I, <x>, Delta x against their limits.
rule quasi_elastic:
    output:
        curves="results/theory/quasi_elastic.parquet",
        csv=report(
            "results/tables/quasi_elastic.csv",
            caption="../report/quasi_elastic.rst",
            category="Tables",
        ),
        md="results/tables/quasi_elastic.md",
    log:
        "logs/theory/quasi_elastic.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=10,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        restitution=config["figures"]["fig13"],
        scaled_speeds=config["figures"]["fig13_scaled_speeds"],
        quadrature_step=config["solver"]["quadrature_step"],
        code=code((*stages.SOLVER, "quasi_elastic"), "quasi_elastic.py"),
    script:
        "../../scripts/quasi_elastic.py"
