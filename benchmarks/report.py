"""The benchmark's results as Markdown: the machine, the time of the run and every table.

``python -m benchmarks`` prints ``markdown_report`` of its results; ``--markdown FILE``
writes it to FILE (e.g. results/benchmarks/benchmark.md).  The results are the dict that
``--json`` prints (``benchmark.main``); ``machine_info`` says where they were measured.
"""

import os
import platform
import sys
from importlib import metadata

import pandas as pd

# targets of the measurements (the benchmark's docstring says why)
REFERENCE_TARGET = 0.9  # numba's speed at least 90% of the C reference's
TARGET_STEPPING = 0.9  # of the hand-tuned loop's collisions per CPU second, stepping alone
SOLVER_TARGET_MS = 50.0  # per r, at the solver's accuracy target
FIRST_CURVE_TARGET_SECONDS = 1.0  # the first P(x) curve at a new r after the solve, warm cache
# the least gain in efficiency of the default estimator over the paper's, by observable
EFFICIENCY_TARGETS = {
    **dict.fromkeys(("I", "<x>", "Delta x", "<T>", "<T^2>"), 4.0),
    "P(x)": 2.0,
    "<v^2>_x": 2.0,
}
WORKFLOW_TARGETS = {
    "noop_seconds": 3.0,
    "grid_dry_run_seconds": 5.0,
    "cores_speedup": 1.8,
    "compile_later_seconds": 0.5,
}


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            for line in cpuinfo:
                if line.lower().startswith(("model name", "hardware", "cpu model")):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


