"""Rule solve: eq. (inteq) solved for P(0, v) at one r, with <x>, Delta x, I and accuracy
checks -> results/solver/r{r}/p0v.parquet (v, p0v) and summary.parquet (one row)."""

import logging
import time

import pandas as pd

from bouncing_ball import solver
from bouncing_ball.bins import log_grid
from bouncing_ball.io import write_tables
from bouncing_ball.jobs import job_log
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label

with job_log(snakemake.log[0]):
    settings = snakemake.params.settings
    exact = parse_restitution(snakemake.params.restitution)
    label = restitution_label(exact)
    started = time.perf_counter()
    solution = solver.solve_outgoing_speed_density(float(exact), step=settings["quadrature_step"])
    elapsed = time.perf_counter() - started
    speeds = log_grid(settings["output_speeds"])
    row = solver.solution_summary(solution)
    provenance = {
        "rule": "solve",
        "r": exact_string(exact),
        "r_label": label,
        "quadrature_step": settings["quadrature_step"],
        "code": snakemake.params.code,
        "normalisation": "momentum balance M_2 = r / (1 + r)",
    }
    p0v = pd.DataFrame({"v": speeds, "p0v": solution.outgoing_speed_density(speeds)})
    write_tables(
        {snakemake.output.p0v: p0v, snakemake.output.summary: pd.DataFrame([row])}, provenance
    )
    logging.info(
        "r=%s: %d nodes, solved in %.1f ms (first call: includes loading the compiled kernel); "
        "<x> = %.10g, Delta x = %.10g, I = %.10g; energy balance residual %.1e, "
        "eigenvalue - 1 = %.1e, accuracy estimate %.1e",
        label,
        row["grid_size"],
        1e3 * elapsed,
        row["mean_x"],
        row["delta_x"],
        row["collision_rate"],
        row["energy_balance_residual"],
        row["eigenvalue_residual"],
        row["accuracy_estimate"],
    )
    if not row["accuracy_estimate"] <= solver.ACCURACY_TARGET:
        logging.warning(
            "r=%s: accuracy estimate %.1e misses the %.0e target",
            label,
            row["accuracy_estimate"],
            solver.ACCURACY_TARGET,
        )
