"""Benchmarks on the machine it runs on (from the repository root):

    python -m benchmarks [--json] [--markdown FILE] [--scaling] [--efficiency-only]
                         [--breakdown-only]

prints the tables as Markdown (``report``), or writes them to FILE with the machine and
the time of the run (e.g. ``--markdown results/benchmarks/benchmark.md``); ``--json``
prints the results themselves.

Measured here (``--scaling`` adds the stage on 1 and 2 cores, outside the default run):
  * simulation throughput on one core at r = 0.25, 0.5, 0.75 with the default
    config's c and delta rule (c = 3, 1/500) and with the paper's c = 5:
    collisions and simulated time per CPU second, steps per collision, ns per
    step, and the CPU per simulated time the default c saves;
  * where a step's time goes at r = 1/2 and c = 5, 3 (``breakdown``,
    alone with ``--breakdown-only``): ns per step of the
    stepping and of each tally, of the criterion root and of the normals, and collisions
    per CPU second against the hand-tuned C loop (``reference/hand_tuned.c``, measured in
    the same run; targets: 0.9 of it stepping, 0.8 with every tally);
  * the same loop in plain C (``reference/shard_loop.c``, gcc -O3, numpy's
    own ziggurat on the same PCG64 stream, so the tallies must be identical):
    numba's speed over C's at r = 1/2, with the tallies and stepping only
    (target: at least 90%);
  * statistical efficiency per observable (``efficiency``, alone with
    ``--efficiency-only``): (relative standard error)^2 x CPU seconds at r = 1/4, 1/2, 3/4, 0.95
    and 0.99 (``efficiency.RESTITUTIONS``) of
    I, <x>, Delta x, <T>, <T^2> and the median bin of P(0, v), P(x), <v^2>_x, P(x, v), for
    the paper's estimator (c = 5, plain tallies) and the project's default (the default c,
    every control variate), their gain and the uncertainty of each;
  * numba's compile: the first shard in a fresh cache against a later shard
    (a new process that loads the cache), and the peak memory of a shard;
  * the solver of eq. (inteq): time per r (median of repeats after a warm-up
    that pays numba's compile or cache load), nodes, and accuracy against the
    exact r = 1/2 and 1/3 solutions over v in [1e-3, 20]; target: 50 ms or
    less per r at relative error 1e-8;
  * the first P(x) curve of 1000 points at a new r (0.6, 0.95, 0.99) after its solve, in a
    fresh process with numba's on-disk cache cold and warm, and the second curve (target: the
    first, warm, within 1 s);
  * the workflow's overhead (from a repository checkout): the dry run of a
    grid of 20 r values x 16 shards (target < 5 s), and a no-op rerun of the
    default workflow (target < 3 s; only where its results are complete);
  * with ``--scaling``: the simulation stage (16 shards of r = 1/2, about 5
    CPU s each, and their merge) with --cores 1 and
    --cores 2 (target: at least 1.8 times as fast).

BLAS is pinned to one thread (as Snakemake does in every job), so times are per core.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

from .breakdown import breakdown
from .efficiency import efficiency_benchmark
from .report import (
    FIRST_CURVE_TARGET_SECONDS,
    REFERENCE_TARGET,
    SOLVER_TARGET_MS,
    machine_info,
    markdown_report,
)
from .shards import PAPER_CRITERION_C, SHARD_SETTINGS, run_shard

SINGLE_THREAD = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")

SOLVER_RESTITUTIONS = (0.05, 0.1, 0.25, 1.0 / 3.0, 0.5, 0.75, 0.9, 0.95, 0.99)

REPOSITORY = Path(__file__).resolve().parents[1]


# simulated time per throughput shard: long enough for a steady rate (the report gives the
# simulated time per CPU second at each r, so the CPU of a shard)
THROUGHPUT_TIMES = {0.25: 6.0e5, 0.5: 2.0e6, 0.75: 6.0e6}


def simulation_benchmark():
    """Throughput on one core with the default config's c and delta rule, and with the paper's c = 5
    (same code, same streams): the CPU the default c saves per simulated time."""
    run_shard(0.5, 10.0)  # warm-up: compile or load the cache
    rows = []
    for r, recorded_time in THROUGHPUT_TIMES.items():
        for criterion_c in (SHARD_SETTINGS.criterion_c, PAPER_CRITERION_C):
            seconds = float("inf")
            for _ in range(2):  # the better of two: a one-off stall of the machine does not count
                started = time.process_time()
                tallies = run_shard(r, recorded_time, criterion_c=criterion_c)
                seconds = min(seconds, time.process_time() - started)
            rows.append(
                {
                    "r": r,
                    "criterion_c": criterion_c,
                    "cpu_seconds": seconds,
                    "collisions_per_cpu_second": tallies.collisions / seconds,
                    "simulated_time_per_cpu_second": tallies.time / seconds,
                    "steps_per_collision": tallies.steps / tallies.collisions,
                    "ns_per_step": 1e9 * seconds / tallies.steps,
                }
            )
    return {
        "rows": rows,
        "default_c": SHARD_SETTINGS.criterion_c,
        "paper_c": PAPER_CRITERION_C,
        "min_step_divisor": SHARD_SETTINGS.min_step_divisor,
    }


def reference_benchmark(r=0.5, recorded_time=2.0e6, repeats=3):
    """The numba loop against the C reference of the same loop (``reference_loop``), same stream:
    best of ``repeats`` CPU times each, with the tallies and without (all steps as equilibration)."""
    from . import reference_loop

    try:
        reference_loop.build()
    except (RuntimeError, OSError) as error:  # no compiler or headers; a read-only package folder
        return {"skipped": str(error).splitlines()[0]}
    from bouncing_ball.simulation import simulate_shard

    loops = {"numba": simulate_shard, "c": reference_loop.reference_shard}
    for loop in loops.values():
        run_shard(r, 10.0, loop=loop, equilibration_time=0.0)  # compile, build or load
    rows = []
    for case, recorded, equilibration in (
        ("with tallies", recorded_time, 100.0),
        ("stepping only", 1e-9, recorded_time),
    ):
        best = {name: float("inf") for name in loops}
        results = {}
        for _ in range(repeats):  # interleaved, so a change of machine load hits both
            for name, loop in loops.items():
                started = time.process_time()
                results[name] = run_shard(r, recorded, loop=loop, equilibration_time=equilibration)
                best[name] = min(best[name], time.process_time() - started)
        same = not reference_loop.differing_tallies(results["numba"], results["c"])
        rows.append(
            {
                "case": case,
                "numba_cpu_seconds": best["numba"],
                "c_cpu_seconds": best["c"],
                "speed_ratio": best["c"] / best["numba"],
                "identical_tallies": bool(same),
            }
        )
    ratio = min(row["speed_ratio"] for row in rows)
    return {
        "r": r,
        "simulated_time": recorded_time,
        "criterion_c": SHARD_SETTINGS.criterion_c,
        "min_step_divisor": SHARD_SETTINGS.min_step_divisor,
        "compiler": " ".join(reference_loop.FLAGS),
        "rows": rows,
        "worst_speed_ratio": ratio,
        "target_met": ratio >= REFERENCE_TARGET,
    }


_PROBE = """
import json, resource, sys, time
started = time.perf_counter()
from bouncing_ball.settings import ShardSettings
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
imported = time.perf_counter()
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
def run(t):
    settings = ShardSettings(t, 100.0, 5.0, 500.0, 10**13)  # the default bins
    return simulate_shard(0.5, shard_seed_sequence(1, "0.5", 0), settings)
