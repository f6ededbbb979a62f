"""The studies' analysis (workflow/rules/studies.smk, config/studies.yaml): pure functions
from shard tallies and reference values to the rows of the reports.

criterion_bias: runs at each (r, c) against the exact r = 1/2 and 1/3 results (the moments
and P(0, v)), with what a run cost.  r075: runs at r = 3/4 against the solver, alone and
pooled, and how far their jackknife errors can be trusted: per-shard spread, errors from
batches of shards, groups of shards, and the shape of the per-shard distribution.

Every estimate is the one of the merge stage (``histograms.position_moments_summary`` and
``histograms.outgoing_speed_histogram``, jackknife errors), applied to all the shards of a
run, to a batch or group of them, or to one shard.
"""

from itertools import islice

import numpy as np
import pandas as pd
from scipy import stats

from .. import exact
from ..comparison import QUANTITIES, SYMBOLS, exact_outgoing_speed_residuals, value_with_error
from ..histograms import outgoing_speed_histogram, position_moments_summary
from ..restitution import parse_restitution
from .shards import read_shards


def read_runs(paths, runs) -> dict:
    """{run name: (shards, provenances)} of a report's input: ``paths`` in the order of
    ``runs`` (the rule's ``params.runs``: dicts with ``run``, ``r_label`` and ``shards``, the
    number of files of that run).  Each run's shards are checked by ``shards.read_shards``."""
    paths = list(paths)
    if len(paths) != sum(run["shards"] for run in runs):
        raise ValueError(
            f"{len(paths)} shard files for {sum(run['shards'] for run in runs)} shards of the runs"
        )
    files = iter(paths)
    return {
        run["run"]: read_shards(list(islice(files, run["shards"])), run["r_label"]) for run in runs
    }


def cpu_seconds(provenances) -> float:
    """The CPU time of a run's shards (``cpu_seconds`` of the study shards' provenance);
    NaN unless every shard recorded it."""
    seconds = [provenance.get("cpu_seconds") for provenance in provenances]
    return float(sum(seconds)) if seconds and None not in seconds else float("nan")


def per_shard_values(shards, restitution) -> pd.DataFrame:
    """<x>, Delta x and I of each shard alone (one row per shard)."""
    return pd.concat(
        [position_moments_summary([shard], restitution)[list(QUANTITIES)] for shard in shards],
        ignore_index=True,
    )


def against_reference(summary: pd.Series, reference) -> dict:
    """{quantity: value, error, reference, relative deviation and error, z} of a one-row
    summary (``position_moments_summary``) against ``reference[quantity]``."""
    out = {}
    for quantity in QUANTITIES:
        value, error = float(summary[quantity]), float(summary[f"{quantity}_err"])
        ref = float(reference[quantity])
        out[quantity] = {
            "value": value,
            "error": error,
            "reference": ref,
            "rel_deviation": value / ref - 1.0,
            "rel_error": error / ref,
            "z": (value - ref) / error if error > 0 else np.nan,
        }
    return out


def batch_errors(shards, restitution, batch_size: int) -> dict:
    """Errors from batches of ``batch_size`` consecutive shards against the jackknife error.

    A batch's estimate is that of its summed tallies; the batch error is the standard error
    of the mean of the batch estimates, the jackknife error that of the same shards taken
    singly (``position_moments_summary``).  Shards beyond the last whole batch are left out
    of both.  {quantity: (batches, batch error, jackknife error)}; NaN errors with fewer
    than 2 batches.
    """
    batches = len(shards) // batch_size
    if batches < 2:
        return dict.fromkeys(QUANTITIES, (batches, np.nan, np.nan))
    estimates = pd.concat(
        [
            position_moments_summary(shards[k * batch_size : (k + 1) * batch_size], restitution)
            for k in range(batches)
        ],
        ignore_index=True,
    )
    single = position_moments_summary(shards[: batches * batch_size], restitution).iloc[0]
    return {
        quantity: (
            batches,
            float(estimates[quantity].std(ddof=1) / np.sqrt(batches)),
            float(single[f"{quantity}_err"]),
        )
        for quantity in QUANTITIES
    }


def group_statistics(shards, restitution, reference, group_size: int) -> dict:
    """The jackknife of groups of ``group_size`` consecutive shards against ``reference``.

    {quantity: dict(groups, z: each group's z-score, spread: standard deviation of the
    groups' relative deviations, mean_error: their mean relative jackknife error,
    ratio: spread / mean_error)}.  If the jackknife errors are right the ratio is 1 within
    about 1 / sqrt(2 (groups - 1)), and each group's error is itself uncertain by about
    ``jackknife_error_uncertainty(group_size)`` (13% for 32 shards).  NaN with fewer than
    2 groups.
    """
    groups = len(shards) // group_size
    rows = [
        against_reference(
            position_moments_summary(
                shards[k * group_size : (k + 1) * group_size], restitution
            ).iloc[0],
            reference,
        )
        for k in range(groups)
    ]
    out = {}
    for quantity in QUANTITIES:
        deviations = np.array([row[quantity]["rel_deviation"] for row in rows])
        errors = np.array([row[quantity]["rel_error"] for row in rows])
        spread = float(deviations.std(ddof=1)) if groups >= 2 else np.nan
        mean_error = float(errors.mean()) if groups >= 2 else np.nan
        out[quantity] = {
            "groups": groups,
            "z": [row[quantity]["z"] for row in rows],
            "spread": spread,
            "mean_error": mean_error,
            "ratio": _ratio(spread, mean_error),
        }
    return out


