"""Where a step of the shard loop spends its time, and how it compares with the hand-tuned
C loop (``hand_tuned_loop``, measured in the same run): part of ``python -m benchmarks``.

Two kinds of measurement, both CPU time on one core, best of ``repeats``:
  * the shard loop itself (``simulation.simulate_shard``) with its tallies switched on
    one at a time (its ``parts`` argument): "stepping" records what the hand-tuned C loop
    records (collisions, their outgoing speeds, time, steps, int x dt and int x^2 dt),
    and each tally's cost is the loop's ns per step with it minus without it;
  * the two pieces of a step that cannot be switched off, timed on their own: the step-size
    root of eq. (criterion) (``free_flight.criterion_root``, from the loop's warm start and
    from the cold start, over the states of a real trajectory, which ``_trajectory``
    records) and the two normals a step draws (numpy's PCG64 and ziggurat, inline as the loop
    draws them: ``pcg64``).  These run alongside the step's other arithmetic in the loop, so
    they bound, not add up to, the stepping time.
"""

import time

import numpy as np

from bouncing_ball.free_flight import (
    criterion_root,
    cubic_slope,
    first_crossing_time,
    free_flight_step,
    hermite_cubic,
    predicted_start,
    root_predictor,
)
from bouncing_ball.jit import fma, njit
from bouncing_ball.pcg64 import standard_normal, stream_words
from bouncing_ball.simulation import (
    CONTROL_VARIATES,
    EVERY_TALLY,
    FLIGHTS,
    JOINT,
    MEAN_PATH_INTEGRALS,
    POSITION,
    shard_seed_sequence,
    simulate_shard,
)

PARTS = (
    ("stepping (collisions, P(0,v), int x, int x^2)", MEAN_PATH_INTEGRALS),
    ("+ P(x) and <v^2>_x", MEAN_PATH_INTEGRALS | POSITION),
    ("+ P(x, v)", MEAN_PATH_INTEGRALS | JOINT),
    ("+ flight times and return speeds", MEAN_PATH_INTEGRALS | FLIGHTS),
    ("+ control variates (noise sums)", MEAN_PATH_INTEGRALS | CONTROL_VARIATES),
    ("every tally", EVERY_TALLY),
)


def _best_cpu(function, repeats):
    best, result = float("inf"), None
    for _ in range(repeats):
        started = time.process_time()
        result = function()
        best = min(best, time.process_time() - started)
    return best, result


def loop_parts(settings, r=0.5, recorded_time=1.0e6, repeats=3):
    """ns per step and collisions per CPU s of the loop with each set of ``PARTS``."""
    stream = shard_seed_sequence(1, "0.5", 0)
    shard = settings.replace(shard_time=recorded_time)
    simulate_shard(r, stream, shard.replace(shard_time=10.0))  # compile or load
    rows = []
    for name, parts in PARTS:
        seconds, tallies = _best_cpu(lambda p=parts: simulate_shard(r, stream, shard, p), repeats)
        rows.append(
            {
                "part": name,
                "parts": parts,
                "ns_per_step": 1e9 * seconds / tallies.steps,
                "collisions_per_cpu_second": tallies.collisions / seconds,
            }
        )
    stepping = rows[0]["ns_per_step"]
    for row in rows[1:]:
        row["extra_ns_per_step"] = row["ns_per_step"] - stepping
    return rows


