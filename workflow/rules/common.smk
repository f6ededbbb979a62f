# Helpers for every stage: r labels and exact values, per-r settings, shard batches, targets.
from fractions import Fraction
from types import SimpleNamespace

from bouncing_ball import source_digest
from bouncing_ball.workflow import stages
from bouncing_ball.workflow.config import (
    batch_ranges,
    check_config,
    exact_settings,
    known_restitutions,
    overlay_per_restitution,
    read_yaml,
    solver_settings,
    shard_batches,
    shard_count,
    shard_settings,
)
from bouncing_ball.workflow.jobs import end_pending_timers
from bouncing_ball.restitution import (
    EXACT_RESTITUTIONS,
    check_distribution_range,
    exact_string,
    parse_restitution,
    restitution_grid,
    restitution_label,
)

# the config files as Snakemake layered them: the Snakefile's, then --configfile overlays
OVERLAYS = [str(path) for path in workflow.overwrite_configfiles]
CONFIG_FILES = [
    str(path) for path in workflow.configfiles if str(path) not in OVERLAYS
] + OVERLAYS
try:
    # refused before any job runs: a key repeated in a file, a float where an integer
    # belongs (the schema check above counts 1.0 as one), what a schema cannot express
    overlay_per_restitution(config, CONFIG_FILES)
    RESTITUTION = check_config(  # {label: exact r}
        config, read_yaml(f"{workflow.basedir}/workflow/schemas/config.schema.yaml")
    )
except ValueError as error:
    raise ValueError(f"invalid config: {error}") from None
# with the r shown in Figs. 4 and 5, which need not be in `restitution`
KNOWN_RESTITUTION = known_restitutions(config)


def code(modules, script):
    """A rule's `code` parameter: a digest of its stage's library modules
    (bouncing_ball.workflow.stages names them without importing them) and of its script, so that
    an edit of either re-runs that rule and what depends on it, and a touch (a checkout,
    a branch switch) re-runs nothing: the default profile turns off Snakemake's
    script-mtime trigger."""
    return source_digest(modules, [f"{workflow.basedir}/scripts/{script}"])


SHARD_CODE = code(stages.SIMULATION, "simulate_shards.py")  # pipeline and study shards

# the r values with an exact solution, eq. (P(0,v)): always computed (Figs. 3 and 5)
EXACT_BY_LABEL = {restitution_label(value): value for value in EXACT_RESTITUTIONS}
EXACT_LABELS = list(EXACT_BY_LABEL)


def restitution_value(wildcards):
    """Exact r of a label: from the config, or the label itself read as a number."""
    if wildcards.r in KNOWN_RESTITUTION:
        return exact_string(KNOWN_RESTITUTION[wildcards.r])
    exact = parse_restitution(wildcards.r, f"r label '{wildcards.r}'")
    if restitution_label(exact) != wildcards.r:
        raise ValueError(
            f"r label '{wildcards.r}' is not canonical: use r{restitution_label(exact)} "
            "(6 significant digits, trailing zeros dropped)"
        )
    return exact_string(exact)


def solve_priority(wildcards):
    """Rule solve: 11 where r > 1/2 (its w(F) takes longer), else 9."""
    return 11 if parse_restitution(restitution_value(wildcards)) > Fraction(1, 2) else 9


def solver_restitution_value(wildcards):
    """``restitution_value``, refused (before any job runs) outside the range of r where P(x, v)
    is verified (rule solve writes the whole distribution)."""
    value = restitution_value(wildcards)
    check_distribution_range(wildcards.r, f"target results/solver/r{wildcards.r}")
    return value


def settings(wildcards):
    """A shard's settings (bouncing_ball.settings.ShardSettings) as the rule's parameter."""
    return shard_settings(config, wildcards.r).as_mapping()


def batch_files(wildcards):
    """The files of the shards of r: one per batch of simulation.shards_per_job shards."""
    return [
        f"results/simulation/r{wildcards.r}/shards{first}-{last}.parquet"
        for first, last in shard_batches(config, wildcards.r)
    ]


def checked_batch(path, wildcards, batches, where):
    """The shards of the batch file ``path``, shards{first}-{last}: first to last, both
    included; refused unless (first, last), as written, is one of ``batches`` ((first,
    last) pairs, ``batch_ranges``), with ``where`` saying whose batches they are."""
    first, last = int(wildcards.first), int(wildcards.last)
    if last < first:
        raise ValueError(
            f"{path}: the last shard ({last}) comes before the first ({first})"
        )
    if (first, last) not in batches or wildcards.first != str(first):
        raise ValueError(
            f"{path}: not a batch of {where}: "
            + ", ".join(f"shards{a}-{b}" for a, b in batches[:8])
            + (", ..." if len(batches) > 8 else "")
        )
    return list(range(first, last + 1))


