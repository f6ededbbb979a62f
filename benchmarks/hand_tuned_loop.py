"""The hand-tuned C loop, the benchmark's speed anchor: build it, run it.

``reference/hand_tuned.c`` is "a hand-tuned C loop of the same physics": the paper's
Sec. IV (step D(x, v) + delta from eq. (criterion), the 1/500 rule for delta after each
collision, the exact free-flight update), collisions placed where the step bridge's mean
path first reaches 0, the in-step integrals of x and x^2 exact in expectation given each
step's ends, and a histogram of outgoing speeds (P(0, v)).  ``python -m benchmarks``
measures the shard loop's collisions per CPU second against it, in the same run
(``breakdown``).  It is outside the package, like ``reference_loop``: the workflow never
runs it.

How it differs from ``simulation.loop._run`` (and from its line-by-line translation
``reference/shard_loop.c``):
  * it tallies only collisions, time, steps, int x dt, int x^2 dt and the outgoing speeds:
    no P(x), <v^2>_x, P(x, v), flight-time or return-speed tallies;
  * its normals come from its own generator, xoshiro256+ with a 256-layer ziggurat,
    seeded by an integer (the project itself only ever draws from numpy's Generator), so its
    numbers are statistically, not bit for bit, those of the project's loop;
  * the step-size root starts from a first-order prediction off the previous step's root
    (Householder's third-order iteration, no cube root), where the project's loop starts
    cold, and a step that does not collide skips the bridge's cubic;
  * gcc -O3 -march=native with fused multiply-adds contracted wherever gcc likes (the
    reference switches contraction off and calls fma() where the numba loop does).

Its physics is checked by ``physics_check``: I, <x> and Delta x against the exact r = 1/2
values and the solver's at other r (z-scores from the scatter of independent seeds), and
the pooled P(0, v) histogram against the exact one (chi^2 over the bins); ``python -m
benchmarks.hand_tuned_loop --check`` prints them.  ``normals`` and ``criterion_root``
expose the generator and the root for their own checks.

``build`` compiles it into ``__pycache__/hand-tuned-<key>/`` keyed on the hash of the source
and the compiler command (``reference_loop.build_shared_library``); ``run`` runs one shard and returns
its tallies with the CPU time measured inside the C call.  ``python -m
benchmarks.hand_tuned_loop`` prints its throughput at r = 0.25, 0.5, 0.75 and c = 3, 5;
``--check`` adds the physics check (``--check-r``: its r, default 1/2).
"""

import argparse
import ctypes
import functools
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np

from bouncing_ball.settings import DEFAULT_SPEED_BINS

from .reference_loop import COMPILER, build_shared_library

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "reference" / "hand_tuned.c"
# fused multiply-adds allowed: -std=c99 alone would switch gcc's contraction off
FLAGS = (
    "-O3",
    "-march=native",
    "-ffp-contract=fast",
    "-fno-math-errno",
    "-std=c99",
    "-fPIC",
    "-shared",
)
SPEED_BINS = DEFAULT_SPEED_BINS  # outgoing speeds of P(0, v)
OUTPUTS = (
    "time",
    "collisions",
    "steps",
    "int_x",
    "int_x2",
    "root_iterations",
    "root_restarts",
    "cpu_seconds",
    "recorded_cpu_seconds",
    "exhausted",
    "equilibration_steps",
)


def compile_command(source: Path, output: Path) -> list[str]:
    """The gcc command that builds ``source`` into the shared library ``output``."""
    return [COMPILER, *FLAGS, str(source), "-lm", "-o", str(output)]


def build(directory=None) -> Path:
    """Compile the hand-tuned loop (if not cached yet) and return the shared library's path
    (``reference_loop.build_shared_library``; RuntimeError where gcc is missing or the
    compile fails)."""
    return build_shared_library(SOURCE, compile_command, "hand-tuned", directory)


_double_array = np.ctypeslib.ndpointer(dtype=np.float64, ndim=1, flags="C_CONTIGUOUS")
_int64_array = np.ctypeslib.ndpointer(dtype=np.int64, ndim=1, flags="C_CONTIGUOUS")


