"""What the P(x) tally's walk over the mean path's crossings costs, and what it buys.

A shard's P(x) and <v^2>_x tally assigns each step's time along the bridge's mean path,
split at every crossing of an x-bin edge (the walk), and corrects that assignment with
the step's bridge point (docs/methods.md). The correction alone already makes the tally
exact in expectation, whatever the assignment; the walk is there to make it rarely fire.
This study runs the same shards twice, on the same random streams: with the walk (a
shard's loop) and without it (``simulation.POSITION_WITHOUT_WALK``: a step's time to the
bin it starts in, moved by the correction alone), and prints, for each x bin in
1e-3 <= x <= 50:

  * P(x) and <v^2>_x with the walk, and their jackknife errors;
  * the errors without the walk over those with it;
  * the paired z of the difference of the two estimates (both are exact in expectation,
    so these are of order 1);

and each loop's CPU ns per step and collisions per CPU s, against issue 18's hand-tuned
figure (``breakdown.ISSUE_HAND_TUNED``).

    python -m benchmarks.position_walk_study [--r 0.5] [--c 5] [--shards 32] [--time 4e4]

About a minute with the defaults (r = 1/2 at the paper's c = 5, one core).
"""

import argparse
import sys
import time

import numpy as np

from bouncing_ball.histograms import jackknife
from bouncing_ball.simulation import (
    EVERY_TALLY,
    POSITION_WITHOUT_WALK,
    shard_seed_sequence,
    simulate_shard,
)

from .benchmark import SHARD_SETTINGS
from .breakdown import ISSUE_HAND_TUNED
from .position_tally_check import checked_bins

LOOPS = {"walk": EVERY_TALLY, "no walk": EVERY_TALLY | POSITION_WITHOUT_WALK}


def run_shards(r, c, shards, shard_time, seed=11):
    """Per loop: the shards' tallies and the loop's CPU seconds (from the same streams)."""
    settings = SHARD_SETTINGS.replace(shard_time=shard_time, criterion_c=c)
    results = {}
    for name, parts in LOOPS.items():
        simulate_shard(
            r, shard_seed_sequence(seed, "warm-up", 0), settings.replace(shard_time=10.0), parts
        )
        tallies, cpu = [], 0.0
        for shard in range(shards):
            started = time.process_time()
            tallies.append(
                simulate_shard(r, shard_seed_sequence(seed, "walk", shard), settings, parts)
            )
            cpu += time.process_time() - started
        results[name] = {"tallies": tallies, "cpu_seconds": cpu}
    return results


def _position_tallies(tallies):
    """Per shard (first axis): the recorded time, the time in each x bin and int v^2 dt there."""
    times = np.array([t.time for t in tallies])[:, None]
    occupied = np.stack([t.position_time for t in tallies])
    speed_squared = np.stack([t.position_v2_time for t in tallies])
    return times, occupied, speed_squared


def _rate(occupied, time):
    return occupied / time


def _mean_speed_squared(speed_squared, occupied):
    return speed_squared / occupied


def compare(results):
    """Per x bin of [LOW, HIGH]: the estimates with the walk, the error ratios and the
    paired z of (no walk - walk); per loop: ns per step and collisions per CPU s."""
    times, a_occupied, a_v2 = _position_tallies(results["walk"]["tallies"])
    _, b_occupied, b_v2 = _position_tallies(results["no walk"]["tallies"])
    with np.errstate(divide="ignore", invalid="ignore"):  # bins that no shard visited
        p, p_error = jackknife(_rate, a_occupied, times)
        v2, v2_error = jackknife(_mean_speed_squared, a_v2, a_occupied)
        _, p_error_no_walk = jackknife(_rate, b_occupied, times)
        _, v2_error_no_walk = jackknife(_mean_speed_squared, b_v2, b_occupied)
        p_difference, p_difference_error = jackknife(
            lambda a, b, t: _rate(b - a, t), a_occupied, b_occupied, times
        )
        v2_difference, v2_difference_error = jackknife(
            lambda wa, oa, wb, ob: _mean_speed_squared(wb, ob) - _mean_speed_squared(wa, oa),
            a_v2,
            a_occupied,
            b_v2,
            b_occupied,
        )
        bins = results["walk"]["tallies"][0].position_bins
        inside = checked_bins(bins)
        table = {
            "x": np.sqrt(bins.lower * bins.upper)[inside],
            "P(x)": p[inside],
            "P(x) error": p_error[inside],
            "P(x) error ratio": (p_error_no_walk / p_error)[inside],
            "P(x) paired z": (p_difference / p_difference_error)[inside],
            "<v^2>_x": v2[inside],
            "<v^2>_x error": v2_error[inside],
            "<v^2>_x error ratio": (v2_error_no_walk / v2_error)[inside],
            "<v^2>_x paired z": (v2_difference / v2_difference_error)[inside],
        }
    speed = {}
    for name, result in results.items():
        steps = sum(t.steps for t in result["tallies"])
        collisions = sum(t.collisions for t in result["tallies"])
        speed[name] = {
            "ns_per_step": 1e9 * result["cpu_seconds"] / steps,
            "collisions_per_cpu_second": collisions / result["cpu_seconds"],
        }
    return table, speed


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m benchmarks.position_walk_study")
    parser.add_argument("--r", type=float, default=0.5)
    parser.add_argument("--c", type=float, default=5.0)
    parser.add_argument("--shards", type=int, default=32)
    parser.add_argument("--time", type=float, default=4.0e4, help="simulated time per shard")
    args = parser.parse_args(argv)
    table, speed = compare(run_shards(args.r, args.c, args.shards, args.time))
    print(
        f"r = {args.r:g}, c = {args.c:g}: {args.shards} shards of simulated time {args.time:g}, "
        "each run with the P(x) walk and without it (same streams)"
    )
    for name, row in speed.items():
        line = (
            f"  {name:8s} {row['ns_per_step']:6.1f} ns/step, "
            f"{row['collisions_per_cpu_second']:.3g} collisions/CPU s"
        )
        if args.c in ISSUE_HAND_TUNED:
            ratio = row["collisions_per_cpu_second"] / ISSUE_HAND_TUNED[args.c]
            line += f" ({ratio:.2f} of issue 18's hand-tuned figure)"
        print(line)
    formats = {"x": "{:8.2g}", "P(x)": "{:8.2e}", "<v^2>_x": "{:8.3g}"}
    for name, values in table.items():
        fmt = formats.get(name, "{:8.2f}" if "ratio" in name or " z" in name else "{:8.1e}")
        print(f"  {name:20s}", " ".join(fmt.format(value) for value in values))
    for name in ("P(x)", "<v^2>_x"):
        ratio = table[f"{name} error ratio"]
        z = table[f"{name} paired z"]
        print(
            f"  {name}: error without the walk over with it, median {np.median(ratio):.2f}, "
            f"max {np.max(ratio):.2f}; paired z, mean z^2 {np.mean(z**2):.2f}, "
            f"max |z| {np.max(np.abs(z)):.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