def batch_shards(wildcards):
    """The shards of a batch file of r (``checked_batch`` against ``shard_batches``)."""
    return checked_batch(
        f"results/simulation/r{wildcards.r}/shards{wildcards.first}-{wildcards.last}.parquet",
        wildcards,
        shard_batches(config, wildcards.r),
        f"the config's shards of r = {wildcards.r} (simulation.shards and shards_per_job)",
    )


def study_batch_shards(wildcards):
    """The shards of a batch file of a study's run (``checked_batch`` against the run's
    batches of simulation.shards_per_job shards; the runs: ``STUDY_RUNS`` of studies.smk).
    """
    run = STUDY_RUNS[wildcards.study].get(wildcards.run)
    return checked_batch(
        f"results/studies/{wildcards.study}/{wildcards.run}/"
        f"shards{wildcards.first}-{wildcards.last}.parquet",
        wildcards,
        study_batch_ranges(run) if run is not None else [],
        "a run of config/studies.yaml (simulation.shards_per_job of the config)",
    )


def study_batch_ranges(run):
    """The batches of a study's run: its shards in batches of simulation.shards_per_job."""
    return batch_ranges(run.shards, int(config["simulation"]["shards_per_job"]))


def batch_provenance(label):
    """What the provenance of every batch file of r = ``label`` records (with its first_shard
    and last_shard): the seed, the simulation code and the shard settings."""
    return {
        "seed": config["seed"],
        "code": SHARD_CODE,
        **shard_settings(config, label).as_mapping(),
    }


def batch_time(label, shards):
    """The simulated time of a batch of ``shards`` shards of r = ``label``."""
    return shards * shard_settings(config, label).shard_time


# the longest batch of the config's r values: the scale of the batches' priorities
LONGEST_BATCH = max(
    batch_time(label, last - first + 1)
    for label in KNOWN_RESTITUTION
    for first, last in shard_batches(config, label)
)


def batch_priority(wildcards):
    """12 for the first batch of the longest (r = 0.75's), else 8.9 times the batch's
    simulated time over the longest batch's: on a few cores one batch starts first and
    compiles the loop while the other cores run the solver (11 where r > 1/2, else 9;
    solve_priority) and the exact solutions (10), so that no second job compiles it at the
    same time; then the longest batches, so that none runs alone at the end."""
    shards = batch_shards(wildcards)
    simulated = batch_time(wildcards.r, len(shards))
    if shards[0] == 0 and simulated >= LONGEST_BATCH:
        return 12
    return round(min(8.9, 8.9 * simulated / LONGEST_BATCH), 2)


# the merged tables of each r (rule merge_shards)
SIMULATION_TABLES = (
    "p0v",
    "position",
    "distribution",
    "flight_time",
    "return_speed",
    "summary",
    "bounce_chain",
)


def simulation_targets():
    """The merged tables and the batch files of every r the config simulates (``restitution``
    and the figures' r): a deleted batch file is made again even where the tables made from
    it are up to date."""
    return expand(
        "results/simulation/r{r}/{table}.parquet",
        r=KNOWN_RESTITUTION,
        table=SIMULATION_TABLES,
    ) + [
        path
        for label in KNOWN_RESTITUTION
        for path in batch_files(SimpleNamespace(r=label))
    ]


def exact_value(wildcards):
    """Exact r of an exact-solution label: 1/2 or 1/3 whatever the config says."""
    if wildcards.r not in EXACT_BY_LABEL:
        raise ValueError(
            f"results/exact/r{wildcards.r}: exact solutions exist only for "
            + " and ".join(
                f"r{label} (r = {exact_string(value)})"
                for label, value in EXACT_BY_LABEL.items()
            )
        )
    return exact_string(EXACT_BY_LABEL[wildcards.r])


def solver_targets():
    return expand(
        "results/solver/r{r}/{table}.parquet",
        r=RESTITUTION,
        table=(
            "p0v",
            "summary",
            "flight_time",
            "return_speed",
            "position",
            "distribution",
            "weight",
        ),
    )


def exact_targets():
    return expand(
        "results/exact/r{r}/{table}.parquet",
        r=EXACT_LABELS,
        table=("p0v", "distribution", "position", "summary"),
    )


def fit_targets():
    return expand("results/fits/r{r}.parquet", r=RESTITUTION)


def figure_labels(figure):
    """The r labels of a figure's panels, config["figures"][figure]."""
    return list(restitution_grid(config["figures"][figure], f"figures.{figure}"))


FIGURE_NUMBERS = range(1, 14)  # Figs. 1-5 the paper's, 6-13 past it


def figure_targets():
    return expand("results/figures/fig{n}.{ext}", n=FIGURE_NUMBERS, ext=("pdf", "png"))


def table_targets():
    return [
        "results/tables/moments.csv",
        "results/tables/moments.md",
        "results/tables/validation.csv",
        "results/tables/validation.md",
        "results/tables/position_asymptotics.csv",
        "results/tables/position_asymptotics.md",
    ]
