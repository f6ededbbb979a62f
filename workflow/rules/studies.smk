# The studies: accuracy checks behind docs/validation.md (c = 3 against c = 5 at the exact r,
# r = 3/4 against the solver), set in config/studies.yaml. Hours of CPU: not part of `all`;
# run with  snakemake --cores 2 studies
from snakemake.exceptions import WorkflowError

from bouncing_ball.workflow.config import check_types, read_yaml, study_runs

STUDIES_FILE = "config/studies.yaml"
try:
    STUDIES = read_yaml(STUDIES_FILE)  # a repeated key refused
    validate(STUDIES, "../schemas/studies.schema.yaml")
except (ValueError, WorkflowError) as error:
    raise WorkflowError(f"{STUDIES_FILE}: {error}") from None
try:
    check_types(
        STUDIES,
        read_yaml(f"{workflow.basedir}/workflow/schemas/studies.schema.yaml"),
        STUDIES_FILE,
    )
    STUDY_RUNS = study_runs(STUDIES, config)  # {study: {run: StudyRun}}
except ValueError as error:
    raise ValueError(f"invalid {STUDIES_FILE}: {error}") from None
R075_LABEL = restitution_label(parse_restitution(STUDIES["r075"]["restitution"]))


# per study: the batch files of every run, run by run (batches of simulation.shards_per_job
# shards, as the pipeline's), and what its report is told about the runs, in the same order
STUDY_SHARDS = {
    study: [
        f"results/studies/{study}/{name}/shards{first}-{last}.parquet"
        for name, run in runs.items()
        for first, last in study_batch_ranges(run)
    ]
    for study, runs in STUDY_RUNS.items()
}
STUDY_RUN_TABLES = {
    study: [run.as_mapping() for run in runs.values()]
    for study, runs in STUDY_RUNS.items()
}
STUDY_TARGETS = expand(
    "results/studies/{study}.{ext}", study=STUDY_RUNS, ext=("md", "csv")
)


rule study_batch:
    output:
        "results/studies/{study}/{run}/shards{first}-{last}.parquet",
    log:
        "logs/studies/{study}/{run}/shards{first}-{last}.log",
    wildcard_constraints:
        study="|".join(STUDY_RUNS),
        run=r"[^/]+",
    conda:
        "../envs/bouncing-ball.yaml"
    # minutes: an upper bound on a study shard (its CPU: python -m benchmarks, config/studies.yaml),
    # per shard of the batch
    resources:
        runtime=lambda wildcards: 20 * len(study_batch_shards(wildcards)),
        mem_mb=500,
        cpus_per_task=1,
    params:
        restitution=lambda w: exact_string(STUDY_RUNS[w.study][w.run].restitution),
        shards=study_batch_shards,
        seed=lambda w: STUDY_RUNS[w.study][w.run].seed,
        settings=lambda w: STUDY_RUNS[w.study][w.run].settings.as_mapping(),
        code=SHARD_CODE,
        record_cpu_seconds=True,
    script:
        "../../scripts/simulate_shards.py"


rule criterion_bias_report:
    input:
        shards=STUDY_SHARDS["criterion_bias"],
    output:
        md="results/studies/criterion_bias.md",
        csv="results/studies/criterion_bias.csv",
    log:
        "logs/studies/criterion_bias.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        runs=STUDY_RUN_TABLES["criterion_bias"],
        minimum_count=STUDIES["criterion_bias"]["minimum_count"],
        code=code(stages.STUDIES, "studies/criterion_bias_report.py"),
    script:
        "../../scripts/studies/criterion_bias_report.py"


rule r075_report:
    input:
        shards=STUDY_SHARDS["r075"],
        solver=f"results/solver/r{R075_LABEL}/summary.parquet",
    output:
        md="results/studies/r075.md",
        csv="results/studies/r075.csv",
    log:
        "logs/studies/r075.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    resources:
        runtime=5,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        runs=STUDY_RUN_TABLES["r075"],
        batch_size=STUDIES["r075"]["batch_size"],
        group_size=STUDIES["r075"]["group_size"],
        code=code(stages.STUDIES, "studies/r075_report.py"),
    script:
        "../../scripts/studies/r075_report.py"


rule coverage_report:
    input:
        shards=STUDY_SHARDS["coverage"],
    output:
        md="results/studies/coverage.md",
        csv="results/studies/coverage.csv",
    log:
        "logs/studies/coverage.log",
    localrule: True
    conda:
        "../envs/bouncing-ball.yaml"
    # minutes: one position_moments_summary per run (the control fits' jackknife)
    resources:
        runtime=30,
        mem_mb=1000,
        cpus_per_task=1,
    params:
        runs=STUDY_RUN_TABLES["coverage"],
        code=code(stages.STUDIES, "studies/coverage_report.py"),
    script:
        "../../scripts/studies/coverage_report.py"
