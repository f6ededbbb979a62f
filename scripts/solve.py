"""Solve eq. (inteq) for P(0, v) at one r, with <x>, Delta x, I and accuracy checks.

Writes results/solver/r{r}/p0v.parquet (v, p0v) and summary.parquet (one row).
Run by Snakemake (rule solve), or by hand with the settings of a config file:
    python scripts/solve.py --restitution 0.6 --p0v p0v.parquet --summary summary.parquet \
        [--config config/config.yaml] [--step 0.2]
"""

import argparse
import logging
import time

import numpy as np
import pandas as pd

from bouncing_ball import solver, source_digest
from bouncing_ball.bins import log_grid
from bouncing_ball.config import read_config, solver_settings
from bouncing_ball.io import write_table
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label

# where the accuracy target (1e-8 relative) is stated, independent of the output grid
CHECKED_SPEEDS = np.geomspace(1e-3, 20.0, 400)


def accuracy_estimate(solution):
    """Largest relative change of P(0, v) over v in [1e-3, 20] against a finer solve
    (step x 0.8, lowest node x 1e-4, highest node x 1.2 where P stays a normal double)."""
    r = solution.restitution
    cap = 0.99 * solver.UNDERFLOW_EFOLDS / solver.large_speed_decay_rate(r)
    finer = solver.solve_outgoing_speed_density(
        r,
        step=0.8 * solution.step,
        lowest_speed=1e-4 * solution.speeds[0],
        highest_speed=min(1.2 * solution.speeds[-1], cap),
    )
    reference = finer.outgoing_speed_density(CHECKED_SPEEDS)
    usable = reference > 0.0  # below r ~ 0.015, P(0, 20) underflows
    return float(
        np.max(
            np.abs(
                solution.outgoing_speed_density(CHECKED_SPEEDS[usable]) / reference[usable] - 1.0
            )
        )
    )


def main(restitution, settings, p0v_path, summary_path):
    """Solve at r = ``restitution`` with ``settings`` = config.solver_settings(config) and write both tables."""
    step = settings["quadrature_step"]
    exact = parse_restitution(restitution)
    label = restitution_label(exact)
    started = time.perf_counter()
    solution = solver.solve_outgoing_speed_density(float(exact), step=step)
    elapsed = time.perf_counter() - started
    speeds = log_grid(settings["output_speeds"])
    density = solution.outgoing_speed_density(speeds)
    averages = solver.time_averages(solution)
    summary = pd.DataFrame(
        [
            {
                "r": float(exact),
                "small_speed_exponent": solution.small_speed_exponent,
                **averages,
                "momentum_balance_residual": solver.momentum_balance_residual(solution),
                "energy_balance_residual": solver.energy_balance_residual(solution),
                "eigenvalue_residual": solution.eigenvalue - 1.0,
                "grid_size": len(solution.speeds),
                "lowest_speed": solution.speeds[0],
                "highest_speed": solution.speeds[-1],
                "accuracy_estimate": accuracy_estimate(solution),
            }
        ]
    )
    provenance = {
        "rule": "solve",
        "r": exact_string(exact),
        "r_label": label,
        "quadrature_step": step,
        "code": source_digest(solver.SOURCES),
        "normalisation": "momentum balance M_2 = r / (1 + r)",
    }
    write_table(pd.DataFrame({"v": speeds, "p0v": density}), p0v_path, provenance)
    write_table(summary, summary_path, provenance)
    row = summary.iloc[0]
    logging.info(
        "r=%s: %d nodes, solved in %.1f ms (first call: includes loading the compiled kernel); <x> = %.10g, Delta x = %.10g, I = %.10g; "
        "energy balance residual %.1e, eigenvalue - 1 = %.1e, accuracy estimate %.1e",
        label,
        row.grid_size,
        1e3 * elapsed,
        row.mean_x,
        row.delta_x,
        row.collision_rate,
        row.energy_balance_residual,
        row.eigenvalue_residual,
        row.accuracy_estimate,
    )
    if not row.accuracy_estimate <= 1e-8:
        logging.warning(
            "r=%s: accuracy estimate %.1e misses the 1e-8 target", label, row.accuracy_estimate
        )


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--restitution", required=True)
    parser.add_argument("--p0v", required=True)
    parser.add_argument("--summary", required=True)
    parser.add_argument("--config", default="config/config.yaml", help="solver settings from here")
    parser.add_argument("--step", type=float, help="override the config's solver.quadrature_step")
    args = parser.parse_args()
    config = read_config(args.config)
    settings = solver_settings(config)
    if args.step is not None:
        settings["quadrature_step"] = args.step
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.restitution, settings, args.p0v, args.summary)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        snakemake.params.restitution,  # noqa: F821
        snakemake.params.settings,  # noqa: F821
        snakemake.output.p0v,  # noqa: F821
        snakemake.output.summary,  # noqa: F821
    )
elif __name__ == "__main__":
    _command_line()
