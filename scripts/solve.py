"""Rule solve: the equilibrium at one r from eq. (inteq), bouncing_ball.Equilibrium with the
config's solver settings, its tables checked and written -> results/solver/r{r}/: p0v (v, p0v),
summary (one row: <x>, Delta x, I, the collision statistics, the accuracy checks), flight_time
(the flight-time density on solver.flight_times), return_speed (on the simulation's speed
bins), position (P(x), <v^2>_x, eqs. (P(x)1), (moment2)), distribution (P(x, v), eq. (fpsol))
and weight (w(F), eq. (weightfunc))."""

import logging
import time

import pandas as pd

from bouncing_ball import solver
from bouncing_ball.bins import linear_grid, log_bins, log_grid
from bouncing_ball.equilibrium import Equilibrium
from bouncing_ball.restitution import exact_string, parse_restitution
from bouncing_ball.scales import outside_summary
from bouncing_ball.workflow import solver_tables
from bouncing_ball.workflow.io import write_tables
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    settings = snakemake.params.settings
    exact = parse_restitution(snakemake.params.restitution)
    started = time.perf_counter()
    # eq. (inteq), solved once with the config's quadrature step, its time averages, and its
    # accuracy estimate (a second, finer solve)
    equilibrium = Equilibrium(
        exact,
        quadrature_step=settings["quadrature_step"],
        weight_panel_nodes=settings["weight_panel_nodes"],
    )
    accuracy = equilibrium.accuracy
    elapsed = time.perf_counter() - started
    label = solver_tables.label(equilibrium)
    tables = {
        "p0v": solver_tables.p0v_table(equilibrium, log_grid(settings["output_speeds"])),
        "flight_time": solver_tables.flight_time_table(
            equilibrium, log_grid(settings["flight_times"])
        ),
        "return_speed": solver_tables.return_speed_table(
            equilibrium, log_bins(snakemake.params.speed_bins)
        ),
    }
    # the whole distribution from the same P(0, v): w(F), then P(x), P(x, v)
    started_distribution = time.perf_counter()
    tables["position"] = solver_tables.position_table(
        equilibrium, log_grid(settings["position_grid"])
    )
    tables["distribution"], worst = solver_tables.distribution_table(
        equilibrium, settings["positions"], linear_grid(settings["speeds"])
    )
    tables["weight"] = solver_tables.weight_table(equilibrium, log_grid(settings["forces"]))
    row = solver_tables.summary(equilibrium)
    logging.info(
        "r=%s: %d nodes, solved with its time averages and accuracy estimate in %.1f ms (first "
        "call: includes loading the compiled kernel); <x> = %.10g, Delta x = %.10g, I = %.10g; "
        "energy balance residual %.1e, eigenvalue - 1 = %.1e, accuracy estimate %.1e",
        label,
        row["grid_size"],
        1e3 * elapsed,
        row["mean_x"],
        row["delta_x"],
        row["collision_rate"],
        row["energy_balance_residual"],
        row["eigenvalue_residual"],
        accuracy,
    )
    logging.info(
        "r=%s: bounce chain: relaxation eigenvalue %.10g (error estimate %.1e, continuum edge "
        "%.6g), %.6g bounces, relaxation time %.6g (NaN below r_c)",
        label,
        row["relaxation_eigenvalue"],
        row["relaxation_eigenvalue_accuracy"],
        row["continuum_edge"],
        row["correlation_bounces"],
        row["relaxation_time"],
    )
    if not accuracy <= solver.ACCURACY_TARGET:
        logging.warning(
            "r=%s: accuracy estimate %.1e misses the %.0e target (solver.quadrature_step %g)",
            label,
            accuracy,
            solver.ACCURACY_TARGET,
            settings["quadrature_step"],
        )
    logging.info(
        "r=%s: w(F), P(x), P(x, v) in %.1f s; from P(x): int P dx - 1 = %.1e, <x> = %.10g, "
        "Delta x = %.10g (Ito: %.10g, %.10g); w(F) interpolation error estimate %.1e; "
        "P(x, v) quadrature error estimate %.1e of the peak at its x; "
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
    solver_tables.check(equilibrium, tables, row)
    provenance = {
        "rule": "solve",
        "r": exact_string(exact),
        "r_label": label,
        "quadrature_step": settings["quadrature_step"],
        "highest_speed": float(equilibrium.solution.speeds[-1]),
        "weight_panel_nodes": settings["weight_panel_nodes"],
        "settings": settings,
        "speed_bins": snakemake.params.speed_bins,
        "code": snakemake.params.code,
        "normalisation": "momentum balance M_2 = r / (1 + r)",
        # how much of each distribution lies beyond its table's range
        "outside": solver_tables.outside_fractions(tables),
    }
    logging.info("r=%s: %s", label, outside_summary(provenance["outside"]))
    write_tables(
        {
            snakemake.output.summary: pd.DataFrame([row]),
            **{getattr(snakemake.output, name): table for name, table in tables.items()},
        },
        provenance,
    )
