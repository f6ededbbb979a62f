"""The two P(x) estimates of a run, held against each other shard by shard.

A shard records P(x) twice: the P(x) tally (``position_time``: the mean path's
assignment with its bridge correction) and, summed over v, the P(x, v) tally
(``position_velocity_time``: one bridge point a step). They share the trajectory, so
their difference has a small error. With the correction they also share the bridge
point, and for a step not cut by a collision their difference has mean zero by
construction: a paired z of order 1 in every bin then checks the bookkeeping and bounds
what the collision steps (kept on their mean path) leave between them. On a run made
before issue 18's correction (the mean path alone) it shows that tally's bias, 4-7
standard errors at r = 0.25 and 0.75 (docs/methods.md).

    python -m benchmarks.position_tally_check [results directory]

prints, for each simulated r, the relative difference and the paired z in every x bin
of 1e-3 <= x <= 50, and the errors of the two estimates. Reads the batch files, so it
needs a run's ``results/simulation/r{r}/shards*.parquet``.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

from bouncing_ball.histograms import jackknife
from bouncing_ball.shards import read_shards

LOW, HIGH = 1e-3, 50.0  # the bins of the validation table's P(x) checks


def checked_bins(bins):
    """Which x bins lie in [LOW, HIGH] (a boolean mask over ``bins``' under-, regular and
    overflow bins)."""
    return (bins.lower >= LOW * (1 - 1e-9)) & (bins.upper <= HIGH * (1 + 1e-9))


def paired_difference(shards):
    """Per x bin: (x, P(x) from the P(x) tally, the relative difference of the P(x, v)
    marginal from it, the paired z of that difference, and each estimate's error)."""
    bins = shards[0].position_bins
    times = np.array([s.time for s in shards])[:, None]
    tally = np.stack([s.position_time for s in shards])
    marginal = np.stack([s.position_velocity_time.sum(axis=1) for s in shards])
    rate = lambda occupied, time: occupied / time  # noqa: E731
    p_tally, e_tally = jackknife(rate, tally, times)
    p_marginal, e_marginal = jackknife(rate, marginal, times)
    difference, e_difference = jackknife(rate, tally - marginal, times)
    inside = checked_bins(bins)  # the other bins may be empty: divide only these
    x = np.sqrt(bins.lower * bins.upper)
    p_tally, p_marginal, difference = p_tally[inside], p_marginal[inside], difference[inside]
    return {
        "x": x[inside],
        "relative_difference": difference / p_tally,
        "z": difference / e_difference[inside],
        "error_tally": e_tally[inside] / p_tally,
        "error_marginal": e_marginal[inside] / p_marginal,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m benchmarks.position_tally_check")
    parser.add_argument("results", nargs="?", default="results", type=Path)
    args = parser.parse_args(argv)
    folders = sorted((args.results / "simulation").glob("r*"))
    if not folders:
        print(f"no simulated r under {args.results / 'simulation'}", file=sys.stderr)
        return 1
    for folder in folders:
        paths = sorted(folder.glob("shards*.parquet"))
        if not paths:
            continue
        shards, _ = read_shards(paths, folder.name[1:])
        result = paired_difference(shards)
        z = result["z"]
        print(
            f"r = {folder.name[1:]}: {len(shards)} shards; P(x) tally minus P(x, v) marginal,"
            f" {len(z)} bins in {LOW:g} <= x <= {HIGH:g}: max |z| {np.max(np.abs(z)):.2f},"
            f" mean z^2 {np.mean(z**2):.2f}"
        )
        for name, fmt in (
            ("x", "{:8.2g}"),
            ("relative_difference", "{:+8.1e}"),
            ("z", "{:+8.1f}"),
            ("error_tally", "{:8.1e}"),
            ("error_marginal", "{:8.1e}"),
        ):
            print(f"  {name:20s}", " ".join(fmt.format(value) for value in result[name]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
