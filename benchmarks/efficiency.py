"""Statistical efficiency per observable: (relative standard error)^2 x CPU seconds.

For each r of ``RESTITUTIONS`` and each of two estimators,
  * ``paper``: the paper's c = 5 and plain tallies (time averages, counts over time);
  * ``default``: the default config's c and the variance reductions independent of the theory
    (the martingale-controlled estimate of ``estimators`` where a table has one: the summary's
    moments, P(0, v), P(x), <v^2>_x),
``SHARDS`` shards run in two processes and each observable's relative standard error is
measured from their scatter (the jackknife of ``estimators``), times the CPU seconds of the
shards: the CPU it takes to reach a relative error of 1 (lower is better).  For P(0, v),
P(x), <v^2>_x and P(x, v) it is the median over the bins inside ``SPEEDS`` and
``POSITIONS``.  The gain is paper / default.

A jackknife error from n shards is itself uncertain (about sqrt(2 / (n - 1)) for Gaussian
shards, more with heavy tails): each efficiency's uncertainty is the delete-one jackknife of
its relative squared error (the error of the error), the whole estimate (cross-fitting
included) repeated without each shard; the gain's adds the two in quadrature.
"""

import time

import numpy as np

RESTITUTIONS = (0.25, 0.5, 0.75, 0.95, 0.99)
ESTIMATORS = ("paper", "default")
# shards per (r, estimator): as many as the default run's, so the cross-fitted slopes are as
# noisy as there; the CPU a shard takes is in the benchmark's report
SHARDS = 64
# Near r = 1 (0.95, 0.99) a shard spans hundreds of relaxation times (``Equilibrium(r).
# relaxation_time``), and every shard discards the default equilibration time at its r
# (``simulation.equilibration.default_equilibration_time``), counted in its CPU seconds.
SHARD_TIMES = {0.25: 4.0e4, 0.5: 1.0e5, 0.75: 4.0e5, 0.95: 1.0e6, 0.99: 1.0e7}
# the bins over which the median is taken
SPEEDS = (0.01, 5.0)
POSITIONS = (1.0e-3, 50.0)
MOMENTS = {
    "I": "collision_rate",
    "<x>": "mean_x",
    "Delta x": "delta_x",
    "<T>": "mean_flight_time",
    "<T^2>": "flight_time_second_moment",
}
DISTRIBUTIONS = ("P(0,v)", "P(x)", "<v^2>_x", "P(x,v)")
OBSERVABLES = (*MOMENTS, *DISTRIBUTIONS)


def moment_relative_squared_errors(shards, r, controlled):
    """{observable: (relative standard error)^2} of the moments of ``MOMENTS`` from ``shards``:
    plain, or (``controlled``) the summary's estimate that the moments table shows, the
    martingale-controlled ``*_martingale`` (``validation.independent_estimate``)."""
    from bouncing_ball.estimators import position_moments_summary

    summary = position_moments_summary(shards, r).iloc[0]
    values = {}
    for observable, name in MOMENTS.items():
        column = f"{name}_martingale" if controlled else name
        if column not in summary or not np.isfinite(summary[column]):
            column = name
        values[observable] = (summary[f"{column}_err"] / summary[column]) ** 2
    return values


def _median_relative_squared_error(table, name, keep, controlled):
    """The median over the bins ``keep`` of (error / value)^2 of column ``name`` of ``table``,
    or (``controlled``) of its martingale-controlled column (``_martingale``, else
    ``_controlled``: P(x) and <v^2>_x, whose controls are the noise sums) where it has one:
    the estimates independent of the theory."""
    if controlled:
        for suffix in ("_martingale", "_controlled"):
            if f"{name}{suffix}" in table:
                name = f"{name}{suffix}"
                break
    value, error = table[name].to_numpy(), table[f"{name}_err"].to_numpy()
    keep = keep.to_numpy() & np.isfinite(value) & np.isfinite(error) & (value > 0)
    return float(np.median((error[keep] / value[keep]) ** 2))


def distribution_relative_squared_errors(shards, controlled, r=None, return_law=None):
    """{observable: median over the bins inside SPEEDS and POSITIONS of (relative standard
    error)^2} of P(0, v), P(x), <v^2>_x and P(x, v) (v within +-SPEEDS[1] for P(x, v)):
    plain, or (``controlled``) the tables' ``*_controlled`` estimates where they have one,
    P(0, v)'s with the return-law control of r (``return_law``: the shards' prediction,
    ``estimators.return_law_prediction``, if at hand)."""
    from bouncing_ball.estimators import (
        distribution_histogram,
        outgoing_speed_histogram,
        position_histogram,
    )

    theory = None  # the solver's P(0, u), for the return-law control
    if controlled and return_law is None:
        from bouncing_ball.solver import solved_outgoing_density

        theory = solved_outgoing_density(r)
    speeds = outgoing_speed_histogram(
        shards, r if controlled else None, theory, return_law=return_law
    )
    positions = position_histogram(shards)
    cells = distribution_histogram(shards)
    in_speeds = (speeds.v_lo >= SPEEDS[0]) & (speeds.v_hi <= SPEEDS[1])
    in_positions = (positions.x_lo >= POSITIONS[0]) & (positions.x_hi <= POSITIONS[1])
    in_cells = (
        (cells.x_lo >= POSITIONS[0])
        & (cells.x_hi <= POSITIONS[1])
        & (cells.v_lo >= -SPEEDS[1])
        & (cells.v_hi <= SPEEDS[1])
    )
    return {
        "P(0,v)": _median_relative_squared_error(speeds, "p0v", in_speeds, controlled),
        "P(x)": _median_relative_squared_error(positions, "px", in_positions, controlled),
        "<v^2>_x": _median_relative_squared_error(
            positions, "v2_given_x", in_positions, controlled
        ),
        "P(x,v)": _median_relative_squared_error(cells, "pxv", in_cells, controlled),
    }


