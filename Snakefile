# bouncing-ball: Burkhardt & Kotsev, "Equilibrium statistics of an inelastically
# bouncing ball, subject to gravity and a random force", reproduced for any r.
from snakemake.utils import min_version, validate

min_version("9.0")


configfile: "config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")


report: "workflow/report/workflow.rst"


wildcard_constraints:
    r=r"[0-9][0-9.e-]*",
    shard=r"[0-9]+",
    first=r"[0-9]+",
    last=r"[0-9]+",


# rules with `localrule: True` (the stage targets below, and jobs of a few seconds whose
# queue wait would exceed their run time) run in Snakemake's own process, never submitted
# to a cluster (profiles/slurm)


include: "workflow/rules/common.smk"
include: "workflow/rules/simulation.smk"
include: "workflow/rules/solver.smk"
include: "workflow/rules/exact.smk"
include: "workflow/rules/theory.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/tables.smk"
include: "workflow/rules/studies.smk"
include: "workflow/rules/audit.smk"


rule all:
    default_target: True
    input:
        simulation_targets(),
        solver_targets(),
        exact_targets(),
        "results/theory/exponents.parquet",
        fit_targets(),
        "results/solver/time_averages.parquet",
        figure_targets(),
        table_targets(),
    localrule: True


# stage target: every simulated r, merged
rule simulation:
    input:
        simulation_targets(),
    localrule: True


# stage target: the solver at every r of the config
rule solver:
    input:
        solver_targets(),
        "results/solver/time_averages.parquet",
    localrule: True


# stage target: the exact solutions at r = 1/2 and 1/3
rule exact:
    input:
        exact_targets(),
    localrule: True


# stage target: the theory's exponents and the fits at every r of the config
rule fits:
    input:
        "results/theory/exponents.parquet",
        fit_targets(),
    localrule: True


# stage target: Figs. 1-7, PDF and PNG
rule figures:
    input:
        figure_targets(),
    localrule: True


# stage target: the moments and validation tables, CSV and Markdown
rule tables:
    input:
        table_targets(),
    localrule: True


# stage target: the studies of config/studies.yaml (hours of CPU; not part of `all`)
rule studies:
    input:
        STUDY_TARGETS,
    localrule: True


# the run ends when its last job does, not when Snakemake's job-rate timer runs out
onsuccess:
    end_pending_timers()


onerror:
    end_pending_timers()