@functools.cache
def _library(path: str):
    library = ctypes.CDLL(path)
    library.hand_tuned_run.restype = ctypes.c_int
    library.hand_tuned_run.argtypes = [
        ctypes.c_double,  # r
        ctypes.c_double,  # c
        ctypes.c_double,  # min step divisor (500)
        ctypes.c_double,  # equilibration time
        ctypes.c_double,  # recorded time
        ctypes.c_int64,  # max steps
        ctypes.c_uint64,  # seed
        _double_array,  # speed edges
        ctypes.c_int64,  # number of speed bins
        _int64_array,  # speed counts
        _double_array,  # outputs
    ]
    library.hand_tuned_normals.restype = None
    library.hand_tuned_normals.argtypes = [ctypes.c_uint64, ctypes.c_int64, _double_array]
    library.hand_tuned_root.restype = ctypes.c_double
    library.hand_tuned_root.argtypes = [
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.POINTER(ctypes.c_int64),
    ]
    return library


def run(
    r,
    criterion_c,
    recorded_time,
    equilibration_time=100.0,
    seed=1,
    min_step_divisor=500.0,
    max_steps=10**13,
    library=None,
) -> dict:
    """One shard of the hand-tuned loop: its tallies and its speed.

    ``cpu_seconds`` is the CPU time of the whole C call (equilibration included, as the
    benchmark times a shard); rates are per recorded collision and step.  ``speed_counts``
    are the outgoing speeds on ``SPEED_BINS`` (first and last: under- and overflow).  Raises
    RuntimeError where the loop cannot be built (no gcc): a caller skips with its message.
    """
    if not 0.0 < r < 1.0:
        raise ValueError(f"restitution must lie in (0, 1), got {r}")
    function = _library(str(library if library is not None else build())).hand_tuned_run
    edges = np.ascontiguousarray(SPEED_BINS.edges, dtype=np.float64)
    speed_counts = np.zeros(SPEED_BINS.n + 2, dtype=np.int64)
    out = np.zeros(len(OUTPUTS))
    function(
        float(r),
        float(criterion_c),
        float(min_step_divisor),
        float(equilibration_time),
        float(recorded_time),
        int(max_steps),
        int(seed),
        edges,
        SPEED_BINS.n,
        speed_counts,
        out,
    )
    result = dict(zip(OUTPUTS, out.tolist()))
    for name in ("collisions", "steps", "root_iterations", "root_restarts", "equilibration_steps"):
        result[name] = int(result[name])
    result["exhausted"] = bool(result["exhausted"])
    seconds = result["cpu_seconds"]
    steps = max(result["steps"], 1)
    recorded = result["time"] or float("nan")  # 0 if the budget ran out while equilibrating
    result.update(
        r=r,
        criterion_c=criterion_c,
        seed=seed,
        collisions_per_cpu_second=result["collisions"] / seconds,
        ns_per_step=1e9 * seconds / steps,
        steps_per_collision=result["steps"] / max(result["collisions"], 1),
        root_iterations_per_step=result["root_iterations"] / steps,
        mean_x=result["int_x"] / recorded,
        mean_x2=result["int_x2"] / recorded,
        collision_rate=result["collisions"] / recorded,
        speed_counts=speed_counts,
    )
    return result


def normals(n, seed=1, library=None) -> np.ndarray:
    """``n`` standard normals of the loop's generator (xoshiro256+ and its ziggurat)."""
    out = np.empty(int(n))
    _library(str(library if library is not None else build())).hand_tuned_normals(
        int(seed), int(n), out
    )
    return out


def criterion_root(x, v, c, start=0.0, library=None) -> tuple[float, int]:
    """The loop's root s* of eq. (criterion) at (x, v) from ``start`` (<= 0: cold start),
    and the iterations it took."""
    iterations = ctypes.c_int64(0)
    root = _library(str(library if library is not None else build())).hand_tuned_root(
        float(x), float(v), float(c), float(start), ctypes.byref(iterations)
    )
    return root, iterations.value


# simulated time per shard, as the benchmark's throughput shards
THROUGHPUT_TIMES = {0.25: 6.0e5, 0.5: 2.0e6, 0.75: 6.0e6}


def throughput(repeats=3, times=None) -> list[dict]:
    """Best of ``repeats`` CPU times at r = 0.25, 0.5, 0.75 and c = 3, 5."""
    rows = []
    for r, recorded_time in (times or THROUGHPUT_TIMES).items():
        for criterion_c in (3.0, 5.0):
            best = min(
                (run(r, criterion_c, recorded_time) for _ in range(repeats)),
                key=lambda result: result["cpu_seconds"],
            )
            rows.append(best)
    return rows


