"""A job's batch of shards: simulated one after the other, stored together in one table.

A shard is the statistical unit (every error bar is the scatter between shards, a
jackknife); a batch is only the unit of work, so that one Python process, with its
start-up and numba's cache load, simulates many shards.  Shard k of r draws from its own
stream, ``simulation.shard_seed_sequence(seed, r label, k)``, whatever batch it is in, so
the tallies do not depend on how the shards are grouped into jobs.

The table of a batch (results/simulation/r{r}/shards{first}-{last}.parquet) is the long
tables of its shards (``tallies.tallies_to_columns``) one after the other, with a first
column ``shard``.  It is made and read as a pyarrow table, so that a simulation job does
not import pandas; ``batch_to_frame`` and ``batch_from_frame`` are the same as pandas frames.
"""

from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from ..tallies import COLUMNS, ShardTallies, tallies_from_columns, tallies_to_columns

if TYPE_CHECKING:
    import pandas as pd

#: The Arrow schema of a batch's table (pandas writes its str columns as large_string).
BATCH_SCHEMA = pa.schema(
    [
        ("shard", pa.int64()),
        ("tally", pa.large_string()),
        *((column, pa.float64()) for column in COLUMNS[1:]),
    ]
)


def simulate_batch(restitution: float, seed: int, label: str, shards, settings):
    """Yield ``(shard, tallies)`` for each shard of ``shards`` in turn, each on its own stream
    (pure: no I/O; the caller may time each step)."""
    from ..simulation import shard_seed_sequence, simulate_shard  # numba: only where it runs

    for shard in shards:
        yield shard, simulate_shard(restitution, shard_seed_sequence(seed, label, shard), settings)


def _arrow_array(values: np.ndarray, kind: pa.DataType) -> pa.Array:
    """``values`` as an Arrow array of ``kind`` (int64, float64 or large_string) made from its
    buffers: ``pyarrow.array`` would import pandas to look at its argument."""
    if kind == pa.large_string():
        encoded = [str(value).encode() for value in values]
        offsets = np.zeros(len(encoded) + 1, dtype=np.int64)
        np.cumsum([len(value) for value in encoded], out=offsets[1:])
        buffers = [None, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))]
    else:
        buffers = [None, pa.py_buffer(np.ascontiguousarray(values, dtype=kind.to_pandas_dtype()))]
    return pa.Array.from_buffers(kind, len(values), buffers)


def batch_to_table(batch: dict[int, ShardTallies]) -> pa.Table:
    """The table of a batch, ``{shard: tallies}``, in the order of the shards (``BATCH_SCHEMA``)."""
    if not batch:
        raise ValueError("a batch needs at least one shard")
    parts = {shard: tallies_to_columns(batch[shard]) for shard in sorted(batch)}
    columns = {
        "shard": np.concatenate(
            [np.full(len(part["value"]), shard, dtype=np.int64) for shard, part in parts.items()]
        ),
        **{key: np.concatenate([part[key] for part in parts.values()]) for key in COLUMNS},
    }
    return pa.Table.from_arrays(
        [_arrow_array(columns[field.name], field.type) for field in BATCH_SCHEMA],
        schema=BATCH_SCHEMA,
    )


def batch_to_frame(batch: dict[int, ShardTallies]) -> "pd.DataFrame":
    """The table of a batch (``batch_to_table``) as a pandas frame."""
    return batch_to_table(batch).to_pandas()


def batch_from_table(table: pa.Table, settings, source: str = "batch") -> dict[int, ShardTallies]:
    """Inverse of ``batch_to_table``: ``{shard: tallies}``, each checked to be on the bins of
    ``settings`` (``tallies.tallies_from_columns``); ValueError naming ``source`` otherwise."""
    if "shard" not in table.column_names:
        raise ValueError(f"{source}: missing column 'shard'")
    missing = set(COLUMNS) - set(table.column_names)
    if missing:
        raise ValueError(f"{source}: missing columns {sorted(missing)}")
    if table.num_rows == 0:
        return {}
    shard = table.column("shard").to_numpy()
    columns = {key: table.column(key).to_numpy() for key in COLUMNS}
    # each shard's rows in their order (a stable sort: the table's order within a shard)
    order = np.argsort(shard, kind="stable")
    shards, starts = np.unique(shard[order], return_index=True)
    batch = {}
    for number, rows in zip(shards, np.split(order, starts[1:]), strict=True):
        batch[int(number)] = tallies_from_columns(
            {key: column[rows] for key, column in columns.items()},
            settings,
            source=f"{source}, shard {int(number)}",
        )
    return batch


def batch_from_frame(
    frame: "pd.DataFrame", settings, source: str = "batch"
) -> dict[int, ShardTallies]:
    """``batch_from_table`` of a pandas frame (``batch_to_frame``)."""
    if "shard" not in frame.columns:
        raise ValueError(f"{source}: missing column 'shard'")
    return batch_from_table(pa.Table.from_pandas(frame, preserve_index=False), settings, source)
