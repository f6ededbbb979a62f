"""Statistical efficiency, (relative error)^2 x CPU s, plain and with the martingale control
variates (``histograms.control_variate_rate``), for I and for chosen P(0, v) bins.

    python -m benchmarks.efficiency_study run R SHARD_TIME SHARDS SEED OUT.npz
    python -m benchmarks.efficiency_study table OUT.npz [BIN ...] [--cost 1.015]
    python -m benchmarks.efficiency_study repeats OUT.npz GROUP_SIZE

``run`` simulates SHARDS shards of r = R (default config: c, the delta rule, the bins, the
equilibration) one after another on one core and saves each shard's scalars, speed counts
and CPU seconds.  ``table`` prints, for I and each speed bin given by index (1 = the first
finite bin), the plain and the controlled estimate with their jackknife errors, the
efficiency of each, the variance reduction factor (VRF) and the uncertainty of these from
a delete-one jackknife over shards of their logarithms; exact values and z at r = 1/2, 1/3.
``--cost`` is the CPU of the loop with the controls over the loop without them (measured
+1-2.6 %), so the plain efficiency is charged the CPU of a loop without them.  ``repeats``
splits the shards into groups: the z-scores of each group's estimates against the exact I,
and the scatter of the group estimates against their mean jackknife error (honest errors).
The numbers of docs/performance.md, 'Control variates', come from these.
"""

import argparse
import time
from fractions import Fraction
from pathlib import Path

import numpy as np

from bouncing_ball.tallies import CONTROL_VARIATE_SUMS

REPOSITORY = Path(__file__).resolve().parents[1]
CONTROLS = {
    "cv1": ("noise_sum",),
    "cv3": ("noise_sum", "noise_v_sum", "noise_scaled_sum"),
    "cv4": CONTROL_VARIATE_SUMS,
}
EXACT_RATE = {Fraction(1, 2): 1.0 / 3.0, Fraction(1, 3): 0.75}


def run(r_text, shard_time, shards, seed, out):
    from bouncing_ball.config import read_config, shard_settings
    from bouncing_ball.restitution import parse_restitution, restitution_label
    from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
    from bouncing_ball.tallies import SCALARS

    r = parse_restitution(r_text)
    label = restitution_label(r)
    settings = shard_settings(read_config(REPOSITORY / "config" / "config.yaml"), label)
    settings = settings.replace(shard_time=shard_time, max_steps=10**13)
    simulate_shard(float(r), shard_seed_sequence(seed, label, 0), settings.replace(shard_time=1.0))
    rows = {name: [] for name in SCALARS}
    counts, cpu = [], []
    for k in range(shards):
        started = time.process_time()
        tallies = simulate_shard(float(r), shard_seed_sequence(seed, label, k), settings)
        cpu.append(time.process_time() - started)
        for name in SCALARS:
            rows[name].append(float(getattr(tallies, name)))
        counts.append(tallies.speed_counts)
    np.savez(
        out,
        r=r_text,
        cpu=np.array(cpu),
        speed_counts=np.array(counts),
        lower=settings.speed_bins.lower,
        upper=settings.speed_bins.upper,
        **{name: np.array(values) for name, values in rows.items()},
    )


def _estimates(tally, times, controls):
    from bouncing_ball.histograms import control_variate_rate, jackknife

    result = {"plain": jackknife(lambda a, t: a / t, tally, times)}
    for key, columns in controls.items():
        value, error, _ = control_variate_rate(tally, times, columns)
        result[key] = (value, error)
    return result


def efficiency_row(data, tally, cost=1.015):
    """Estimates, errors, efficiencies and VRFs of ``tally`` (one per shard), with the
    relative uncertainty of each efficiency and VRF (jackknife of the logarithms)."""
    times = data["time"]
    n = len(times)
    cpu = float(data["cpu"].sum())
    controls = {
        key: np.column_stack([data[name] for name in names]) for key, names in CONTROLS.items()
    }

    def logs(keep):
        found = _estimates(tally[keep], times[keep], {k: c[keep] for k, c in controls.items()})
        share = cpu * keep.sum() / n
        eff = {k: (e / v) ** 2 * share for k, (v, e) in found.items()}
        eff["plain"] /= cost
        return found, eff

    found, eff = logs(np.ones(n, dtype=bool))
    keys = list(found)
    samples = []
    for k in range(n):
        keep = np.ones(n, dtype=bool)
        keep[k] = False
        _, e = logs(keep)
        samples.append(
            [np.log(e[key]) for key in keys] + [np.log(e["plain"] / e[key]) for key in keys]
        )
    samples = np.array(samples)
    spread = np.sqrt((n - 1) / n * ((samples - samples.mean(axis=0)) ** 2).sum(axis=0))
    row = {}
    for i, key in enumerate(keys):
        row[key] = {
            "value": float(found[key][0]),
            "error": float(found[key][1]),
            "efficiency": float(eff[key]),
            "efficiency_relative_uncertainty": float(spread[i]),
            "vrf": float(eff["plain"] / eff[key]),
            "vrf_relative_uncertainty": float(spread[len(keys) + i]),
        }
    return row


