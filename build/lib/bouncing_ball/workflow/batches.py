"""A job's batch of shards: simulated one after the other, stored together in one table.

A shard is the statistical unit (every error bar is the scatter between shards, a
jackknife); a batch is only the unit of work, so that one Python process, with its
start-up and numba's cache load, simulates many shards.  Shard k of r draws from its own
stream, ``simulation.shard_seed_sequence(seed, r label, k)``, whatever batch it is in, so
the tallies do not depend on how the shards are grouped into jobs.

The table of a batch (results/simulation/r{r}/shards{first}-{last}.parquet) is the long
tables of its shards (``tallies.tallies_to_frame``) one after the other, with a first
column ``shard``.
"""

import numpy as np
import pandas as pd

from ..tallies import ShardTallies, tallies_from_frame, tallies_to_frame


def simulate_batch(restitution: float, seed: int, label: str, shards, settings):
    """Yield ``(shard, tallies)`` for each shard of ``shards`` in turn, each on its own stream
    (pure: no I/O; the caller may time each step)."""
    from ..simulation import shard_seed_sequence, simulate_shard  # numba: only where it runs

    for shard in shards:
        yield shard, simulate_shard(restitution, shard_seed_sequence(seed, label, shard), settings)


def batch_to_frame(batch: dict[int, ShardTallies]) -> pd.DataFrame:
    """The table of a batch, ``{shard: tallies}``, in the order of the shards."""
    if not batch:
        raise ValueError("a batch needs at least one shard")
    parts = []
    for shard in sorted(batch):
        frame = tallies_to_frame(batch[shard])
        frame.insert(0, "shard", np.int64(shard))
        parts.append(frame)
    return pd.concat(parts, ignore_index=True)


def batch_from_frame(
    frame: pd.DataFrame, settings, source: str = "batch"
) -> dict[int, ShardTallies]:
    """Inverse of ``batch_to_frame``: ``{shard: tallies}``, each checked to be on the bins of
    ``settings`` (``tallies.tallies_from_frame``); ValueError naming ``source`` otherwise."""
    if "shard" not in frame.columns:
        raise ValueError(f"{source}: missing column 'shard'")
    # a category makes the per-tally row selections of tallies_from_frame cheap
    frame = frame.astype({"tally": "category"})
    return {
        int(shard): tallies_from_frame(rows, settings, source=f"{source}, shard {int(shard)}")
        for shard, rows in frame.groupby("shard", sort=True)
    }