def reference_values(r) -> dict:
    """<x>, Delta x and I: exact at r = 1/2 and 1/3, from the solver of eq. (inteq) otherwise."""
    from bouncing_ball import exact, solver

    fraction = Fraction(r).limit_denominator(1000)
    if fraction in exact.EXACT_RESTITUTIONS and abs(float(fraction) - r) < 1e-12:
        values = exact.position_moments(fraction)
        values["source"] = "exact"
    else:
        values = solver.time_averages(solver.solve_outgoing_speed_density(r))
        values["source"] = "solver"
    return values


def physics_check(r=0.5, criterion_c=5.0, runs=16, recorded_time=2.0e6) -> dict:
    """I, <x> and Delta x from ``runs`` independent seeds against ``reference_values``.

    The error is the scatter of the runs over sqrt(runs); z = (mean - reference) / error.  At
    r = 1/2 and 1/3 also chi^2 of the pooled outgoing-speed histogram against the exact
    P(0, v), over the finite bins that expect at least 20 collisions.
    """
    reference = reference_values(r)
    results = [run(r, criterion_c, recorded_time, seed=seed) for seed in range(1, runs + 1)]
    check = {"r": r, "criterion_c": criterion_c, "runs": runs, "recorded_time": recorded_time}
    check["reference"] = reference["source"]
    per_run = {
        "collision_rate": [result["collision_rate"] for result in results],
        "mean_x": [result["mean_x"] for result in results],
        "delta_x": [np.sqrt(result["mean_x2"] - result["mean_x"] ** 2) for result in results],
    }
    for name, values in per_run.items():
        values = np.array(values)
        mean = values.mean()
        error = values.std(ddof=1) / np.sqrt(runs)
        check[name] = {
            "simulation": float(mean),
            "error": float(error),
            "reference": float(reference[name]),
            "z": float((mean - reference[name]) / error),
        }
    if reference["source"] == "exact":
        from bouncing_ball.exact import outgoing_speed_bin_average

        counts = sum(result["speed_counts"] for result in results)[1:-1]
        lower, upper = SPEED_BINS.edges[:-1], SPEED_BINS.edges[1:]
        fraction = Fraction(r).limit_denominator(1000)
        flux = outgoing_speed_bin_average(lower, upper, fraction) * (upper**2 - lower**2) / 2.0
        expected = flux * runs * recorded_time
        kept = expected >= 20.0
        chi2 = float((((counts - expected) ** 2 / expected)[kept]).sum())
        check["speed_histogram"] = {"chi2": chi2, "bins": int(kept.sum())}
    return check


def _main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--check", action="store_true", help="also the physics check")
    parser.add_argument(
        "--check-r", type=float, nargs="+", default=[0.5], help="r of the physics check"
    )
    arguments = parser.parse_args(argv)
    try:
        build()
    except (RuntimeError, OSError) as error:
        print(f"skipped: {str(error).splitlines()[0]}")
        return 0
    print(f"hand-tuned C loop ({' '.join(FLAGS)}), best of {arguments.repeats} CPU times")
    print(
        f"{'r':>5} {'c':>3} {'collisions/CPU s':>17} {'ns/step':>8} {'steps/coll':>10} "
        f"{'iter/step':>9}"
    )
    for row in throughput(arguments.repeats):
        print(
            f"{row['r']:>5} {row['criterion_c']:>3.0f} {row['collisions_per_cpu_second']:>17.3e} "
            f"{row['ns_per_step']:>8.1f} {row['steps_per_collision']:>10.2f} "
            f"{row['root_iterations_per_step']:>9.3f}"
        )
    if arguments.check:
        print("physics: 16 seeds x 2e6 time units each; error = scatter / sqrt(16)")
        for r in arguments.check_r:
            for criterion_c in (3.0, 5.0):
                check = physics_check(r, criterion_c)
                for name in ("collision_rate", "mean_x", "delta_x"):
                    item = check[name]
                    print(
                        f"r = {r}, c = {criterion_c:.0f}, {name}: {item['simulation']:.6f} "
                        f"+- {item['error']:.6f} ({check['reference']} {item['reference']:.6f}, "
                        f"z = {item['z']:+.2f})"
                    )
                if "speed_histogram" in check:
                    histogram = check["speed_histogram"]
                    print(
                        f"r = {r}, c = {criterion_c:.0f}, P(0, v) histogram: "
                        f"chi^2 = {histogram['chi2']:.1f} on {histogram['bins']} bins"
                    )
    return 0


if __name__ == "__main__":
    sys.exit(_main())
