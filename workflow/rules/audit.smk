# Before any job: do the results on disk belong to this config? (bouncing_ball.workflow.audit)
# Included last: it reads the figure rules' inputs.
import sys
from base64 import urlsafe_b64encode
from pathlib import Path
from types import SimpleNamespace

from bouncing_ball.workflow.audit import (
    figure_differences,
    older_than_inputs,
    stale_message,
    table_differences,
)


def snakemake_has_record(path):
    """Whether Snakemake recorded making ``path`` (its file persistence: .snakemake/metadata,
    one file per output named by its path in URL-safe base64); without a record a
    changed parameter does not re-run the job."""
    name = urlsafe_b64encode(str(path).encode()).decode()
    return Path(".snakemake/metadata", name).exists()


def settings_of(label):
    return shard_settings(config, label).as_mapping()


def stale_simulation():
    """{file: what differs} of the batches of shards and merged tables of every r the config
    simulates."""
    stale = {}
    for label in KNOWN_RESTITUTION:
        for path, (first, last) in zip(
            batch_files(SimpleNamespace(r=label)),
            shard_batches(config, label),
            strict=True,
        ):
            found = table_differences(
                path,
                {"first_shard": first, "last_shard": last, **batch_provenance(label)},
            )
            if found:
                stale[path] = found
        merged = {
            "shards": shard_count(config, label),
            "seed": config["seed"],
            "simulation_code": SHARD_CODE,
            "code": code(stages.MERGE, "merge_shards.py"),
            **settings_of(label),
        }
        for table in SIMULATION_TABLES:
            path = f"results/simulation/r{label}/{table}.parquet"
            found = table_differences(path, merged)
            if found:
                stale[path] = found
    return stale


# the parameters of the rules that write the other tables, as their provenance records them:
# {rule: ({parameter: provenance key}, the r labels of its outputs)}
RECORDED_PARAMETERS = {
    "solve": (
        {"settings": "settings", "speed_bins": "speed_bins", "code": "code"},
        None,
    ),
    "solve_grid": (
        {"grid": "restitution_grid", "step": "quadrature_step", "code": "code"},
        None,
    ),
    "exact_solution": ({"settings": "settings", "code": "code"}, EXACT_LABELS),
    "theory": ({"grid": "restitution_grid", "code": "code"}, None),
    "fit": ({"settings": "settings", "code": "code"}, None),
}


def rule_parameters(maker, label):
    """{name: value} of a rule's parameters for the outputs of r = ``label``."""
    wildcards = SimpleNamespace(r=label)
    return {
        name: value(wildcards) if callable(value) else value
        for name, value in maker.params.items()
    }


def stale_tables():
    """{table: what differs} of the solver's, the exact solutions', the theory's and the fits'
    tables: every setting of their rule's parameters, as each table's provenance records it.
    """
    stale = {}
    for name, (recorded, labels) in RECORDED_PARAMETERS.items():
        maker = getattr(rules, name).rule
        wildcard = "r" in maker.wildcard_names
        for label in (labels or KNOWN_RESTITUTION) if wildcard else [None]:
            parameters = rule_parameters(maker, label)
            expected = {
                key: parameters[parameter] for parameter, key in recorded.items()
            }
            for pattern in maker.output:
                path = (
                    str(pattern.apply_wildcards({"r": label}))
                    if wildcard
                    else str(pattern)
                )
                found = table_differences(path, expected)
                if found:
                    stale[path] = found
    return stale


# the rules whose outputs the report shows: the figures and the tables
REPORTED_RULES = [f"fig{n}" for n in FIGURE_NUMBERS] + [
    "moments_table",
    "validation_table",
    "position_asymptotics",
]


def stale_figures():
    """{figure: why} of the figures not drawn from what the config asks for now, or with
    other settings (their rule's parameters, which the PNG's provenance records)."""
    stale = {}
    for n in FIGURE_NUMBERS:
        drawing = getattr(rules, f"fig{n}").rule
        png = f"results/figures/fig{n}.png"
        found = figure_differences(png, drawing.input, rule_parameters(drawing, None))
        if found:
            stale[png] = found
    return stale


def stale_reported():
    """{output: why} of the figures and tables the report shows that are missing, or older
    than an input (not made from the files on disk)."""
    stale = {}
    for name in REPORTED_RULES:
        maker = getattr(rules, name).rule
        for path in map(str, maker.output):
            missing = [
                str(source) for source in maker.input if not Path(source).exists()
            ]
            found = [f"its inputs {', '.join(missing)} do not exist"] if missing else []
            if not Path(path).exists():
                found.append("it does not exist")
            else:
                found += older_than_inputs(path, maker.input)
            if found:
                stale[path] = found
    return stale


def combined(*stale):
    """{file: every reason} of several {file: reasons}."""
    reasons = {}
    for found in stale:
        for path, why in found.items():
            reasons.setdefault(path, []).extend(why)
    return reasons


# `--report FILE` alone makes the report of what is on disk; with `--report-after-run`
# Snakemake runs the workflow first (checked as any run) and reports what it made
MAKING_REPORT = (
    any(
        argument == "--report" or argument.startswith("--report=")
        for argument in sys.argv
    )
    and "--report-after-run" not in sys.argv
)
if MAKING_REPORT:
    # the report shows what is on disk: all of it must be this config's
    STALE = combined(
        stale_simulation(), stale_tables(), stale_figures(), stale_reported()
    )
    if STALE:
        raise WorkflowError(
            stale_message(
                STALE,
                "the report would caption results that are not this config's:",
                "Make the report with the config of the run that made them (the same "
                "--configfile), or run snakemake --cores 2 with this config first.",
            )
        )
else:
    # Snakemake re-runs these itself where it has a record of making them
    STALE = {
        path: found
        for path, found in combined(
            stale_simulation(), stale_tables(), stale_figures()
        ).items()
        if not snakemake_has_record(path)
    }
    if STALE:
        raise WorkflowError(
            stale_message(
                STALE,
                "results made for another config, which Snakemake has no record of "
                "making (.snakemake/ removed, or results/ copied), so it would keep them:",
                "Remove them (they are not this config's) and run again: rm "
                + " ".join(sorted(STALE)),
            )
        )