def _ratio(numerator, denominator) -> float:
    """numerator / denominator; NaN where undefined (a zero or NaN denominator)."""
    return numerator / denominator if denominator > 0 else np.nan


def jackknife_error_uncertainty(shards: int) -> float:
    """Relative standard deviation of a jackknife (standard) error from ``shards`` shards
    with Gaussian per-shard values: 1 / sqrt(2 (n - 1)); 0.127 for n = 32."""
    return 1.0 / np.sqrt(2.0 * (shards - 1)) if shards >= 2 else np.nan


def shape(values) -> tuple[float, float]:
    """Skewness and excess kurtosis (scipy.stats, biased estimators) of per-shard values;
    0 and 0 for a Gaussian."""
    values = np.asarray(values, dtype=float)
    if len(values) < 3:
        return np.nan, np.nan
    return float(stats.skew(values)), float(stats.kurtosis(values))


def outgoing_speed_check(shards, restitution, minimum_count: int) -> dict:
    """The simulated P(0, v) (bin averages, jackknife errors) against the exact one
    (``comparison.exact_outgoing_speed_residuals``) over the finite bins with at least
    ``minimum_count`` collisions: their number, chi^2 / n of their z and the largest ``|z|``."""
    table = outgoing_speed_histogram(shards)
    z = exact_outgoing_speed_residuals(table[table["count"] >= minimum_count], restitution).residual
    if z.empty:
        return {"p0v_bins": 0, "p0v_chi2_per_bin": np.nan, "p0v_max_abs_z": np.nan}
    return {
        "p0v_bins": len(z),
        "p0v_chi2_per_bin": float(np.mean(z**2)),
        "p0v_max_abs_z": float(np.max(np.abs(z))),
    }


def criterion_bias_row(run: dict, shards, provenances, minimum_count: int) -> dict:
    """One row of the criterion_bias report: the run ``run`` (``params.runs`` entry) of one
    (r, c) against the exact results (``exact.position_moments``), and its cost."""
    restitution = parse_restitution(run["r"])
    summary = position_moments_summary(shards, float(restitution)).iloc[0]
    cpu = cpu_seconds(provenances)
    row = {
        "r_label": run["r_label"],
        "r": run["r"],
        "criterion_c": float(run["criterion_c"]),
        "shards": len(shards),
        "cpu_seconds": cpu,
        "steps_per_collision": summary.steps / summary.collisions,
        "shards_out_of_budget": int(summary.shards_out_of_budget),
    }
    for quantity, numbers in against_reference(
        summary, exact.position_moments(restitution)
    ).items():
        row.update(
            {
                quantity: numbers["value"],
                f"{quantity}_err": numbers["error"],
                f"{quantity}_exact": numbers["reference"],
                f"{quantity}_rel_deviation": numbers["rel_deviation"],
                f"{quantity}_rel_error": numbers["rel_error"],
                f"{quantity}_z": numbers["z"],
            }
        )
    row["rel_error_I_squared_cpu"] = row["collision_rate_rel_error"] ** 2 * cpu
    row.update(outgoing_speed_check(shards, restitution, minimum_count))
    return row


def criterion_bias_table(rows) -> pd.DataFrame:
    """The rows of ``criterion_bias_row``; the CPU columns dropped if no run recorded CPU."""
    table = pd.DataFrame(rows)
    if table.cpu_seconds.isna().all():
        table = table.drop(columns=["cpu_seconds", "rel_error_I_squared_cpu"])
    return table


def _percent(deviation, error, z) -> str:
    return f"{100 * deviation:+.3f} ± {100 * error:.3f}% (z = {z:+.2f})"


def _shown(form: str):
    """A formatter of numbers for the Markdown tables: blank for NaN."""
    return lambda value: "" if not np.isfinite(value) else form.format(value)


