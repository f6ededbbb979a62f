"""What one simulation shard records, and merging shards (a sum).

A shard is stored as one long table, a row per tally entry:

    tally               lo     hi     value
    outgoing_speed      v_lo   v_hi   collisions with v_out in [v_lo, v_hi)
    position_time       x_lo   x_hi   time spent with x in [x_lo, x_hi)
    position_v2_time    x_lo   x_hi   int v^2 dt over that time
    time, collisions, steps, int_x, int_x2, budget_exhausted
                        NaN    NaN    the scalar

Every entry is additive over shards, so merging is a sum.
"""

from dataclasses import dataclass, fields, replace

import numpy as np
import pandas as pd

from .bins import LogBins

HISTOGRAMS = {
    "outgoing_speed": ("speed_bins", "speed_counts"),
    "position_time": ("position_bins", "position_time"),
    "position_v2_time": ("position_bins", "position_v2_time"),
}
SCALARS = ("time", "collisions", "steps", "int_x", "int_x2", "budget_exhausted")
_INTEGER = ("collisions", "steps", "budget_exhausted")


@dataclass(frozen=True)
class ShardTallies:
    speed_bins: LogBins
    position_bins: LogBins
    speed_counts: np.ndarray
    position_time: np.ndarray
    position_v2_time: np.ndarray
    time: float
    collisions: int
    steps: int
    int_x: float
    int_x2: float
    budget_exhausted: int  # number of shards that ran out of their step budget

    @staticmethod
    def loop_arrays(speed_bins, position_bins):
        """Zeroed arrays a compiled shard loop fills: speed counts, time and int v^2 dt per x bin
        (each with under- and overflow), and the scalars in the order of ``SCALARS``."""
        return (
            np.zeros(speed_bins.n + 2, dtype=np.int64),
            np.zeros(position_bins.n + 2),
            np.zeros(position_bins.n + 2),
            np.zeros(len(SCALARS)),
        )

    @classmethod
    def from_loop(
        cls, speed_bins, position_bins, speed_counts, position_time, position_v2_time, scalars
    ):
        """The tallies of a compiled shard loop: its three histograms and its scalar array,
        ordered as ``SCALARS`` (the numba loop and its C reference both fill them so)."""
        values = dict(zip(SCALARS, scalars))
        for name in _INTEGER:
            values[name] = int(values[name])
        return cls(
            speed_bins=speed_bins,
            position_bins=position_bins,
            speed_counts=speed_counts,
            position_time=position_time,
            position_v2_time=position_v2_time,
            **values,
        )

    def __add__(self, other: "ShardTallies") -> "ShardTallies":
        if (self.speed_bins, self.position_bins) != (other.speed_bins, other.position_bins):
            raise ValueError("cannot merge shards recorded on different bins")
        summed = {
            f.name: getattr(self, f.name) + getattr(other, f.name)
            for f in fields(self)
            if f.name not in ("speed_bins", "position_bins")
        }
        return replace(self, **summed)


def merge_shards(shards) -> ShardTallies:
    """Sum the tallies of several shards (order does not matter)."""
    shards = list(shards)
    if not shards:
        raise ValueError("no shards to merge")
    total = shards[0]
    for shard in shards[1:]:
        total = total + shard
    return total


def tallies_to_frame(tallies: ShardTallies) -> pd.DataFrame:
    parts = []
    for name, (bins_attr, values_attr) in HISTOGRAMS.items():
        bins = getattr(tallies, bins_attr)
        parts.append(
            pd.DataFrame(
                {
                    "tally": name,
                    "lo": bins.lower,
                    "hi": bins.upper,
                    "value": np.asarray(getattr(tallies, values_attr), dtype=float),
                }
            )
        )
    parts.append(
        pd.DataFrame(
            {
                "tally": list(SCALARS),
                "lo": np.nan,
                "hi": np.nan,
                "value": [float(getattr(tallies, s)) for s in SCALARS],
            }
        )
    )
    return pd.concat(parts, ignore_index=True)


def tallies_from_frame(
    frame: pd.DataFrame, speed_bins: LogBins, position_bins: LogBins, source: str = "shard"
) -> ShardTallies:
    """Inverse of ``tallies_to_frame``; checks that the bins are the expected ones."""
    missing = {"tally", "lo", "hi", "value"} - set(frame.columns)
    if missing:
        raise ValueError(f"{source}: missing columns {sorted(missing)}")
    values = {}
    bins_of = {"speed_bins": speed_bins, "position_bins": position_bins}
    for name, (bins_attr, values_attr) in HISTOGRAMS.items():
        rows = frame[frame["tally"] == name]
        bins = bins_of[bins_attr]
        if len(rows) != bins.n + 2 or not np.allclose(rows["lo"].to_numpy(), bins.lower):
            raise ValueError(
                f"{source}: tally '{name}' is not on the configured bins "
                f"({len(rows)} rows, expected {bins.n + 2}); re-run the shard"
            )
        column = rows["value"].to_numpy()
        values[values_attr] = column.astype(np.int64) if name == "outgoing_speed" else column
    for name in SCALARS:
        rows = frame.loc[frame["tally"] == name, "value"]
        if len(rows) != 1:
            raise ValueError(f"{source}: expected one '{name}' row, found {len(rows)}")
        value = float(rows.iloc[0])
        values[name] = int(value) if name in _INTEGER else value
    return ShardTallies(speed_bins=speed_bins, position_bins=position_bins, **values)
