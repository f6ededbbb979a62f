"""c = 3 vs c = 5 (eq. (criterion)) against the exact results at r = 1/2, 1/3.

usage:  python studies/criterion_bias.py run C R SHARD_TIME FIRST LAST   (appends shards to results.json in $STUDY_DIR or .)
        python studies/criterion_bias.py analyse                         (prints the report numbers)

The README numbers (Performance, "c = 3"): run 3 1/2 2e7 0 32 and run 3 1/3 8.5e6 0 32 (about 700 CPU s each).
"""

import json
import os
import sys
import time
from fractions import Fraction

import numpy as np

from bouncing_ball import exact
from bouncing_ball.bins import LogBins
from bouncing_ball.histograms import jackknife, outgoing_speed_density
from bouncing_ball.restitution import restitution_label
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard

# (run from a copy of the package so that edits do not change a running study)
HERE = os.environ.get("STUDY_DIR", os.getcwd())
RESULTS = os.path.join(HERE, "results.json")
SEED = 31415926
SPEED_BINS = LogBins(1e-4, 1e2, 10)
POSITION_BINS = LogBins(1e-3, 1e3, 5)
RS = {"1/2": Fraction(1, 2), "1/3": Fraction(1, 3)}


def load():
    if os.path.exists(RESULTS):
        with open(RESULTS) as f:
            return json.load(f)
    return []


def save(rows):
    tmp = RESULTS + ".tmp"
    with open(tmp, "w") as f:
        json.dump(rows, f)
    os.replace(tmp, RESULTS)


def run(c, rkey, shard_time, first, last):
    r = RS[rkey]
    for k in range(first, last):
        t0 = time.process_time()
        s = simulate_shard(
            float(r),
            shard_seed_sequence(SEED, restitution_label(r), k),
            shard_time,
            1e3,
            float(c),
            500.0,
            10**12,
            SPEED_BINS,
            POSITION_BINS,
        )
        cpu = time.process_time() - t0
        rows = load()
        rows.append(
            dict(
                c=float(c),
                r=rkey,
                shard=k,
                shard_time=shard_time,
                cpu=cpu,
                time=s.time,
                collisions=s.collisions,
                steps=s.steps,
                int_x=s.int_x,
                int_x2=s.int_x2,
                exhausted=int(s.budget_exhausted),
                speed_counts=s.speed_counts.tolist(),
            )
        )
        save(rows)
        print(
            f"c={c} r={rkey} shard {k}: cpu {cpu:.1f}s, coll {s.collisions}, I {s.collisions / s.time:.5f}, "
            f"steps/coll {s.steps / s.collisions:.2f}",
            flush=True,
        )


def group(rows, c, rkey):
    g = sorted([x for x in rows if x["c"] == c and x["r"] == rkey], key=lambda x: x["shard"])
    return g


