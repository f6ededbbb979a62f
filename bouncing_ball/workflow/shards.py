"""Reading the shards of one r back from their batch files, with every check a downstream
step needs (the files: ``batches``)."""

from ..asymptotics import CRITICAL_RESTITUTION
from ..restitution import parse_restitution
from ..settings import ShardSettings
from .audit import differences, stale_message
from .batches import batch_from_table
from .io import UnreadableFileError, read_arrow_table, read_provenance


def _provenance_shards(path, provenance) -> list[int]:
    """The shards a batch file says it holds (``first_shard`` .. ``last_shard``)."""
    first, last = provenance.get("first_shard"), provenance.get("last_shard")
    if not (isinstance(first, int) and isinstance(last, int) and 0 <= first <= last):
        raise UnreadableFileError(
            f"{path}: not a batch of shards (its provenance names first_shard = {first!r}, "
            f"last_shard = {last!r}); make it again with  snakemake --cores 2 --forcerun {path}"
        )
    return list(range(first, last + 1))


def _recorded_no_time(path, shard, provenance) -> UnreadableFileError:
    below = parse_restitution(provenance["r"]) < CRITICAL_RESTITUTION
    advice = (
        f"r = {provenance['r']} is below r_c = {CRITICAL_RESTITUTION:.4f}: the particle collapses onto "
        "the floor (infinitely many collisions in a finite time) and a larger budget cannot help. "
        "Set simulation.min_step_floor (e.g. 1.0e-10, per r under simulation.per_restitution) "
        "to regularise the collapse (docs/methods.md, 'Below r_c')."
        if below and not provenance.get("min_step_floor", 0.0) > 0.0
        else "Raise the budget or shorten equilibration_time, then rerun this batch."
    )
    return UnreadableFileError(
        f"{path}: shard {shard} recorded no time: its step budget (simulation.max_steps = "
        f"{provenance['max_steps']}) ran out during equilibration. {advice}"
    )


def check_batch_provenance(paths, expected: dict) -> None:
    """Refuse batch files whose provenance records another value of a key of ``expected``
    (seed, code, shard settings: what the config asks for now), naming every such file and
    how to make them again (they may be copies of another run, which Snakemake has no
    reason to re-run)."""
    stale = {}
    for path in paths:
        found = differences(read_provenance(path), expected)
        if found:
            stale[str(path)] = found
    if stale:
        files = " ".join(stale)
        raise UnreadableFileError(
            stale_message(
                stale,
                "batch files made with other settings than the config's:",
                "Make them again (your targets, if any, first):  snakemake --cores 2 "
                f"--forcerun {files}",
            )
        )


def read_shards(paths, label, expected: dict | None = None):
    """The tallies of every shard in the batch files ``paths``, in file order, and one
    provenance per shard (its file's, with ``shard`` and, where the file records it, the
    shard's own ``cpu_seconds``).  Checked: every file belongs to r = ``label``, records
    the values of ``expected`` (``check_batch_provenance``) and holds the shards it names,
    all share settings, no shard appears twice, every shard recorded some time; and there
    are two shards at least, since every error bar is the scatter between shards (a
    jackknife)."""
    paths = list(paths)
    if expected is not None:
        check_batch_provenance(paths, expected)
    shards, provenances, first_file = [], [], {}
    for path in paths:
        table, provenance = read_arrow_table(path, label=label)
        named = _provenance_shards(path, provenance)
        if provenances and any(
            provenance.get(key) != provenances[0].get(key)
            for key in ("seed", "code", *ShardSettings.names())
        ):
            raise UnreadableFileError(
                f"{path}: made with other settings than {paths[0]}; rerun the stale batches"
            )
        try:
            batch = batch_from_table(
                table, ShardSettings.from_mapping(provenance), source=str(path)
            )
        except (KeyError, TypeError, ValueError) as error:
            raise UnreadableFileError(f"{path}: malformed batch of shards ({error})") from None
        if sorted(batch) != named:
            raise UnreadableFileError(
                f"{path}: holds shards {sorted(batch)}, not shards {named[0]}-{named[-1]} as it "
                f"says; make it again with  snakemake --cores 2 --forcerun {path}"
            )
        cpu_seconds = provenance.get("cpu_seconds")
        for index, shard in enumerate(named):
            if shard in first_file:
                raise UnreadableFileError(
                    f"{path}: shard {shard} is also in {first_file[shard]}; each shard must be "
                    "counted once"
                )
            first_file[shard] = path
            tallies = batch[shard]
            if not tallies.time > 0.0:
                raise _recorded_no_time(path, shard, provenance)
            own = {key: value for key, value in provenance.items() if key != "cpu_seconds"}
            own["shard"] = shard
            if isinstance(cpu_seconds, list) and len(cpu_seconds) == len(named):
                own["cpu_seconds"] = cpu_seconds[index]
            shards.append(tallies)
            provenances.append(own)
    if len(shards) < 2:
        raise UnreadableFileError(
            f"r = {label}: {len(shards)} shard ({', '.join(map(str, paths)) or 'no file'}); error "
            "bars come from the scatter between shards and need two or more "
            "(simulation.shards >= 2)"
        )
    return shards, provenances
