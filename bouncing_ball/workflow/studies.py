"""The studies' analysis (workflow/rules/studies.smk, config/studies.yaml): pure functions
from shard tallies and reference values to the rows of the reports.

criterion_bias: runs at each (r, c) against the exact r = 1/2 and 1/3 results (the moments
and P(0, v)), with what a run cost.  r075: runs at r = 3/4 against the solver, alone and
pooled, and how far their jackknife errors can be trusted: per-shard spread, errors from
batches of shards, groups of shards, and the shape of the per-shard distribution.

Every estimate is the one of the merge stage (``estimators.position_moments_summary`` and
``estimators.outgoing_speed_histogram``, jackknife errors), applied to all the shards of a
run, to a batch or group of them, or to one shard.

coverage: many independent runs of n shards at r = 1/2 and 1/3 against the exact results;
per moment and estimator (plain, controlled) the scatter of the runs' z against Student's t
with n - 1 degrees of freedom: whether the jackknife errors are honest.
"""

from itertools import groupby
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import special, stats

from .. import exact
from ..estimators import outgoing_speed_histogram, position_moments_summary
from ..restitution import parse_restitution
from ..validation import QUANTITIES, SYMBOLS, exact_outgoing_speed_residuals, value_with_error
from .shards import read_shards


def read_runs(paths, runs) -> dict:
    """{run name: (shards, provenances)} of a report's input: the batch files ``paths``,
    run by run in the order of ``runs`` (the rule's ``params.runs``: dicts with ``run``,
    ``r_label`` and ``shards``).  Each run's shards are checked by ``shards.read_shards``."""
    return {run["run"]: read for run, read in iter_runs(paths, runs)}


