"""Rule solve: eq. (inteq) solved for P(0, v) at one r, with <x>, Delta x, I, accuracy checks,
the collision statistics and the whole distribution -> results/solver/r{r}/: p0v (v, p0v),
summary (one row), flight_time (the equilibrium flight-time density on solver.flight_times),
position (P(x), <v^2>_x, eqs. (P(x)1), (moment2)), distribution (P(x, v), eq. (fpsol)) and
weight (w(F), eq. (weightfunc))."""

import logging
import time

import pandas as pd

from bouncing_ball import distribution, flight_time, solver
from bouncing_ball.bins import linear_grid, log_bins, log_grid
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.workflow.io import write_tables
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0]):
    settings = snakemake.params.settings
    exact = parse_restitution(snakemake.params.restitution)
    label = restitution_label(exact)
    started = time.perf_counter()
    # eq. (inteq), solved once: the highest node where P(0, v) reaches e^-690, as w(F) at small
    # F needs (distribution.outgoing_speed_solution), with the config's quadrature step
    solution = distribution.outgoing_speed_solution(exact, step=settings["quadrature_step"])
    elapsed = time.perf_counter() - started
    speeds = log_grid(settings["output_speeds"])
    row = solver.solution_summary(solution)
    # the collision statistics: McKean's first-passage law with gravity (bouncing_ball.flight_time)
    collisions = flight_time.flight_time_summary(solution)
    row.update({key: value for key, value in collisions.items() if key not in row})
    flights = flight_time.flight_time_table(solution, log_grid(settings["flight_times"]))
    returns = flight_time.return_speed_table(solution, log_bins(snakemake.params.speed_bins))
    # the whole distribution from P(0, v) (bouncing_ball.distribution): w(F), then P(x), P(x, v)
    started_distribution = time.perf_counter()
    weight = distribution.interpolated_weight_function(
        solution, panel_nodes=settings["weight_panel_nodes"]
    )
    position = distribution.position_table(weight, log_grid(settings["position_grid"]))
    joint, worst = distribution.distribution_table(
        weight, solution, settings["positions"], linear_grid(settings["speeds"])
    )
    weights = distribution.weight_table(weight, log_grid(settings["forces"]))
    averages = distribution.position_averages(weight)
    row["position_normalization"] = averages["normalization"]
    row["mean_x_from_position"] = averages["mean_x"]
    row["delta_x_from_position"] = averages["delta_x"]
    row["weight_interpolation_error"] = weight.interpolation_error
    measured = distribution.measured_exponents(weight)
    for key, value in distribution.predicted_exponents(exact).items():
        row[f"{key}_measured"], row[f"{key}_predicted"] = measured[key], value
    row["large_x_window_lo"], row["large_x_window_hi"] = measured["large_x_window"]
    p0v = pd.DataFrame({"v": speeds, "p0v": solution.outgoing_speed_density(speeds)})
    tables = {
        "p0v": p0v,
        "flight_time": flights,
        "return_speed": returns,
        "position": position,
        "distribution": joint,
        "weight": weights,
    }
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
            "r=%s: accuracy estimate %.1e misses the %.0e target (solver.quadrature_step %g)",
            label,
            row["accuracy_estimate"],
            solver.ACCURACY_TARGET,
            settings["quadrature_step"],
        )
    logging.info(
        "r=%s: w(F), P(x), P(x, v) in %.1f s; from P(x): int P dx - 1 = %.1e, <x> = %.10g, "
        "Delta x = %.10g (Ito: %.10g, %.10g); w(F) interpolation error estimate %.1e; "
        "P(x, v) quadrature error estimate %.1e; "
        "large-x decay rate %.6g (predicted %.6g), power %.4g (predicted %.4g)",
        label,
        time.perf_counter() - started_distribution,
        row["position_normalization"] - 1.0,
        row["mean_x_from_position"],
        row["delta_x_from_position"],
        row["mean_x"],
        row["delta_x"],
        row["weight_interpolation_error"],
        worst,
        row["large_x_rate_measured"],
        row["large_x_rate_predicted"],
        row["large_x_power_measured"],
        row["large_x_power_predicted"],
    )
    # nothing is written unless every table passes (an error naming r and the failed checks)
    distribution.check_solve_tables(label, row, tables, solver.ACCURACY_TARGET)
    provenance = {
        "rule": "solve",
        "r": exact_string(exact),
        "r_label": label,
        "quadrature_step": settings["quadrature_step"],
        "highest_speed": float(solution.speeds[-1]),
        "weight_panel_nodes": settings["weight_panel_nodes"],
        "settings": settings,
        "speed_bins": snakemake.params.speed_bins,
        "code": snakemake.params.code,
        "normalisation": "momentum balance M_2 = r / (1 + r)",
    }
    write_tables(
        {
            snakemake.output.summary: pd.DataFrame([row]),
            **{getattr(snakemake.output, name): table for name, table in tables.items()},
        },
        provenance,
    )
