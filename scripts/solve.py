"""Rule solve: eq. (inteq) solved for P(0, v) at one r, with <x>, Delta x, I, accuracy checks
and the collision statistics -> results/solver/r{r}/p0v.parquet (v, p0v), summary.parquet (one
row) and flight_time.parquet (the equilibrium flight-time density on solver.flight_times)."""

import logging
import time

import pandas as pd

from bouncing_ball import flight_time, solver
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
    # the collision statistics: McKean's first-passage law with gravity (bouncing_ball.flight_time)
    collisions = flight_time.flight_time_summary(solution)
    row.update({key: value for key, value in collisions.items() if key not in row})
    flights = flight_time.flight_time_table(solution, log_grid(settings["flight_times"]))
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
        {
            snakemake.output.p0v: p0v,
            snakemake.output.summary: pd.DataFrame([row]),
            snakemake.output.flight_time: flights,
        },
        provenance,
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