@njit(cache=True)
def _trajectory(rng, steps, r, c, min_step_divisor):
    """The states (x, v) and the loop's warm starts of ``steps`` steps of the stepping
    alone (the loop's eq. (criterion), free flight and collision rule), for timing the root."""
    xs = np.empty(steps)
    vs = np.empty(steps)
    starts = np.empty(steps)
    x, v = 1.0, 0.0
    root, slope = criterion_root(x, v, c, 0.0)
    min_root_2delta = 1.0 / min_step_divisor
    delta = 0.5 * min_root_2delta * min_root_2delta
    start = 0.0
    for i in range(steps):
        xs[i], vs[i], starts[i] = x, v, start
        dt = fma(root, root, delta)
        predictor = root_predictor(root, slope, x, v)
        x1, v1 = free_flight_step(x, v, dt, rng.standard_normal(), rng.standard_normal())
        if x1 < 0.0:
            a0, a1, a2, a3 = hermite_cubic(x, v, x1, v1, dt)
            tau = first_crossing_time(a0, a1, a2, a3, dt, x1)
            x, v = 0.0, r * abs(cubic_slope(a1, a2, a3, tau))
            root_2delta = v * min_root_2delta
            delta = 0.5 * root_2delta * root_2delta
            start = 0.0
        else:
            x, v = x1, v1
            start = predicted_start(predictor, root, x1, v1)
        root, slope = criterion_root(x, v, c, start)
    return xs, vs, starts


@njit(cache=True)
def _roots(xs, vs, starts, c):
    total = 0.0
    for i in range(xs.shape[0]):
        total += criterion_root(xs[i], vs[i], c, starts[i])[0]
    return total


@njit(cache=True)
def _normals(words, steps):
    """Two normals a step, drawn as the loop draws them (``pcg64.standard_normal``)."""
    high, low, inc_high, inc_low = words
    total = 0.0
    for _ in range(steps):
        high, low, normal_r = standard_normal(high, low, inc_high, inc_low)
        high, low, normal_s = standard_normal(high, low, inc_high, inc_low)
        total += normal_r + normal_s
    return total


def step_pieces(settings, r=0.5, steps=2_000_000, repeats=3):
    """ns per step of the criterion root (warm and cold start) and of two normals."""
    c = settings.criterion_c
    rng = np.random.Generator(np.random.PCG64(1))
    xs, vs, starts = _trajectory(rng, steps, r, c, settings.min_step_divisor)
    cold = np.zeros(steps)
    _roots(xs[:10], vs[:10], starts[:10], c)
    words = stream_words(rng)
    _normals(words, 10)
    warm_seconds, _ = _best_cpu(lambda: _roots(xs, vs, starts, c), repeats)
    cold_seconds, _ = _best_cpu(lambda: _roots(xs, vs, cold, c), repeats)
    normal_seconds, _ = _best_cpu(lambda: _normals(words, steps), repeats)
    return {
        "criterion_root_ns": 1e9 * warm_seconds / steps,
        "criterion_root_cold_start_ns": 1e9 * cold_seconds / steps,
        "two_normals_ns": 1e9 * normal_seconds / steps,
    }


def hand_tuned_rate(r, criterion_c, recorded_time=2.0e6, repeats=3):
    """Collisions per CPU second of the hand-tuned C loop (best of ``repeats``), or None with
    the reason where it cannot be built (no gcc)."""
    from . import hand_tuned_loop

    try:
        best = min(
            (hand_tuned_loop.run(r, criterion_c, recorded_time) for _ in range(repeats)),
            key=lambda result: result["cpu_seconds"],
        )
    except (RuntimeError, OSError) as error:  # no compiler
        return None, str(error).splitlines()[0]
    return best["collisions_per_cpu_second"], None


def breakdown(settings, criterion_cs=(5.0, 3.0), r=0.5):
    """Per c: the loop's parts, the root and the normals, and the loop's speed against the
    hand-tuned C loop measured here (skipped, with the reason, where gcc is missing)."""
    results = []
    for c in criterion_cs:
        shard = settings.replace(criterion_c=c)
        rows = loop_parts(shard, r)
        row = {"r": r, "criterion_c": c, "parts": rows, **step_pieces(shard, r)}
        rate, skipped = hand_tuned_rate(r, c)
        if rate is None:
            row["hand_tuned_skipped"] = skipped
        else:
            ours = {"stepping": rows[0], "every tally": rows[-1]}
            row["hand_tuned_collisions_per_cpu_second"] = rate
            row["against_hand_tuned"] = {
                case: ours[case]["collisions_per_cpu_second"] / rate for case in ours
            }
        results.append(row)
    return results
