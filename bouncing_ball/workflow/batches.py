"""A job's batch of shards: simulated one after the other, stored together in one table.

A shard is the statistical unit (every error bar is the scatter between shards, a
jackknife); a batch is only the unit of work, so that one Python process, with its
start-up and numba's cache load, simulates many shards.  Shard k of r draws from its own
stream, ``simulation.shard_seed_sequence(seed, r label, k)``, whatever batch it is in, so
the tallies do not depend on how the shards are grouped into jobs.

The table of a batch (results/simulation/r{r}/shards{first}-{last}.parquet) is
``tallies.batch_to_table``'s: the long tables of its shards one after the other, with a first
column ``shard``, made and read as a pyarrow table, so that a simulation job does not import
pandas (``tallies.batch_to_frame`` and ``batch_from_frame`` are the same as pandas frames).
``SimulationResult.save`` stores its shards in the same table.
"""

from ..tallies import (
    batch_from_frame,
    batch_from_table,
    batch_schema,
    batch_to_frame,
    batch_to_table,
)

__all__ = [
    "BATCH_SCHEMA",
    "simulate_batch",
    "batch_to_table",
    "batch_from_table",
    "batch_to_frame",
    "batch_from_frame",
]

#: The Arrow schema of a batch's table (``tallies.batch_schema``).
BATCH_SCHEMA = batch_schema()


def simulate_batch(restitution: float, seed: int, label: str, shards, settings):
    """Yield ``(shard, tallies)`` for each shard of ``shards`` in turn, each on its own stream
    (pure: no I/O; the caller may time each step)."""
    from ..simulation import shard_seed_sequence, simulate_shard  # numba: only where it runs

    for shard in shards:
        yield shard, simulate_shard(restitution, shard_seed_sequence(seed, label, shard), settings)