def criterion_bias_markdown(table: pd.DataFrame) -> str:
    """The criterion_bias report for a reader."""
    shown = {
        "r": table.r,
        "c": table.criterion_c.map("{:g}".format),
        "shards": table.shards.astype(str),
    }
    if "cpu_seconds" in table:
        shown["CPU s"] = table.cpu_seconds.map(_shown("{:.4g}"))
    shown["steps / collision"] = table.steps_per_collision.map(_shown("{:.2f}"))
    for quantity in QUANTITIES:
        shown[f"{SYMBOLS[quantity]} vs exact"] = [
            _percent(d, e, z)
            for d, e, z in zip(
                table[f"{quantity}_rel_deviation"],
                table[f"{quantity}_rel_error"],
                table[f"{quantity}_z"],
            )
        ]
    if "cpu_seconds" in table:
        shown["(rel. err. I)^2 x CPU s"] = table.rel_error_I_squared_cpu.map(_shown("{:.3g}"))
    shown["P(0,v): bins, chi^2/n, max abs z"] = [
        f"{n}, {chi2:.2f}, {worst:.2f}"
        for n, chi2, worst in zip(table.p0v_bins, table.p0v_chi2_per_bin, table.p0v_max_abs_z)
    ]
    return (
        "# c of eq. (criterion) against the exact results (r = 1/2, 1/3)\n\n"
        "Relative deviations from the exact <x>, Delta x, I (bouncing_ball.exact) with "
        "jackknife errors; P(0,v) against the exact bin averages over the bins with enough "
        "collisions. (rel. err. I)^2 x CPU: lower is more efficient.\n\n"
        + pd.DataFrame(shown).to_markdown(index=False, disable_numparse=True)
        + "\n"
    )


def r075_rows(name: str, run: dict | None, shards, provenances, reference, batch_size, group_size):
    """The rows (one per quantity) of the r075 report for one run, or for all runs pooled
    (``name`` "all", ``run`` None): the estimate against the solver's ``reference``, the
    per-shard relative spread, batch errors, group statistics and the per-shard shape."""
    restitution = float(parse_restitution(provenances[0]["r"]))
    summary = position_moments_summary(shards, restitution).iloc[0]
    compared = against_reference(summary, reference)
    values = per_shard_values(shards, restitution)
    batches = batch_errors(shards, restitution, batch_size)
    groups = group_statistics(shards, restitution, reference, group_size)
    rows = []
    for quantity in QUANTITIES:
        per_shard = values[quantity].to_numpy()
        skewness, kurtosis = shape(per_shard)
        count, batch_error, single_error = batches[quantity]
        group = groups[quantity]
        rows.append(
            {
                "run": name,
                "criterion_c": float(run["criterion_c"]) if run else np.nan,
                "seed": run["seed"] if run else "",
                "shards": len(shards),
                "cpu_seconds": cpu_seconds(provenances),
                "quantity": quantity,
                "value": compared[quantity]["value"],
                "error": compared[quantity]["error"],
                "solver": compared[quantity]["reference"],
                "rel_deviation": compared[quantity]["rel_deviation"],
                "rel_error": compared[quantity]["rel_error"],
                "z": compared[quantity]["z"],
                "shard_rel_spread": float(per_shard.std(ddof=1) / per_shard.mean()),
                "batch_size": batch_size,
                "batches": count,
                "batch_error": batch_error,
                "batch_jackknife_error": single_error,
                "batch_error_ratio": _ratio(batch_error, single_error),
                "group_size": group_size,
                "groups": group["groups"],
                "group_z": " ".join(f"{z:+.2f}" for z in group["z"]),
                "group_rel_spread": group["spread"],
                "group_mean_rel_error": group["mean_error"],
                "group_spread_ratio": group["ratio"],
                "group_error_uncertainty": jackknife_error_uncertainty(group_size),
                "skewness": skewness,
                "excess_kurtosis": kurtosis,
            }
        )
    return rows


def r075_markdown(table: pd.DataFrame, label: str) -> str:
    """The r075 report for a reader."""
    size = table.batch_size.iloc[0]
    group = table.group_size.iloc[0]
    shown = pd.DataFrame(
        {
            "run": table.run,
            "c": table.criterion_c.map(_shown("{:g}")),
            "shards": table.shards.astype(str),
            "quantity": table.quantity.map(SYMBOLS),
            "simulation": [value_with_error(v, e) for v, e in zip(table.value, table.error)],
            "solver": table.solver.map(_shown("{:.10g}")),
            "rel. dev.": [
                _percent(d, e, z) for d, e, z in zip(table.rel_deviation, table.rel_error, table.z)
            ],
            "per-shard spread": table.shard_rel_spread.map(_shown("{:.3%}")),
            f"batch / jackknife error ({size} shards)": table.batch_error_ratio.map(
                _shown("{:.2f}")
            ),
            f"z of groups of {group}": table.group_z,
            "group spread / mean error": table.group_spread_ratio.map(_shown("{:.2f}")),
            "skewness": table.skewness.map(_shown("{:+.2f}")),
            "excess kurtosis": table.excess_kurtosis.map(_shown("{:+.2f}")),
        }
    )
    return (
        f"# <x>, Delta x, I at r = {label} against the solver\n\n"
        "Each run alone and all runs pooled (run `all`), with jackknife errors. The errors "
        f"checked: batches of {size} shards against the jackknife of the same shards (ratio "
        f"near 1); groups of {group} shards, whose means should scatter by their mean "
        "jackknife error (ratio near 1); a jackknife error from "
        f"{group} shards is itself uncertain by about "
        f"{jackknife_error_uncertainty(group):.0%} (1 / sqrt(2 (n - 1))). Skewness and "
        "excess kurtosis of the per-shard values: 0 for a Gaussian.\n\n"
        + shown.to_markdown(index=False, disable_numparse=True)
        + "\n"
    )