def analyse_group(g, rkey):
    r = RS[rkey]
    ex = exact.position_moments(r)
    T = np.array([x["time"] for x in g])
    C = np.array([x["collisions"] for x in g], float)
    IX = np.array([x["int_x"] for x in g])
    IX2 = np.array([x["int_x2"] for x in g])
    cpu = sum(x["cpu"] for x in g)
    steps = sum(x["steps"] for x in g)
    out = {
        "shards": len(g),
        "cpu": cpu,
        "collisions": C.sum(),
        "steps_per_coll": steps / C.sum(),
        "coll_per_cpu": C.sum() / cpu,
        "exhausted": sum(x["exhausted"] for x in g),
    }
    for name, est, args, key in [
        ("I", lambda c, t: c / t, (C, T), "collision_rate"),
        ("mean_x", lambda a, t: a / t, (IX, T), "mean_x"),
        ("delta_x", lambda a, b, t: np.sqrt(b / t - (a / t) ** 2), (IX, IX2, T), "delta_x"),
    ]:
        v, e = jackknife(est, *args)
        out[name] = (
            float(v),
            float(e),
            float((v - ex[key]) / e),
            float(v / ex[key] - 1),
            float(e / ex[key]),
        )
    out["relerrI2_cpu"] = out["I"][4] ** 2 * cpu
    # P(0,v)
    lo, hi = SPEED_BINS.lower, SPEED_BINS.upper
    counts = np.array([x["speed_counts"] for x in g], float)
    p, pe = jackknife(lambda c, t: outgoing_speed_density(c, t, lo, hi), counts, T[:, None])
    use = (counts.sum(0) >= 50) & np.isfinite(hi) & (lo > 0)
    lo_u, hi_u = lo[use], hi[use]
    e = exact.outgoing_speed_bin_average(lo_u, hi_u, r)
    z = (p[use] - e) / pe[use]
    out["p0v_n"] = int(use.sum())
    out["p0v_chi2n"] = float(np.mean(z**2))
    out["p0v_signs"] = "".join("+" if zz > 0 else "-" for zz in z)
    out["p0v_z"] = np.round(z, 2).tolist()
    out["p0v_vrange"] = (float(lo_u[0]), float(hi_u[-1]))
    # tilt: relative deviation = a + b log10 v, weighted LS with merged errors; error from per-shard scatter
    per = outgoing_speed_density(counts[:, use], T[:, None], lo_u, hi_u) / e - 1.0
    lv = np.log10(np.sqrt(lo_u * hi_u))
    w = (e / pe[use]) ** 2
    X = np.stack([np.ones_like(lv), lv - np.average(lv, weights=w)], 1)
    A = np.linalg.solve(X.T @ (w[:, None] * X), (X * w[:, None]).T)
    coef = per @ A.T  # per-shard (offset, slope)
    n = len(g)
    m = coef.mean(0)
    se = coef.std(0, ddof=1) / np.sqrt(n)
    out["p0v_offset"] = (float(m[0]), float(se[0]))
    out["p0v_tilt_per_decade"] = (float(m[1]), float(se[1]))
    # sign-flip p for chi^2 (bin correlations), as tests/shard_statistics.py
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
    from shard_statistics import sign_flip_p_values

    chi2, p_chi2, p_worst = sign_flip_p_values(per * e)
    out["p0v_signflip"] = (chi2, float(p_chi2), float(p_worst))
    return out


def paired(rows, rkey):
    a = {x["shard"]: x for x in group(rows, 3.0, rkey)}
    b = {x["shard"]: x for x in group(rows, 5.0, rkey)}
    ks = sorted(set(a) & set(b))
    if len(ks) < 3:
        return None
    Ia = np.array([a[k]["collisions"] / a[k]["time"] for k in ks])
    Ib = np.array([b[k]["collisions"] / b[k]["time"] for k in ks])
    d = (Ia - Ib) / Ib.mean()
    return {
        "shards": len(ks),
        "rel_diff_I_c3_minus_c5": (float(d.mean()), float(d.std(ddof=1) / np.sqrt(len(ks)))),
        "corr": float(np.corrcoef(Ia, Ib)[0, 1]),
        "cpu_ratio_c3_over_c5": sum(a[k]["cpu"] for k in ks) / sum(b[k]["cpu"] for k in ks),
        "steps_ratio": sum(a[k]["steps"] for k in ks) / sum(b[k]["steps"] for k in ks),
    }


if __name__ == "__main__":
    if sys.argv[1] == "run":
        run(float(sys.argv[2]), sys.argv[3], float(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6]))
    else:
        rows = load()
        for c in (3.0, 5.0):
            for rk in RS:
                g = group(rows, c, rk)
                if len(g) >= 3:
                    print(f"== c={c} r={rk}")
                    print(json.dumps(analyse_group(g, rk)))
        for rk in RS:
            p = paired(rows, rk)
            if p:
                print(f"== paired r={rk}", json.dumps(p))
