"""Analyse per-shard JSON: estimates vs solver, scatter vs jackknife, batches, subsets, normality."""

import json
import sys

import numpy as np
from scipy import stats

REF = dict(mean_x=23.70957864, delta_x=35.09414161, rate=0.1137910538)


def load(fn):
    d = json.load(open(fn))
    s = d["shards"]
    a = lambda k: np.array([r[k] for r in s], float)
    return d, a("time"), a("collisions"), a("int_x"), a("int_x2")


def est(t, c, ix, ix2):
    T = t.sum()
    m = ix.sum() / T
    return dict(mean_x=m, delta_x=np.sqrt(ix2.sum() / T - m * m), rate=c.sum() / T)


def jack(t, c, ix, ix2):
    n = len(t)
    full = est(t, c, ix, ix2)
    loo = [est(*(np.delete(v, i) for v in (t, c, ix, ix2))) for i in range(n)]
    out = {}
    for k in full:
        v = np.array([l[k] for l in loo])
        out[k] = (full[k], np.sqrt((n - 1) / n * np.sum((v - v.mean()) ** 2)))
    return out


def rel(k, v, e):
    return 100 * (v / REF[k] - 1), 100 * e / REF[k]


if __name__ == "__main__":
    d, t, c, ix, ix2 = load(sys.argv[1])
    n = len(t)
    print(f"{sys.argv[1]}: {n} shards, T={d['T']:.3g}, c={d['c']}")
    J = jack(t, c, ix, ix2)
    for k, (v, e) in J.items():
        rv, re = rel(k, v, e)
        print(f"  {k:7s} {v:.8f} +- {e:.8f}   {rv:+.4f} +- {re:.4f} %  z={rv / re:+.2f}")
    # per-shard quantities
    ps = {
        k: np.array(
            [est(t[i : i + 1], c[i : i + 1], ix[i : i + 1], ix2[i : i + 1])[k] for i in range(n)]
        )
        for k in REF
    }
    for k, v in ps.items():
        sem = v.std(ddof=1) / np.sqrt(n)
        sw, p = stats.shapiro(v) if n >= 3 else (np.nan, np.nan)
        print(
            f"  per-shard {k:7s}: rel sd {100 * v.std(ddof=1) / v.mean():.4f}%  sem {100 * sem / REF[k]:.4f}%  skew {stats.skew(v):+.2f}  exkurt {stats.kurtosis(v):+.2f}  Shapiro p={p:.3f}  max|z|={np.max(np.abs(v - v.mean())) / v.std(ddof=1):.2f}"
        )
    # batches of 8 shards
    if n >= 32:
        for bs in (4, 8, 16):
            nb = n // bs
            bm = {
                k: np.array(
                    [
                        est(*(v[j * bs : (j + 1) * bs] for v in (t, c, ix, ix2)))[k]
                        for j in range(nb)
                    ]
                )
                for k in REF
            }
            print(
                f"  batches of {bs} ({nb}): "
                + "  ".join(
                    f"{k} err {100 * bm[k].std(ddof=1) / np.sqrt(nb) / REF[k]:.4f}%" for k in REF
                )
            )
    if n >= 64:
        g = 32
        ng = n // g
        print(f"  {ng} groups of {g} shards:")
        gm = {k: [] for k in REF}
        for j in range(ng):
            Jg = jack(*(v[j * g : (j + 1) * g] for v in (t, c, ix, ix2)))
            line = []
            for k, (v, e) in Jg.items():
                rv, re = rel(k, v, e)
                gm[k].append((rv, re))
                line.append(f"{k} {rv:+.4f}+-{re:.4f}% (z {rv / re:+.2f})")
            print("    ", "  ".join(line))
        for k in REF:
            a = np.array(gm[k])
            print(
                f"    {k}: sd of group means {a[:, 0].std(ddof=1):.4f}%  vs mean jackknife err {a[:, 1].mean():.4f}% (ratio {a[:, 0].std(ddof=1) / a[:, 1].mean():.2f})"
            )
