"""Benchmarks on the machine it runs on: ``python -m bouncing_ball.benchmark [--json]``.

Measured here:
  * the solver of eq. (inteq): time per r (median of repeats after a warm-up
    that pays numba's compile or cache load), nodes, and accuracy against the
    exact r = 1/2 and 1/3 solutions over v in [1e-3, 20];
    target: 50 ms or less per r at relative error 1e-8.

BLAS is pinned to one thread (as Snakemake does in every job), so times are per core.
"""

import argparse
import json
import os
import sys
import time

SINGLE_THREAD = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")

SOLVER_RESTITUTIONS = (0.05, 0.1, 0.25, 1.0 / 3.0, 0.5, 0.75, 0.9, 0.95, 0.99)
SOLVER_TARGET_SECONDS = 0.050
SOLVER_TARGET_ERROR = 1e-8


def _median_seconds(function, repeats):
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return sorted(times)[len(times) // 2]


def solver_benchmark(repeats=7):
    import numpy as np

    from . import exact, solver

    solver.solve_outgoing_speed_density(0.5)  # warm-up: numba compile or cache load
    output_speeds = np.geomspace(1e-4, 50.0, 401)
    checked = np.geomspace(1e-3, 20.0, 400)
    rows = []
    for r in SOLVER_RESTITUTIONS:
        solution = solver.solve_outgoing_speed_density(r)
        seconds = _median_seconds(lambda: solver.solve_outgoing_speed_density(r), repeats)
        with_output = _median_seconds(
            lambda: solver.solve_outgoing_speed_density(r).outgoing_speed_density(output_speeds), repeats
        )
        row = {
            "r": r,
            "nodes": len(solution.speeds),
            "solve_ms": 1e3 * seconds,
            "solve_and_401_outputs_ms": 1e3 * with_output,
            "energy_balance_residual": solver.energy_balance_residual(solution),
        }
        if any(abs(r - float(e)) < 1e-12 for e in exact.EXACT_RESTITUTIONS):
            relative = solution.outgoing_speed_density(checked) / exact.outgoing_speed_density(checked, r) - 1.0
            row["error_vs_exact"] = float(np.max(np.abs(relative)))
        rows.append(row)
    worst_time = max(row["solve_ms"] for row in rows)
    worst_error = max(row.get("error_vs_exact", 0.0) for row in rows)
    return {
        "rows": rows,
        "worst_solve_ms": worst_time,
        "worst_error_vs_exact": worst_error,
        "target_met": worst_time <= 1e3 * SOLVER_TARGET_SECONDS and worst_error <= SOLVER_TARGET_ERROR,
    }


def _print_solver(result):
    print("Solver of eq. (inteq), one core (median of repeats, after warm-up)")
    print(f"{'r':>8} {'nodes':>6} {'solve ms':>9} {'+401 outputs ms':>16} {'energy resid':>13} {'err vs exact':>13}")
    for row in result["rows"]:
        error = f"{row['error_vs_exact']:.1e}" if "error_vs_exact" in row else "-"
        print(
            f"{row['r']:8.4g} {row['nodes']:6d} {row['solve_ms']:9.1f} {row['solve_and_401_outputs_ms']:16.1f}"
            f" {row['energy_balance_residual']:13.1e} {error:>13}"
        )
    verdict = "met" if result["target_met"] else "MISSED"
    print(
        f"target: <= {1e3 * SOLVER_TARGET_SECONDS:.0f} ms per r at <= {SOLVER_TARGET_ERROR:.0e}: {verdict}"
        f" (worst {result['worst_solve_ms']:.1f} ms, worst error {result['worst_error_vs_exact']:.1e})"
    )


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m bouncing_ball.benchmark", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print machine-readable JSON instead of tables")
    args = parser.parse_args(argv)
    results = {"solver": solver_benchmark()}
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        _print_solver(results["solver"])
    return 0


if __name__ == "__main__":
    if any(os.environ.get(name) != "1" for name in SINGLE_THREAD):
        # BLAS reads these when numpy is first imported: start again with them set
        os.environ.update({name: "1" for name in SINGLE_THREAD})
        os.execv(sys.executable, [sys.executable, "-m", "bouncing_ball.benchmark", *sys.argv[1:]])
    sys.exit(main())
