"""Reading a set of shard files back, with every check a downstream step needs."""

from .asymptotics import CRITICAL_RESTITUTION
from .io import UnreadableFileError, read_table
from .restitution import parse_restitution
from .settings import ShardSettings
from .tallies import tallies_from_frame


def read_shards(paths, label):
    """The tallies of every shard, checked to belong to r = ``label``, to share
    settings, to be distinct shards, and to have recorded some time; and two of them at
    least, since every error bar is the scatter between shards (a jackknife)."""
    paths = list(paths)
    if len(paths) < 2:
        raise UnreadableFileError(
            f"r = {label}: {len(paths)} shard ({', '.join(map(str, paths)) or 'none'}); error "
            "bars come from the scatter between shards and need two or more "
            "(simulation.shards >= 2)"
        )
    shards, provenances = [], []
    for path in paths:
        frame, provenance = read_table(path)
        if provenance.get("r_label") != label:
            raise UnreadableFileError(
                f"{path}: simulated for r = {provenance.get('r_label')}, not r = {label}"
            )
        repeated = [
            p for p, q in zip(paths, provenances) if q.get("shard") == provenance.get("shard")
        ]
        if repeated:
            raise UnreadableFileError(f"{path}: the same shard as {repeated[0]}")
        if provenances and any(
            provenance.get(key) != provenances[0].get(key)
            for key in ("seed", "code", *ShardSettings.names())
        ):
            raise UnreadableFileError(
                f"{path}: made with other settings than {paths[0]}; rerun the stale shards"
            )
        try:
            shards.append(
                tallies_from_frame(frame, ShardSettings.from_mapping(provenance), source=str(path))
            )
        except (KeyError, TypeError, ValueError) as error:
            raise UnreadableFileError(f"{path}: malformed shard ({error})") from None
        if not shards[-1].time > 0.0:
            below = parse_restitution(provenance["r"]) < CRITICAL_RESTITUTION
            advice = (
                f"r = {provenance['r']} is below r_c = {CRITICAL_RESTITUTION:.4f}: the particle collapses onto "
                "the floor (infinitely many collisions in a finite time) and a larger budget cannot help. "
                "Set simulation.min_step_floor (e.g. 1.0e-10, per r under simulation.per_restitution) "
                "to regularise the collapse (docs/methods.md, 'Below r_c')."
                if below and not provenance.get("min_step_floor", 0.0) > 0.0
                else "Raise the budget or shorten equilibration_time, then rerun this shard."
            )
            raise UnreadableFileError(
                f"{path}: recorded no time: its step budget (simulation.max_steps = "
                f"{provenance['max_steps']}) ran out during equilibration. {advice}"
            )
        provenances.append(provenance)
    return shards, provenances