def iter_runs(paths, runs):
    """``read_runs`` one run at a time: (run, (shards, provenances)) in the order of
    ``runs``, each run read when asked for (a report of many runs holds one in memory).  A
    run's files are those in its directory, results/studies/{study}/{run}/; ValueError unless
    the files are in the order of ``runs`` and hold the shards each run names."""
    paths = [Path(path) for path in paths]
    names = [run["run"] for run in runs]
    order = [name for name, _ in groupby(path.parent.name for path in paths)]
    if order != names:
        raise ValueError(f"the batch files are of the runs {order}, not of {names} in that order")
    files = iter(paths)
    for run, (_, group) in zip(runs, groupby(files, key=lambda path: path.parent.name)):
        shards, provenances = read_shards(list(group), run["r_label"])
        if len(shards) != run["shards"]:
            raise ValueError(
                f"run {run['run']}: {len(shards)} shards in its files, not {run['shards']}"
            )
        yield run, (shards, provenances)


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
    (``validation.exact_outgoing_speed_residuals``) over the finite bins with at least
    ``minimum_count`` collisions: their number, chi^2 / n of their z and the largest ``abs(z)``."""
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


#: The moments of the coverage study: <x>, Delta x (eq. (xandDeltax)), I (eq. (collrate)),
#: <T> and <T^2> per flight (eqs. (meanT), (meanT2)), each as ``position_moments_summary``
#: gives it, plain and ``*_controlled``.
COVERAGE_MOMENTS = (
    "mean_x",
    "delta_x",
    "collision_rate",
    "mean_flight_time",
    "flight_time_second_moment",
)
COVERAGE_SYMBOLS = {**SYMBOLS, "mean_flight_time": "<T>", "flight_time_second_moment": "<T^2>"}
#: The estimators of each moment: the plain tallies, the martingale-controlled ones (independent
#: of the theory) and the controlled ones (with eq. (kernel3) where r is in the solver's range).
COVERAGE_ESTIMATORS = ("plain", "martingale", "controlled")
#: abs(z) beyond this counts as a miss in the coverage report.
COVERAGE_Z_LIMIT = 2.0


def exact_moments(restitution) -> dict:
    """{moment of ``COVERAGE_MOMENTS``: exact value} at r = 1/2 or 1/3 (``ExactEquilibrium``:
    ``exact.position_moments`` and the flight-time moments of the exact P(0, u))."""
    from ..equilibrium import ExactEquilibrium

    equilibrium = ExactEquilibrium(restitution)
    return {moment: float(getattr(equilibrium, moment)) for moment in COVERAGE_MOMENTS}


def run_z_scores(summary: pd.Series, reference: dict) -> dict:
    """{(moment, estimator): z} of one run's summary row (``position_moments_summary``)
    against ``reference`` (``exact_moments``): (estimate - exact) / jackknife error, NaN
    where the estimator has no value (the controlled ones with too few shards)."""
    out = {}
    for moment in COVERAGE_MOMENTS:
        for estimator in COVERAGE_ESTIMATORS:
            column = moment if estimator == "plain" else f"{moment}_{estimator}"
            if column not in summary:  # a summary from before the martingale columns
                out[moment, estimator] = np.nan
                continue
            value, error = float(summary[column]), float(summary[f"{column}_err"])
            finite = np.isfinite(value) and np.isfinite(error) and error > 0.0
            out[moment, estimator] = (value - reference[moment]) / error if finite else np.nan
    return out


def student_t_coverage(shards: int, limit: float = COVERAGE_Z_LIMIT) -> tuple[float, float]:
    """What z = (estimate - exact) / error gives if it follows Student's t with n - 1 degrees
    of freedom (a mean of n independent, normal shard values over its standard error).

    Parameters
    ----------
    shards : int
        n, at least 2.
    limit : float, optional
        The abs(z) counted as a miss, positive.

    Returns
    -------
    tuple of float
        E[z^2] = (n - 1) / (n - 3), NaN for n <= 3 (where it is infinite), and
        P(abs(z) > ``limit``) = 2 P(t_{n-1} < -limit) (``scipy.special.stdtr``).

    Examples
    --------
    >>> from bouncing_ball.workflow.studies import student_t_coverage
    >>> print([round(value, 4) for value in student_t_coverage(64)])
    [1.0328, 0.0498]
    """
    if isinstance(shards, bool) or not isinstance(shards, (int, np.integer)) or shards < 2:
        raise ValueError(f"shards = {shards!r}: a whole number of at least 2")
    if not limit > 0:
        raise ValueError(f"limit = {limit!r}: must be positive")
    dof = shards - 1
    mean_square = dof / (dof - 2) if dof > 2 else np.nan
    return float(mean_square), float(2.0 * special.stdtr(dof, -limit))


def coverage_rows(z_scores: pd.DataFrame, shards: int) -> pd.DataFrame:
    """The coverage of the errors: per r, moment and estimator, how the runs' z scatter.

    Parameters
    ----------
    z_scores : pandas.DataFrame
        One row per (run, moment, estimator): columns ``r_label``, ``run``, ``moment``,
        ``estimator``, ``z`` (``run_z_scores``; NaN rows are left out of the statistics).
    shards : int
        The shards n of every run, at least 2: the expectations are Student's t with n - 1
        degrees of freedom (``student_t_coverage``; the controls' fitted slopes take more).

    Returns
    -------
    pandas.DataFrame
        One row per (r_label, moment, estimator), in the order of ``COVERAGE_MOMENTS`` and
        ``COVERAGE_ESTIMATORS``: ``runs`` (finite z), ``mean_z`` and ``mean_z_err`` (its
        standard error), ``mean_z2`` and ``mean_z2_err`` (the standard error of z^2 over the
        runs), ``miss`` (the fraction of abs(z) > ``COVERAGE_Z_LIMIT``) and ``miss_err`` (its
        binomial error if the errors are right, sqrt(P (1 - P) / runs) with P =
        ``expected_miss``: never 0, and the scale on which a departure from P is judged),
        ``expected_mean_z2``, ``expected_miss``.
        NaN where there are too few runs (an error needs two).
    """
    expected_z2, expected_miss = student_t_coverage(shards)
    rows = []
    for label in dict.fromkeys(z_scores["r_label"]):
        for moment in COVERAGE_MOMENTS:
            for estimator in COVERAGE_ESTIMATORS:
                chosen = z_scores[
                    (z_scores["r_label"] == label)
                    & (z_scores["moment"] == moment)
                    & (z_scores["estimator"] == estimator)
                ]
                z = chosen["z"].to_numpy(dtype=float)
                z = z[np.isfinite(z)]
                runs = len(z)
                miss = float(np.mean(np.abs(z) > COVERAGE_Z_LIMIT)) if runs else np.nan
                rows.append(
                    {
                        "r_label": label,
                        "moment": moment,
                        "estimator": estimator,
                        "shards": shards,
                        "runs": runs,
                        "mean_z": float(z.mean()) if runs else np.nan,
                        "mean_z_err": _standard_error(z),
                        "mean_z2": float(np.mean(z**2)) if runs else np.nan,
                        "mean_z2_err": _standard_error(z**2),
                        "miss": miss,
                        "miss_err": (
                            float(np.sqrt(expected_miss * (1 - expected_miss) / runs))
                            if runs
                            else np.nan
                        ),
                        "expected_mean_z2": expected_z2,
                        "expected_miss": expected_miss,
                    }
                )
    return pd.DataFrame(rows)


def _standard_error(values) -> float:
    """The standard error of the mean of ``values``; NaN with fewer than two."""
    return float(values.std(ddof=1) / np.sqrt(len(values))) if len(values) >= 2 else np.nan


def coverage_markdown(table: pd.DataFrame, runs: dict) -> str:
    """The coverage report for a reader; ``runs`` is {r label: number of runs}."""
    shown = pd.DataFrame(
        {
            "r": table.r_label,
            "moment": table.moment.map(COVERAGE_SYMBOLS),
            "estimator": table.estimator,
            "runs": table.runs.astype(str),
            "mean z": [_pm(v, e, "{:+.2f}") for v, e in zip(table.mean_z, table.mean_z_err)],
            "mean z^2": [_pm(v, e, "{:.2f}") for v, e in zip(table.mean_z2, table.mean_z2_err)],
            "t: mean z^2": table.expected_mean_z2.map(_shown("{:.3f}")),
            f"abs z > {COVERAGE_Z_LIMIT:g}": [
                _pm(v, e, "{:.3f}") for v, e in zip(table.miss, table.miss_err)
            ],
            f"t: P(abs t > {COVERAGE_Z_LIMIT:g})": table.expected_miss.map(_shown("{:.3f}")),
        }
    )
    shards = table.shards.iloc[0]
    described = ", ".join(f"r = {label}: {count} runs" for label, count in runs.items())
    return (
        "# Coverage of the jackknife errors against the exact r = 1/2 and 1/3 results\n\n"
        f"Independent runs ({described}) of {shards} shards each; per run and estimator "
        "z = (estimate - exact) / jackknife error. If the errors are right, z follows "
        f"Student's t with n - 1 = {shards - 1} degrees of freedom (columns t: ...; the controlled "
        "estimators fit their slopes to the same shards, which leaves fewer), so mean z is 0, "
        f"mean z^2 is (n - 1)/(n - 3) and abs z exceeds {COVERAGE_Z_LIMIT:g} with "
        "the probability P given. Errors: the standard errors of mean z and mean z^2 over the "
        "runs, and the binomial error of the fraction under t, sqrt(P (1 - P) / runs). "
        "Controlled: blank with too few shards "
        "to fit the control slopes.\n\n"
        + shown.to_markdown(index=False, disable_numparse=True)
        + "\n"
    )


def _pm(value, error, form: str) -> str:
    """``value ± error`` in ``form``; blank for NaN, the value alone without an error."""
    if not np.isfinite(value):
        return ""
    shown = form.format(value)
    return f"{shown} ± {form.format(error).lstrip('+')}" if np.isfinite(error) else shown
