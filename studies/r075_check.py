"""<x>, Delta x, I at r = 3/4 with c = 3 (seed 777, 32 shards) and c = 5 (seed 778, 64 shards) against the solver.

usage: python studies/r075_check.py      (about 1000 CPU s on 2 processes; README, Validation, "r = 3/4")
"""

import time
from concurrent.futures import ProcessPoolExecutor

from bouncing_ball.bins import LogBins
from bouncing_ball.histograms import position_moments_summary
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard


def one(args):
    c, k, seed = args
    t0 = time.process_time()
    s = simulate_shard(
        0.75,
        shard_seed_sequence(seed, "0.75", k),
        3.1e7,
        1e3,
        c,
        500.0,
        10**12,
        LogBins(1e-4, 1e2, 10),
        LogBins(1e-3, 1e3, 5),
    )
    return c, k, s, time.process_time() - t0


if __name__ == "__main__":
    jobs = [(3.0, k, 777) for k in range(32)] + [(5.0, k, 778) for k in range(64)]
    out = {3.0: [], 5.0: []}
    cpu = {3.0: 0.0, 5.0: 0.0}
    with ProcessPoolExecutor(2) as pool:
        for c, k, s, sec in pool.map(one, jobs):
            out[c].append(s)
            cpu[c] += sec
    solver = {"mean_x": 23.70957864, "delta_x": 35.09414161, "collision_rate": 0.1137910538}
    for c in (3.0, 5.0):
        row = position_moments_summary(out[c], 0.75).iloc[0]
        msg = [
            f"c={c}: {len(out[c])} shards, CPU {cpu[c]:.0f} s, steps/coll {row.steps / row.collisions:.2f}"
        ]
        for q, ref in solver.items():
            v, e = row[q], row[f"{q}_err"]
            msg.append(
                f"  {q}: {v:.6g} +- {e:.2g} ({100 * (v / ref - 1):+.3f} +- {100 * e / ref:.3f}%), z = {(v - ref) / e:+.2f}"
            )
        print("\n".join(msg), flush=True)