run(10.0)
first = time.perf_counter()
run(10.0)
second = time.perf_counter()
run(float(sys.argv[1]))
print(json.dumps({"import_s": imported - started, "first_call_s": first - imported,
                  "second_call_s": second - first, "rss_before_mib": before / 1024,
                  "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def compile_benchmark(memory_shard_time=2.0e5):
    """A shard in a new process with an empty numba cache, then another new process with the
    cache it left: the first pays the compile, the later one only loads it. Peak memory of a shard."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        runs = []
        for _ in range(2):
            output = subprocess.run(
                [sys.executable, "-c", _PROBE, str(memory_shard_time)],
                env=env,
                capture_output=True,
                text=True,
                check=True,
                timeout=300,
            ).stdout
            runs.append(json.loads(output))
    first, later = runs
    return {
        "first_shard_compile_seconds": first["first_call_s"],
        "later_shard_load_seconds": later["first_call_s"],
        "import_seconds": later["import_s"],
        "peak_memory_mib": later["peak_rss_mib"],
        "memory_before_shard_mib": later["rss_before_mib"],
        "memory_shard_time": memory_shard_time,
    }


def _workflow_copy(directory, config):
    import yaml

    for name in ("Snakefile", "workflow", "scripts", "config", "profiles"):
        source = REPOSITORY / name
        if source.is_dir():
            shutil.copytree(source, directory / name)
        elif source.exists():
            shutil.copy(source, directory / name)
    (directory / "config" / "config.yaml").write_text(yaml.safe_dump(config))


def _timed_snakemake(directory, *arguments):
    started = time.perf_counter()
    result = subprocess.run(
        [sys.executable, "-m", "snakemake", *arguments],
        cwd=directory,
        capture_output=True,
        text=True,
        timeout=600,
    )
    return time.perf_counter() - started, result


def workflow_benchmark():
    """Dry run of 20 r x 16 shards in a copy of the workflow; a no-op rerun of the default workflow."""
    import yaml

    if not (REPOSITORY / "Snakefile").exists():
        return {
            "skipped": f"no Snakefile next to the package ({REPOSITORY}): run from a repository checkout"
        }
    config = yaml.safe_load((REPOSITORY / "config" / "config.yaml").read_text())
    # 20 r inside the run's range (restitution.DISTRIBUTION_RESTITUTION_RANGE)
    config["restitution"] = [round(0.2 + 0.035 * k, 4) for k in range(20)]
    config["simulation"]["shards"] = 16
    config["simulation"]["shards_per_job"] = 1  # a job per shard: the largest plan
    config["simulation"]["per_restitution"] = {}
    # every figure's panels from the grid: 320 shard jobs
    config["figures"].update({name: [0.5] for name in ("fig4", "fig5", "fig8", "fig10", "fig11")})
    with tempfile.TemporaryDirectory() as folder:
        _workflow_copy(Path(folder), config)
        dry_run, result = _timed_snakemake(folder, "--cores", "2", "--dry-run", "--quiet", "rules")
        if result.returncode != 0:
            raise RuntimeError(f"the grid's dry run failed:\n{result.stderr[-2000:]}")
        jobs = next(
            (
                int(line.split()[1])
                for line in result.stdout.splitlines()
                if line.startswith("simulate_shard")
            ),
            0,
        )
    planned, result = _timed_snakemake(REPOSITORY, "--cores", "2", "--dry-run", "--quiet", "rules")
    complete = "Nothing to be done" in result.stdout + result.stderr
    noop = _timed_snakemake(REPOSITORY, "--cores", "2")[0] if complete else None
    return {
        "grid_shard_jobs": jobs,
        "grid_dry_run_seconds": dry_run,
        "default_results_complete": complete,
        "noop_seconds": noop,
        "default_dry_run_seconds": planned,
    }


def scaling_benchmark(shards=16, shard_time=5.0e6):
    """The simulation stage of ``shards`` shards of r = 1/2 with --cores 1 and with --cores 2."""
    import yaml

    config = yaml.safe_load((REPOSITORY / "config" / "config.yaml").read_text())
    config["restitution"] = [0.5]
    config["simulation"].update(
        # 8 jobs of 2 shards: work that 2 cores can share
        {"shards": shards, "shard_time": shard_time, "shards_per_job": 2, "per_restitution": {}}
    )
    times = {}
    for cores in (1, 2):
        with tempfile.TemporaryDirectory() as folder:
            _workflow_copy(Path(folder), config)
            seconds, result = _timed_snakemake(folder, "--cores", str(cores), "simulation")
            if result.returncode != 0:
                raise RuntimeError(result.stderr[-2000:])
            times[cores] = seconds
    return {
        "shards": shards,
        "shard_time": shard_time,
        "cores_1_seconds": times[1],
        "cores_2_seconds": times[2],
        "speedup": times[1] / times[2],
    }


def _median_seconds(function, repeats):
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return sorted(times)[len(times) // 2]


def solver_benchmark(repeats=7):
    import numpy as np

    from bouncing_ball import exact, solver

    solver.solve_outgoing_speed_density(0.5)  # warm-up: numba compile or cache load
    output_speeds = np.geomspace(1e-4, 50.0, 401)
    checked = solver.CHECKED_SPEEDS
    rows = []
    for r in SOLVER_RESTITUTIONS:
        solution = solver.solve_outgoing_speed_density(r)
        seconds = _median_seconds(lambda r=r: solver.solve_outgoing_speed_density(r), repeats)
        with_output = _median_seconds(
            lambda r=r: solver.solve_outgoing_speed_density(r).outgoing_speed_density(
                output_speeds
            ),
            repeats,
        )
        row = {
            "r": r,
            "nodes": len(solution.speeds),
            "solve_ms": 1e3 * seconds,
            "solve_and_401_outputs_ms": 1e3 * with_output,
            "energy_balance_residual": solver.energy_balance_residual(solution),
        }
        if any(abs(r - float(e)) < 1e-12 for e in exact.EXACT_RESTITUTIONS):
            relative = (
                solution.outgoing_speed_density(checked) / exact.outgoing_speed_density(checked, r)
                - 1.0
            )
            row["error_vs_exact"] = float(np.max(np.abs(relative)))
        rows.append(row)
    worst_time = max(row["solve_ms"] for row in rows)
    worst_error = max(row.get("error_vs_exact", 0.0) for row in rows)
    return {
        "rows": rows,
        "worst_solve_ms": worst_time,
        "worst_error_vs_exact": worst_error,
        "accuracy_target": solver.ACCURACY_TARGET,
        "target_met": worst_time <= SOLVER_TARGET_MS and worst_error <= solver.ACCURACY_TARGET,
    }


DISTRIBUTION_RESTITUTIONS = (0.25, 0.5, 0.75, 0.99)


def distribution_benchmark():
    """What rule solve adds to P(0, v) for one r, with the default config's grids: w(F)
    (bouncing_ball.distribution), the P(x), P(x, v) and w tables, the flight-time and
    return-speed tables (bouncing_ball.flight_time)."""
    from bouncing_ball import distribution, flight_time, solver
    from bouncing_ball.bins import linear_grid, log_bins, log_grid
    from bouncing_ball.workflow import solver_tables
    from bouncing_ball.workflow.config import read_config

    config = read_config(REPOSITORY / "config" / "config.yaml")
    grids = config["solver"]
    speed_bins = log_bins(config["simulation"]["speed_bins"])
    rows = []
    for r in DISTRIBUTION_RESTITUTIONS:
        started = time.perf_counter()
        far = distribution.outgoing_speed_solution(r)
        weight = distribution.interpolated_weight_function(far)
        built = time.perf_counter()
        solver_tables.position_frame(weight, log_grid(grids["position_grid"]))
        solver_tables.weight_frame(weight, log_grid(grids["forces"]))
        tabulated = time.perf_counter()
        solver_tables.distribution_frame(
            weight, far, grids["positions"], linear_grid(grids["speeds"])
        )
        joint = time.perf_counter()
        solution = solver.solve_outgoing_speed_density(r)
        flight_time.flight_time_table(solution, log_grid(grids["flight_times"]))
        flight_time.return_speed_table(solution, speed_bins)
        collisions = time.perf_counter()
        rows.append(
            {
                "r": r,
                "weight_function_seconds": built - started,
                "position_and_weight_tables_seconds": tabulated - built,
                "distribution_table_seconds": joint - tabulated,
                "collision_tables_seconds": collisions - joint,
                "total_seconds": collisions - started,
            }
        )
    return {"rows": rows}


FIRST_CURVE_RESTITUTIONS = (0.6, 0.95, 0.99)


FIRST_CURVE_POINTS = 1000


# a fresh process: solve (untimed), then time (CPU) the first P(x) curve over the span of P(x)
# (1e-6 / q^2 to (22 / b)^2, b the large-x rate: docs/distribution.md) and a second one
_FIRST_CURVE = """
import json, sys, time
import numpy as np
from bouncing_ball import Equilibrium
from bouncing_ball.asymptotics import large_speed_decay_rate
r, points = float(sys.argv[1]), int(sys.argv[2])
q = large_speed_decay_rate(r)
b = q * np.sqrt(2.0 * (3.0 - 2.0 * q) / 3.0) if r > 0.5 else np.sqrt(2.0 / 3.0)
x = np.geomspace(1e-6 / q**2, (22.0 / b) ** 2, points)
eq = Equilibrium(r)
eq.p0v(1.0)
started = time.process_time()
eq.px(x)
first = time.process_time() - started
started = time.process_time()
eq.px(x)
print(json.dumps({"first": first, "second": time.process_time() - started}))
"""


def _first_curve(r, environment):
    output = subprocess.run(
        [sys.executable, "-c", _FIRST_CURVE, repr(r), str(FIRST_CURVE_POINTS)],
        capture_output=True,
        text=True,
        check=True,
        cwd=REPOSITORY,
        env=environment,
    ).stdout
    return json.loads(output.strip().splitlines()[-1])


def first_curve_benchmark():
    """The first P(x) curve of FIRST_CURVE_POINTS points at a new r after its solve (building
    w(F) of eq. (weightfunc) and P(x) of eq. (P(x)1)), in CPU seconds of one core (BLAS pinned
    to one thread, so a shared machine's load does not count), each in a fresh process: with numba's
    on-disk cache cold (an empty NUMBA_CACHE_DIR: the compile is in the time) and warm (a
    second process on the same cache), and the second curve in the same process."""
    rows = []
    for r in FIRST_CURVE_RESTITUTIONS:
        with tempfile.TemporaryDirectory() as cache:
            environment = {**os.environ, "NUMBA_CACHE_DIR": cache}
            cold = _first_curve(r, environment)
            warm = _first_curve(r, environment)
        rows.append(
            {
                "r": r,
                "points": FIRST_CURVE_POINTS,
                "first_cold_seconds": cold["first"],
                "first_warm_seconds": warm["first"],
                "second_seconds": warm["second"],
            }
        )
    worst = max(row["first_warm_seconds"] for row in rows)
    return {
        "rows": rows,
        "worst_first_warm_seconds": worst,
        "target_met": worst <= FIRST_CURVE_TARGET_SECONDS,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--json", action="store_true", help="print machine-readable JSON instead of tables"
    )
    parser.add_argument(
        "--markdown",
        metavar="FILE",
        type=Path,
        help="write the tables as Markdown to FILE (e.g. results/benchmarks/benchmark.md)",
    )
    parser.add_argument(
        "--scaling", action="store_true", help="also time the simulation stage with 1 and 2 cores"
    )
    parser.add_argument(
        "--efficiency-only",
        action="store_true",
        help="measure only the statistical efficiency per observable (``efficiency``)",
    )
    parser.add_argument(
        "--breakdown-only",
        action="store_true",
        help="measure only where a step goes, against the hand-tuned C loop (``breakdown``)",
    )
    args = parser.parse_args(argv)
    started = time.perf_counter()
    results = {
        "started_utc": datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S"),
        "machine": machine_info(),
    }
    if args.efficiency_only:
        results["efficiency"] = efficiency_benchmark()
    elif args.breakdown_only:
        results["breakdown"] = breakdown(SHARD_SETTINGS)
    else:
        _full_benchmark(results, args.scaling)
    results["seconds"] = time.perf_counter() - started
    if args.json:
        print(json.dumps(results, indent=2))
    report = markdown_report(results)
    if args.markdown:
        write_markdown(report, args.markdown)
        print(f"wrote {args.markdown}", file=sys.stderr)
    elif not args.json:
        print(report)
    return 0


def _full_benchmark(results, scaling):
    """Every measurement into ``results`` (with ``scaling``, the simulation stage on 1 and 2
    cores too); the solver first, timed in a process that has run nothing else."""
    results["solver"] = solver_benchmark()
    results.update(
        {
            "simulation": simulation_benchmark(),
            "breakdown": breakdown(SHARD_SETTINGS),
            "reference": reference_benchmark(),
            "efficiency": efficiency_benchmark(),
            "compile": compile_benchmark(),
            "distribution": distribution_benchmark(),
            "first_curve": first_curve_benchmark(),
            "workflow": workflow_benchmark(),
        }
    )
    if scaling:
        results["scaling"] = scaling_benchmark()


def write_markdown(report: str, path) -> None:
    """Write ``report`` to ``path``, making its folder."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(report)


def run_single_threaded(module="benchmarks"):
    """``main()`` with BLAS pinned to one thread, as Snakemake does in every job: the
    variables are read when numpy is first imported, so start again with them set."""
    if any(os.environ.get(name) != "1" for name in SINGLE_THREAD):
        os.environ.update(dict.fromkeys(SINGLE_THREAD, "1"))
        os.execv(sys.executable, [sys.executable, "-m", module, *sys.argv[1:]])
    sys.exit(main())


if __name__ == "__main__":
    run_single_threaded("benchmarks.benchmark")
