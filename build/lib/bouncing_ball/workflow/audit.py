"""Do the results on disk belong to the config?  Provenance read back and compared.

Snakemake re-runs a job whose parameters changed only if it has a record of the
run that made its output (``.snakemake/metadata``): with that folder gone, or
``results/`` copied from another clone, a changed ``shards`` or ``shard_time``
would leave the old tables in place and say "Nothing to be done".  And
``snakemake --report`` never re-runs anything: it shows what is on disk,
captioned from the config it is given.  So the workflow reads back the
provenance every table and figure carries (``io.write_table``,
``plotting.save_figure``) and compares it with what the config asks
(workflow/rules/audit.smk), before any job runs.
"""

import json
from pathlib import Path

from .io import UnreadableFileError, read_provenance


def differences(provenance: dict, expected: dict) -> list[str]:
    """``key = recorded (config: asked)`` for every key of ``expected`` the provenance
    records otherwise (JSON round trip: numbers and nested mappings compare exactly); in a
    nested mapping, only the keys that differ (``settings.positions = ...``)."""
    expected = json.loads(json.dumps(expected, default=str))
    found = []
    for key, value in expected.items():
        recorded = provenance.get(key)
        if recorded == value:
            continue
        if isinstance(recorded, dict) and isinstance(value, dict):
            found += [f"{key}.{difference}" for difference in differences(recorded, value)]
            found += [
                f"{key}.{extra} = {recorded[extra]!r} (config: none)"
                for extra in recorded
                if extra not in value
            ]
        else:
            found.append(f"{key} = {recorded!r} (config: {value!r})")
    return found


def table_differences(path, expected: dict) -> list[str] | None:
    """``differences`` of an existing table's provenance; None if there is no such file.
    An unreadable file counts as differing (it must be made again)."""
    if not Path(path).exists():
        return None
    try:
        provenance = read_provenance(path)
    except UnreadableFileError as error:
        return [str(error)]
    return differences(provenance, expected)


def figure_provenance(png) -> dict | None:
    """The provenance ``plotting.save_figure`` wrote into a PNG, None if it has none."""
    from PIL import Image  # matplotlib's own PNG library

    try:
        with Image.open(png) as image:
            description = image.text.get("Description")
    except OSError:
        return None
    try:
        return json.loads(description) if description else None
    except json.JSONDecodeError:
        return None


def figure_differences(png, inputs, params: dict) -> list[str] | None:
    """Why an existing figure is not the one its rule would draw now from ``inputs`` with
    ``params`` (its settings: those its caption names among them); None if there is no
    such file."""
    if not Path(png).exists():
        return None
    provenance = figure_provenance(png)
    if provenance is None:
        return ["no provenance in its metadata"]
    found = []
    drawn, asked = list(provenance.get("inputs", [])), [str(path) for path in inputs]
    if drawn != asked:
        found.append(f"drawn from {', '.join(drawn)}; the config asks for {', '.join(asked)}")
    return found + differences(provenance.get("params", {}), params)


def older_than_inputs(path, inputs) -> list[str]:
    """The inputs of an existing output that are newer than it (it was not made from them)."""
    made = Path(path).stat().st_mtime_ns
    return [
        f"its input {source} is newer"
        for source in map(str, inputs)
        if Path(source).exists() and Path(source).stat().st_mtime_ns > made
    ]


def stale_message(stale: dict, why: str, remedy: str) -> str:
    """The message that refuses to go on: each file, what differs, and what to do."""
    lines = [why]
    for path, found in stale.items():
        lines.append(f"  {path}: " + "; ".join(found))
    lines.append(remedy)
    return "\n".join(lines)
