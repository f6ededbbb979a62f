# Before any job: do the results on disk belong to this config? (bouncing_ball.audit)
# Included last: it reads the figure rules' inputs.
import sys
from base64 import urlsafe_b64encode
from pathlib import Path
from types import SimpleNamespace

from bouncing_ball.audit import (
    figure_differences,
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
        asked = settings_of(label)
        batch = {"seed": config["seed"], "code": SHARD_CODE, **asked}
        for path, (first, last) in zip(
            batch_files(SimpleNamespace(r=label)),
            shard_batches(config, label),
            strict=True,
        ):
            found = table_differences(
                path, {"first_shard": first, "last_shard": last, **batch}
            )
            if found:
                stale[path] = found
        merged = {
            "shards": shard_count(config, label),
            "seed": config["seed"],
            "simulation_code": SHARD_CODE,
            "code": code(stages.MERGE, "merge_shards.py"),
            **asked,
        }
        for table in SIMULATION_TABLES:
            path = f"results/simulation/r{label}/{table}.parquet"
            found = table_differences(path, merged)
            if found:
                stale[path] = found
    return stale


def stale_figures():
    """{figure: why} of the figures not drawn from what the config asks for now."""
    stale = {}
    for n in FIGURE_NUMBERS:
        drawing = getattr(rules, f"fig{n}").rule
        png = f"results/figures/fig{n}.png"
        found = figure_differences(png, drawing.input)
        missing = [str(path) for path in drawing.input if not Path(path).exists()]
        if missing:
            found = (found or []) + [f"its inputs {', '.join(missing)} do not exist"]
        if found:
            stale[png] = found
    return stale


MAKING_REPORT = any(argument.startswith("--report") for argument in sys.argv)
if MAKING_REPORT:
    # the report shows what is on disk: all of it must be this config's
    STALE = stale_simulation() | stale_figures()
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
        for path, found in stale_simulation().items()
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
