"""Prototype: RESTART importance splitting for the rare P(0, v) bins (no solver, no kernel).

Not used by the workflow: it measures what splitting would buy the bins the paper's Fig. 4
needs (the large-v tail at r = 0.25, the small-v end at r = 0.75), where the martingale
control variates give nothing (docs/performance.md, 'Control variates').

The loop is the simulation's stepping (``simulation._run`` without the tallies: same
criterion, delta rule, free flight, collision on the bridge's mean path, the same normals
from the shard's stream), so the main trajectory and its plain outgoing-speed counts are
those of ``simulation.simulate_shard`` bit for bit.  Splitting (Villen-Altamirano's
RESTART): the importance function is phi = sign ln E, E = x + v^2/2 (the ball lands with
speed sqrt(2 E)), sign = +1 for the large-v tail and -1 for the small-v end, with levels
phi_1 < phi_2 < ...; a trajectory whose state at the end of a step has crossed level j upward
is split into R_j copies (nested when a step crosses several levels), each further copy
continuing independently (its own generator) and killed at the end of the first step where
phi is back below the level it was born at; the main trajectory is never killed.  A
collision is counted with weight 1 / (R_1 ... R_k), k the region (number of levels below
phi) of the step's start.  Each copy born at level j follows the law of the main trajectory
from the same state until that stopping time, so the weighted counts have the plain counts'
expectation, for any levels and factors: only the variance and the cost depend on them.

    python -m benchmarks.restart_prototype R SIGN SHARD_TIME SHARDS SEED U_LEVELS FACTORS
        [--criterion-c 3] [--divisor 500] [--plain]

U_LEVELS are the levels as speeds u = sqrt(2 E) (JSON list), FACTORS the R_j (JSON list).
It prints per bin the plain and the split estimate of the collision rate in the bin, their
jackknife errors, the CPU and the share of steps spent in the copies, and at r = 1/2, 1/3
the ratio to the exact bin average.
"""

import argparse
import json
import math
import time
from fractions import Fraction

import numpy as np

from bouncing_ball.free_flight import (
    cubic_slope,
    first_crossing_time,
    free_flight_step,
    hermite_cubic,
    largest_safe_step,
)
from bouncing_ball.jit import njit
from bouncing_ball.simulation import _bin_index, shard_seed_sequence

SPEED_EDGES = np.geomspace(1e-4, 1e2, 61)  # the default config's speed bins
STACK = 200_000  # copies waiting to be run, at most


@njit(cache=True)
def _region(x, v, sign, levels):
    energy = x + 0.5 * v * v
    phi = sign * math.log(energy) if energy > 0.0 else -1e300 * sign
    k = 0
    while k < levels.shape[0] and phi >= levels[k]:
        k += 1
    return k


@njit(cache=True)
def _step(x, v, delta, t, t_stop, c, rng):
    dt = largest_safe_step(x, v, c) + delta
    if t + dt > t_stop:
        dt = t_stop - t
    normal_r = rng.standard_normal()
    normal_s = rng.standard_normal()
    x1, v1 = free_flight_step(x, v, dt, normal_r, normal_s)
    a0, a1, a2, a3 = hermite_cubic(x, v, x1, v1, dt)
    if x1 < 0.0:
        tau = first_crossing_time(a0, a1, a2, a3, dt, x1)
        return True, tau, 0.0, cubic_slope(a1, a2, a3, tau)
    return False, dt, x1, v1


@njit(cache=True)
def _push(stack, top, x, v, delta, t, old, new, factors):
    """The copies of a state that crossed levels old + 1 .. new: (R_j - 1) prod_{old<l<j} R_l
    born at each level j.  Returns the new top of the stack, -1 if it is full."""
    multiple = 1
    for j in range(old + 1, new + 1):
        for _ in range((factors[j - 1] - 1) * multiple):
            if top >= stack.shape[0]:
                return -1
            stack[top, 0] = x
            stack[top, 1] = v
            stack[top, 2] = delta
            stack[top, 3] = t
            stack[top, 4] = j
            stack[top, 5] = new
            top += 1
        multiple *= factors[j - 1]
    return top


@njit(cache=True)
def _run(
    rng,
    rng_split,
    r,
    c,
    divisor,
    equilibration_time,
    recorded_time,
    v_edges,
    sign,
    levels,
    factors,
    counts_main,
    counts_split,
    stats,
):
    nv = v_edges.shape[0] - 1
    v_log_lo = math.log(v_edges[0])
    v_per_ln = nv / (math.log(v_edges[nv]) - v_log_lo)
    weights = np.ones(levels.shape[0] + 1)
    for k in range(1, levels.shape[0] + 1):
        weights[k] = weights[k - 1] / factors[k - 1]
    stack = np.empty((STACK, 6))
    x, v = 1.0, 0.0
    root = 1.0 / divisor
    delta = 0.5 * root * root
    recording = equilibration_time <= 0.0
    t = 0.0
    t_stop = recorded_time if recording else equilibration_time
    region = _region(x, v, sign, levels)
    main_steps = 0
    copy_steps = 0
    overflow = 0
    while True:
        if t >= t_stop:
            if recording:
                break
            recording = True
            t = 0.0
            t_stop = recorded_time
            continue
        collided, tau, x1, v1 = _step(x, v, delta, t, t_stop, c, rng)
        main_steps += 1
        t += tau
        if collided:
            v_out = r * abs(v1)
            if recording:
                b = _bin_index(v_out, v_log_lo, v_per_ln, nv, v_edges)
                counts_main[b] += 1
                counts_split[b] += weights[region]
            x, v = 0.0, v_out
            root_2delta = v_out * root
            delta = 0.5 * root_2delta * root_2delta
        else:
            x, v = x1, v1
        new = _region(x, v, sign, levels)
        if recording and new > region:
            top = _push(stack, 0, x, v, delta, t, region, new, factors)
            if top < 0:
                overflow += 1
                top = 0
            while top > 0:  # the copies, depth first, each until it is killed
                top -= 1
                cx, cv, cdelta, ct = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3]
                birth, cregion = int(stack[top, 4]), int(stack[top, 5])
                while ct < t_stop:
                    ccollided, ctau, cx1, cv1 = _step(cx, cv, cdelta, ct, t_stop, c, rng_split)
                    copy_steps += 1
                    ct += ctau
                    if ccollided:
                        c_out = r * abs(cv1)
                        b = _bin_index(c_out, v_log_lo, v_per_ln, nv, v_edges)
                        counts_split[b] += weights[cregion]
                        cx, cv = 0.0, c_out
                        root_2delta = c_out * root
                        cdelta = 0.5 * root_2delta * root_2delta
                    else:
                        cx, cv = cx1, cv1
                    cnew = _region(cx, cv, sign, levels)
                    if cnew < birth:
                        break
                    if cnew > cregion:
                        pushed = _push(stack, top, cx, cv, cdelta, ct, cregion, cnew, factors)
                        if pushed < 0:
                            overflow += 1
                        else:
                            top = pushed
                    cregion = cnew
        region = new
    stats[0] = t
    stats[1] = main_steps
    stats[2] = copy_steps
    stats[3] = overflow


