"""Reading a set of shard files back, with every check a downstream step needs."""

from .config import SHARD_SETTINGS, log_bins
from .io import UnreadableFileError, read_table
from .tallies import tallies_from_frame


def read_shards(paths, label):
    """The tallies of every shard, checked to belong to r = ``label``, to share
    settings, to be distinct shards, and to have recorded some time."""
    shards, provenances = [], []
    for path in paths:
        frame, provenance = read_table(path)
        if provenance.get("r_label") != label:
            raise UnreadableFileError(
                f"{path}: simulated for r = {provenance.get('r_label')}, not r = {label}"
            )
        repeated = [p for p, q in zip(paths, provenances) if q.get("shard") == provenance.get("shard")]
        if repeated:
            raise UnreadableFileError(f"{path}: the same shard as {repeated[0]}")
        if provenances and any(
            provenance.get(key) != provenances[0].get(key)
            for key in ("seed", "code", *SHARD_SETTINGS)
        ):
            raise UnreadableFileError(
                f"{path}: made with other settings than {paths[0]}; rerun the stale shards"
            )
        try:
            shards.append(
                tallies_from_frame(
                    frame,
                    log_bins(provenance["speed_bins"]),
                    log_bins(provenance["position_bins"]),
                    source=str(path),
                )
            )
        except (KeyError, ValueError) as error:
            raise UnreadableFileError(f"{path}: malformed shard ({error})") from None
        if not shards[-1].time > 0.0:
            raise UnreadableFileError(
                f"{path}: recorded no time: its step budget (simulation.max_steps = "
                f"{provenance['max_steps']}) ran out during equilibration. Raise the budget "
                "or shorten equilibration_time, then rerun this shard."
            )
        provenances.append(provenance)
    return shards, provenances