def relative_squared_errors(shards, r, controlled, return_law=None):
    """{observable: (relative standard error)^2} of every observable of ``OBSERVABLES``."""
    return {
        **moment_relative_squared_errors(shards, r, controlled),
        **distribution_relative_squared_errors(shards, controlled, r, return_law),
    }


def with_error_of_error(shards, r, controlled):
    """{observable: (relative squared error, its delete-one jackknife standard error)}: the
    estimate of ``relative_squared_errors`` from all shards, and repeated without each."""
    from bouncing_ball.estimators import return_law_prediction
    from bouncing_ball.solver import solve_outgoing_speed_density

    law = None
    if controlled:  # a row per shard: the same rows without shard k
        density = solve_outgoing_speed_density(r).outgoing_speed_density
        law = return_law_prediction(shards, r, density)
    full = relative_squared_errors(shards, r, controlled, law)
    n = len(shards)
    leave_one_out = [
        relative_squared_errors(
            shards[:k] + shards[k + 1 :],
            r,
            controlled,
            None if law is None else np.delete(law, k, axis=0),
        )
        for k in range(n)
    ]
    result = {}
    for observable, value in full.items():
        others = np.array([values[observable] for values in leave_one_out])
        spread = np.sqrt((n - 1) / n * ((others - others.mean()) ** 2).sum())
        result[observable] = (float(value), float(spread))
    return result


def efficiency_rows(measurements):
    """The rows of the efficiency table from ``measurements``: {(estimator, r): {"cpu_seconds":
    CPU s of its shards, "relative_squared_errors": {observable: (value, error)}}} for both
    estimators of ``ESTIMATORS`` at each r.  Each row: observable, r, paper and default
    ((relative squared error) x CPU s), gain (paper / default), and the uncertainty of each
    (``*_err``; the gain's from the two relative uncertainties in quadrature)."""
    rows = []
    restitutions = sorted({r for _, r in measurements})
    for observable in OBSERVABLES:
        for r in restitutions:
            row = {"observable": observable, "r": r}
            relative = {}
            for estimator in ESTIMATORS:
                measured = measurements[(estimator, r)]
                value, error = measured["relative_squared_errors"][observable]
                row[estimator] = value * measured["cpu_seconds"]
                row[f"{estimator}_err"] = error * measured["cpu_seconds"]
                relative[estimator] = error / value
            row["gain"] = row["paper"] / row["default"]
            row["gain_err"] = row["gain"] * float(np.hypot(relative["paper"], relative["default"]))
            rows.append(row)
    return rows


def _timed_shard(arguments):
    from .shards import run_shard

    r, recorded_time, equilibration_time, shard, criterion_c = arguments
    started = time.process_time()
    tallies = run_shard(
        r,
        recorded_time,
        shard=shard,
        seed=7,
        criterion_c=criterion_c,
        equilibration_time=equilibration_time,
    )
    return tallies, time.process_time() - started


def efficiency_benchmark(shards=SHARDS, shard_times=None):
    """Run the shards of every (estimator, r) in two processes and return the efficiency table
    (``efficiency_rows``) with what was run."""
    from concurrent.futures import ProcessPoolExecutor

    from bouncing_ball.simulation.equilibration import default_equilibration_time

    from .shards import PAPER_CRITERION_C, SHARD_SETTINGS, run_shard

    shard_times = shard_times or SHARD_TIMES
    criteria = {"paper": PAPER_CRITERION_C, "default": SHARD_SETTINGS.criterion_c}
    run_shard(0.5, 10.0)  # compile or load the cache here before the pool forks
    measurements = {}
    with ProcessPoolExecutor(2) as pool:
        for r, recorded_time in shard_times.items():
            equilibration_time = default_equilibration_time(r)  # a solve: once per r, here
            for estimator, criterion_c in criteria.items():
                jobs = [
                    (r, recorded_time, equilibration_time, k, criterion_c) for k in range(shards)
                ]
                results = list(pool.map(_timed_shard, jobs))
                tallies = [t for t, _ in results]
                measurements[(estimator, r)] = {
                    "cpu_seconds": sum(seconds for _, seconds in results),
                    "relative_squared_errors": with_error_of_error(
                        tallies, r, controlled=estimator == "default"
                    ),
                }
    return {
        "shards": shards,
        "shard_times": {str(r): t for r, t in shard_times.items()},
        "criterion_c": criteria,
        "speeds": list(SPEEDS),
        "positions": list(POSITIONS),
        "cpu_seconds": {
            f"{estimator} r={r:g}": m["cpu_seconds"] for (estimator, r), m in measurements.items()
        },
        "rows": efficiency_rows(measurements),
    }