def table(path, bins, cost):
    from bouncing_ball import exact
    from bouncing_ball.restitution import parse_restitution

    data = dict(np.load(path))
    r = parse_restitution(str(data["r"]))
    lower, upper = data["lower"], data["upper"]
    print(f"{path}: r = {data['r']}, {len(data['time'])} shards, CPU {data['cpu'].sum():.1f} s")
    targets = [("I", data["collisions"], EXACT_RATE.get(r))]
    for b in bins:
        measure = 0.5 * (upper[b] ** 2 - lower[b] ** 2)
        truth = None
        if r in EXACT_RATE:
            truth = float(exact.outgoing_speed_bin_average(lower[b], upper[b], r))
        count = int(data["speed_counts"][:, b].sum())
        name = f"P(0,v) [{lower[b]:.3g}, {upper[b]:.3g}) ({count} collisions)"
        targets.append((name, data["speed_counts"][:, b] / measure, truth))
    for name, tally, truth in targets:
        row = efficiency_row(data, np.asarray(tally, dtype=float), cost)
        print(f"  {name}")
        for key, entry in row.items():
            z = "" if truth is None else f"  z {(entry['value'] - truth) / entry['error']:+.2f}"
            print(
                f"    {key:5s} {entry['value']:.6g} +- {entry['error']:.2g}{z}  efficiency "
                f"{entry['efficiency']:.3g} s (+-{100 * entry['efficiency_relative_uncertainty']:.0f}%)"
                f"  VRF {entry['vrf']:.2f} (+-{100 * entry['vrf_relative_uncertainty']:.0f}%)"
            )


def repeats(path, group):
    from bouncing_ball.restitution import parse_restitution

    data = dict(np.load(path))
    truth = EXACT_RATE[parse_restitution(str(data["r"]))]
    groups = len(data["time"]) // group
    found = {}
    for g in range(groups):
        part = slice(g * group, (g + 1) * group)
        controls = {k: np.column_stack([data[c][part] for c in v]) for k, v in CONTROLS.items()}
        for key, (value, error) in _estimates(
            data["collisions"][part], data["time"][part], controls
        ).items():
            found.setdefault(key, []).append((value, error))
    print(f"{path}: {groups} groups of {group} shards, exact I = {truth:.6g}")
    for key, values in found.items():
        values = np.array(values)
        z = (values[:, 0] - truth) / values[:, 1]
        print(
            f"  {key:5s} mean z {z.mean():+.2f} (+-{1 / np.sqrt(groups):.2f}), mean z^2 "
            f"{np.mean(z**2):.2f}, max |z| {np.abs(z).max():.2f}, scatter of the groups / mean "
            f"error {values[:, 0].std(ddof=1) / values[:, 1].mean():.2f}"
        )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    running = commands.add_parser("run")
    running.add_argument("r")
    running.add_argument("shard_time", type=float)
    running.add_argument("shards", type=int)
    running.add_argument("seed", type=int)
    running.add_argument("out")
    tabling = commands.add_parser("table")
    tabling.add_argument("path")
    tabling.add_argument("bins", type=int, nargs="*")
    tabling.add_argument("--cost", type=float, default=1.015)
    grouping = commands.add_parser("repeats")
    grouping.add_argument("path")
    grouping.add_argument("group", type=int)
    arguments = parser.parse_args()
    if arguments.command == "run":
        run(arguments.r, arguments.shard_time, arguments.shards, arguments.seed, arguments.out)
    elif arguments.command == "table":
        table(arguments.path, arguments.bins, arguments.cost)
    else:
        repeats(arguments.path, arguments.group)


if __name__ == "__main__":
    main()