def shard(
    r,
    label,
    seed,
    index,
    recorded_time,
    sign,
    u_levels,
    factors,
    criterion_c=3.0,
    divisor=500.0,
    equilibration_time=1.0e3,
):
    """(plain counts, split counts, [time, main steps, copy steps, overflows], CPU s)."""
    stream = shard_seed_sequence(seed, label, index)
    rng = np.random.Generator(np.random.PCG64(stream))
    split_stream = np.random.SeedSequence(stream.entropy, spawn_key=(*stream.spawn_key, 7))
    rng_split = np.random.Generator(np.random.PCG64(split_stream))
    levels = np.sort(sign * np.log(0.5 * np.asarray(u_levels, dtype=float) ** 2))
    ordered = np.asarray(factors, dtype=np.int64)[np.argsort(sign * np.asarray(u_levels))]
    counts_main = np.zeros(SPEED_EDGES.size + 1, dtype=np.int64)
    counts_split = np.zeros(SPEED_EDGES.size + 1)
    stats = np.zeros(4)
    started = time.process_time()
    _run(
        rng,
        rng_split,
        float(r),
        criterion_c,
        divisor,
        equilibration_time,
        recorded_time,
        SPEED_EDGES,
        float(sign),
        levels,
        ordered,
        counts_main,
        counts_split,
        stats,
    )
    return counts_main, counts_split, stats, time.process_time() - started


def main():
    from bouncing_ball import exact
    from bouncing_ball.histograms import jackknife
    from bouncing_ball.restitution import parse_restitution, restitution_label

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("r")
    parser.add_argument("sign", type=float)
    parser.add_argument("shard_time", type=float)
    parser.add_argument("shards", type=int)
    parser.add_argument("seed", type=int)
    parser.add_argument("u_levels", type=json.loads)
    parser.add_argument("factors", type=json.loads)
    parser.add_argument("--criterion-c", type=float, default=3.0)
    parser.add_argument("--divisor", type=float, default=500.0)
    a = parser.parse_args()
    r = parse_restitution(a.r)
    label = restitution_label(r)
    options = {"criterion_c": a.criterion_c, "divisor": a.divisor}
    shard(r, label, a.seed, 0, 1.0, a.sign, a.u_levels, a.factors, **options)  # compile
    results = [
        shard(r, label, a.seed, k, a.shard_time, a.sign, a.u_levels, a.factors, **options)
        for k in range(a.shards)
    ]
    main_counts = np.array([m for m, *_ in results], dtype=float)
    split_counts = np.array([s for _, s, *_ in results])
    stats = np.array([s for *_, s, _ in results])
    cpu = sum(c for *_, c in results)
    print(
        f"r = {a.r}, sign {a.sign:+g}, levels u = {a.u_levels}, factors {a.factors}: {a.shards} "
        f"shards x {a.shard_time:g}, CPU {cpu:.1f} s, steps in copies / main steps "
        f"{stats[:, 2].sum() / stats[:, 1].sum():.2f}, stack overflows {int(stats[:, 3].sum())}"
    )
    times = np.full((a.shards, 1), a.shard_time)
    plain, plain_error = jackknife(lambda c, t: c / t, main_counts, times)
    split, split_error = jackknife(lambda c, t: c / t, split_counts, times)
    lower, upper = SPEED_EDGES[:-1], SPEED_EDGES[1:]
    for b in np.flatnonzero(split_counts.sum(axis=0)[1:-1] > 0) + 1:
        line = (
            f"  [{lower[b - 1]:.3g}, {upper[b - 1]:.3g}): collisions per time plain "
            f"{plain[b]:.4g} +- {plain_error[b]:.2g} ({int(main_counts[:, b].sum())}), split "
            f"{split[b]:.4g} +- {split_error[b]:.2g}"
        )
        if r in (Fraction(1, 2), Fraction(1, 3)):
            measure = 0.5 * (upper[b - 1] ** 2 - lower[b - 1] ** 2)
            expected = float(exact.outgoing_speed_bin_average(lower[b - 1], upper[b - 1], r))
            expected *= measure
            line += f", split / exact {split[b] / expected:.4f} +- {split_error[b] / expected:.4f}"
        print(line)


if __name__ == "__main__":
    main()