def machine_info() -> dict:
    """Where a benchmark runs: CPU model, cores, operating system, Python and the versions of
    the packages whose code is timed."""
    return {
        "cpu_model": _cpu_model(),
        "cores": os.cpu_count(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        **{package: _version(package) for package in ("numba", "numpy", "scipy", "snakemake")},
    }


def _table(rows: list[dict]) -> str:
    return pd.DataFrame(rows).to_markdown(index=False, disable_numparse=True) + "\n"


def _verdict(value, target, larger_is_better=False) -> str:
    if value is None:
        return "not measured"
    return "met" if (value >= target if larger_is_better else value <= target) else "MISSED"


def _header(results) -> str:
    machine = results["machine"]
    rows = [
        {"": "CPU", "value": machine["cpu_model"]},
        {"": "cores", "value": str(machine["cores"])},
        {"": "platform", "value": machine["platform"]},
        {"": "Python", "value": machine["python"]},
        *(
            {"": package, "value": machine[package]}
            for package in ("numba", "numpy", "scipy", "snakemake")
        ),
    ]
    return (
        "# Benchmark\n\n"
        f"One run of `python -m benchmarks`, started {results['started_utc']} (UTC), "
        f"{results['seconds']:.0f} s. CPU times on one core (BLAS pinned to one thread), "
        "best of repeats unless said otherwise.\n\n" + _table(rows)
    )


def _simulation(results) -> str:
    section = results["simulation"]
    rows = [
        {
            "r": f"{row['r']:g}",
            "c": f"{row['criterion_c']:g}",
            "CPU s": f"{row['cpu_seconds']:.2f}",
            "collisions / CPU s": f"{row['collisions_per_cpu_second']:.3g}",
            "simulated time / CPU s": f"{row['simulated_time_per_cpu_second']:.3g}",
            "steps / collision": f"{row['steps_per_collision']:.1f}",
            "ns / step": f"{row['ns_per_step']:.0f}",
        }
        for row in section["rows"]
    ]
    text = (
        f"## Simulation throughput\n\nOne shard per row, the default c = {section['default_c']:g} "
        f"and the paper's c = {section['paper_c']:g}, the 1/{section['min_step_divisor']:g} "
        "rule for delta.\n\n" + _table(rows)
    )
    default, paper = section["default_c"], section["paper_c"]
    rate = {
        (row["r"], row["criterion_c"]): row["simulated_time_per_cpu_second"]
        for row in section["rows"]
    }
    restitutions = sorted({row["r"] for row in section["rows"]})
    if default != paper and all((r, c) in rate for r in restitutions for c in (default, paper)):
        saving = ", ".join(
            f"{100 * (1 - rate[r, paper] / rate[r, default]):.0f}% at r = {r:g}"
            for r in restitutions
        )
        text += f"\nCPU per simulated time saved by c = {default:g} over c = {paper:g}: {saving}.\n"
    return text


def _breakdown(results) -> str:
    text = "## Where a step goes\n\n"
    anchors = []
    for row in results["breakdown"]:
        parts = [
            {
                "part": part["part"],
                "ns / step": f"{part['ns_per_step']:.1f}",
                "extra ns / step": (
                    f"{part['extra_ns_per_step']:.1f}" if "extra_ns_per_step" in part else ""
                ),
                "collisions / CPU s": f"{part['collisions_per_cpu_second']:.3g}",
            }
            for part in row["parts"]
        ]
        text += (
            f"r = {row['r']:g}, c = {row['criterion_c']:g} ('extra': over stepping). On their own: "
            f"the criterion root {row['criterion_root_ns']:.1f} ns a step from the loop's warm "
            f"start ({row['criterion_root_cold_start_ns']:.1f} from the cold start), two normals "
            f"{row['two_normals_ns']:.1f} ns.\n\n" + _table(parts) + "\n"
        )
        if "hand_tuned_skipped" in row:
            anchors.append(
                {"c": f"{row['criterion_c']:g}", "hand-tuned C loop": row["hand_tuned_skipped"]}
            )
            continue
        ratios = row["against_hand_tuned"]
        anchors.append(
            {
                "c": f"{row['criterion_c']:g}",
                "hand-tuned C loop, collisions / CPU s": (
                    f"{row['hand_tuned_collisions_per_cpu_second']:.3g}"
                ),
                "stepping / hand-tuned": f"{ratios['stepping']:.2f}",
                f"target {TARGET_STEPPING}": _verdict(ratios["stepping"], TARGET_STEPPING, True),
                "every tally / hand-tuned (no target: it tallies more)": (
                    f"{ratios['every tally']:.2f}"
                ),
            }
        )
    text += (
        "The shard loop's collisions per CPU second against the hand-tuned C loop "
        "(benchmarks/reference/hand_tuned.c), measured in this run, same r and c.\n\n"
        + _table(anchors)
    )
    return text


def _reference(results) -> str:
    ref = results["reference"]
    if "skipped" in ref:
        return f"## numba against the C reference\n\nNot measured: {ref['skipped']}.\n"
    rows = [
        {
            "case": row["case"],
            "numba CPU s": f"{row['numba_cpu_seconds']:.2f}",
            "C CPU s": f"{row['c_cpu_seconds']:.2f}",
            "numba speed / C speed": f"{row['speed_ratio']:.2f}",
            "identical tallies": str(row["identical_tallies"]),
        }
        for row in ref["rows"]
    ]
    verdict = _verdict(ref["worst_speed_ratio"], REFERENCE_TARGET, larger_is_better=True)
    return (
        "## numba against the C reference\n\nThe same loop in plain C "
        f"(benchmarks/reference/shard_loop.c, gcc {ref['compiler']}, the same random stream), "
        f"r = {ref['r']:g}, c = {ref['criterion_c']:g}, {ref['simulated_time']:.0e} time units."
        f"\n\n" + _table(rows) + f"\nTarget: numba at least {REFERENCE_TARGET:.0%} of C's speed: "
        f"{verdict}.\n"
    )


def _efficiency(results) -> str:
    e = results["efficiency"]
    rows = [
        {
            "observable": row["observable"],
            "r": f"{row['r']:g}",
            "paper": f"{row['paper']:.2e} +- {row['paper_err']:.0e}",
            "default": f"{row['default']:.2e} +- {row['default_err']:.0e}",
            "gain": f"{row['gain']:.1f} +- {row['gain_err']:.1f}",
            "target": (
                f">= {EFFICIENCY_TARGETS[row['observable']]:g}: "
                + _verdict(row["gain"], EFFICIENCY_TARGETS[row["observable"]], True)
                if row["observable"] in EFFICIENCY_TARGETS
                else ""
            ),
        }
        for row in e["rows"]
    ]
    criteria = e["criterion_c"]
    times = ", ".join(f"{t:.0e} at r = {r}" for r, t in e["shard_times"].items())
    return (
        "## Statistical efficiency\n\n(relative standard error)^2 x CPU seconds (lower is "
        "better) of the paper's estimator (c = "
        f"{criteria['paper']:g}, plain tallies) and the project's default (c = "
        f"{criteria['default']:g}, every control variate), and the gain paper / default; "
        "P(0,v), P(x), <v^2>_x and P(x,v): the median over the bins with "
        f"{e['speeds'][0]:g} <= v <= {e['speeds'][1]:g} (|v| for P(x,v)) and "
        f"{e['positions'][0]:g} <= x <= {e['positions'][1]:g}. {e['shards']} shards per r and "
        f"estimator, each of simulated time {times}; +- is the delete-one jackknife of the "
        "error (the error of the error).\n\n" + _table(rows)
    )


def _compile(results) -> str:
    c = results["compile"]
    later = WORKFLOW_TARGETS["compile_later_seconds"]
    rows = [
        {
            "": "first shard, empty numba cache (compile)",
            "value": f"{c['first_shard_compile_seconds']:.1f} s",
            "target": "",
        },
        {
            "": "later shard, new process (cache load)",
            "value": f"{c['later_shard_load_seconds']:.2f} s",
            "target": f"<= {later} s: {_verdict(c['later_shard_load_seconds'], later)}",
        },
        {"": "imports", "value": f"{c['import_seconds']:.1f} s", "target": ""},
        {
            "": f"peak memory of a shard (r = 1/2, {c['memory_shard_time']:.0e} time units)",
            "value": f"{c['peak_memory_mib']:.0f} MiB",
            "target": "",
        },
        {
            "": "memory before the shard",
            "value": f"{c['memory_before_shard_mib']:.0f} MiB",
            "target": "",
        },
    ]
    return "## numba's compile and a shard's memory\n\n" + _table(rows)


def _solver(results) -> str:
    s = results["solver"]
    rows = [
        {
            "r": f"{row['r']:.4g}",
            "nodes": str(row["nodes"]),
            "solve ms": f"{row['solve_ms']:.1f}",
            "solve and 401 outputs ms": f"{row['solve_and_401_outputs_ms']:.1f}",
            "energy balance residual": f"{row['energy_balance_residual']:.1e}",
            "error vs exact": f"{row['error_vs_exact']:.1e}" if "error_vs_exact" in row else "",
        }
        for row in s["rows"]
    ]
    verdict = "met" if s["target_met"] else "MISSED"
    return (
        "## Solver of eq. (inteq)\n\nMedian of repeats after a warm-up.\n\n"
        + _table(rows)
        + f"\nTarget: <= {SOLVER_TARGET_MS:.0f} ms per r at <= {s['accuracy_target']:.0e}: "
        f"{verdict} (worst {s['worst_solve_ms']:.1f} ms, worst error "
        f"{s['worst_error_vs_exact']:.1e}).\n"
    )


def _distribution(results) -> str:
    rows = [
        {
            "r": f"{row['r']:g}",
            "w(F) build s": f"{row['weight_function_seconds']:.1f}",
            "P(x), w tables s": f"{row['position_and_weight_tables_seconds']:.2f}",
            "P(x,v) table s": f"{row['distribution_table_seconds']:.1f}",
            "flight tables s": f"{row['collision_tables_seconds']:.2f}",
            "total s": f"{row['total_seconds']:.1f}",
        }
        for row in results["distribution"]["rows"]
    ]
    return (
        "## The whole distribution and the collision statistics\n\nPer r, what rule solve "
        "computes besides P(0, v), on the default grids.\n\n" + _table(rows)
    )


def _first_curve(results) -> str:
    f = results["first_curve"]
    rows = [
        {
            "r": f"{row['r']:g}",
            "points": f"{row['points']}",
            "first, cold cache CPU s": f"{row['first_cold_seconds']:.2f}",
            "first, warm cache CPU s": f"{row['first_warm_seconds']:.2f}",
            "second CPU s": f"{row['second_seconds']:.3f}",
            "target": f"<= {FIRST_CURVE_TARGET_SECONDS:g} s: "
            + _verdict(row["first_warm_seconds"], FIRST_CURVE_TARGET_SECONDS),
        }
        for row in f["rows"]
    ]
    return (
        "## The first P(x) curve at a new r\n\nAfter the solve, CPU seconds on one core, each r in a fresh process: "
        "w(F) is built and P(x) evaluated (numba's on-disk cache empty, then warm).\n\n"
        + _table(rows)
    )


def _workflow(results) -> str:
    w = results["workflow"]
    if "skipped" in w:
        return f"## Workflow overhead\n\nNot measured: {w['skipped']}.\n"
    dry, noop = WORKFLOW_TARGETS["grid_dry_run_seconds"], WORKFLOW_TARGETS["noop_seconds"]
    rows = [
        {
            "": f"dry run of 20 r x 16 shards ({w['grid_shard_jobs']} shard jobs)",
            "seconds": f"{w['grid_dry_run_seconds']:.1f}",
            "target": f"< {dry:.0f} s: {_verdict(w['grid_dry_run_seconds'], dry)}",
        },
        {
            "": "no-op rerun of the default workflow",
            "seconds": "" if w["noop_seconds"] is None else f"{w['noop_seconds']:.1f}",
            "target": (
                "not measured: its results are not complete"
                if w["noop_seconds"] is None
                else f"< {noop:.0f} s: {_verdict(w['noop_seconds'], noop)}"
            ),
        },
        {
            "": "dry run of the default workflow",
            "seconds": f"{w['default_dry_run_seconds']:.1f}",
            "target": "",
        },
    ]
    text = "## Workflow overhead\n\n" + _table(rows)
    if "scaling" in results:
        s = results["scaling"]
        speedup = WORKFLOW_TARGETS["cores_speedup"]
        text += "\n" + _table(
            [
                {
                    f"simulation stage, {s['shards']} shards of {s['shard_time']:.0e}": "",
                    "--cores 1 s": f"{s['cores_1_seconds']:.1f}",
                    "--cores 2 s": f"{s['cores_2_seconds']:.1f}",
                    "speed-up": f"{s['speedup']:.2f}",
                    "target": f">= {speedup}: {_verdict(s['speedup'], speedup, True)}",
                }
            ]
        )
    return text


SECTIONS = (
    _simulation,
    _breakdown,
    _reference,
    _efficiency,
    _compile,
    _solver,
    _distribution,
    _first_curve,
    _workflow,
)


def markdown_report(results: dict) -> str:
    """One run of the benchmark (the dict of ``benchmark.main``) as a Markdown page: the
    machine and the time of the run, then a table per measurement."""
    # each section reads the results of its name (``--efficiency-only`` has one)
    sections = (
        section(results) for section in SECTIONS if section.__name__.removeprefix("_") in results
    )
    return "\n".join([_header(results), *sections])
