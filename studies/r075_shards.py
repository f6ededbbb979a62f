"""Run N shards at r = 3/4 and save per-shard scalars to JSON as they finish.

usage: python studies/r075_shards.py SEED N SHARD_TIME C OUT.json [FIRST]
The README's 192-shard study (Validation, "r = 3/4"): 20240931 128 3.1e7 3.0 c3.json; 55501 64 3.1e7 5.0 c5.json;
then python studies/r075_analyse.py on the JSON files.
"""

import json
import os
import sys
import time as _t
from concurrent.futures import ProcessPoolExecutor, as_completed

from bouncing_ball.bins import LogBins
from bouncing_ball.restitution import restitution_label
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

R = 0.75


def one(args):
    seed, shard, T, c = args
    ss = shard_seed_sequence(seed, restitution_label(R), shard)
    t0 = _t.time()
    s = simulate_shard(
        R, ss, T, 1e3, c, 500.0, 10**12, LogBins(1e-4, 1e2, 10), LogBins(1e-3, 1e3, 5)
    )
    return dict(
        shard=shard,
        time=float(s.time),
        collisions=int(s.collisions),
        steps=int(s.steps),
        int_x=float(s.int_x),
        int_x2=float(s.int_x2),
        exhausted=int(s.budget_exhausted),
        cpu=_t.time() - t0,
    )


if __name__ == "__main__":
    seed, n, T, c, out = (
        int(sys.argv[1]),
        int(sys.argv[2]),
        float(sys.argv[3]),
        float(sys.argv[4]),
        sys.argv[5],
    )
    first = int(sys.argv[6]) if len(sys.argv) > 6 else 0
    res = []
    if os.path.exists(out):
        res = json.load(open(out))["shards"]
    done = {r["shard"] for r in res}
    todo = [(seed, k, T, c) for k in range(first, first + n) if k not in done]
    with ProcessPoolExecutor(2) as ex:
        futs = [ex.submit(one, a) for a in todo]
        for f in as_completed(futs):
            res.append(f.result())
            json.dump(
                dict(seed=seed, T=T, c=c, r=R, shards=sorted(res, key=lambda r: r["shard"])),
                open(out + ".tmp", "w"),
            )
            os.replace(out + ".tmp", out)
    print("done", len(res))
