"""Rule exact_solution: the exact solution at r = 1/2 or 1/3 -> results/exact/r{r}/: P(0, v)
(p0v), P(x, v) of Fig. 3 (distribution), P(x) and <v^2>_x (position), <x>, Delta x, I (summary)."""

import logging

import pandas as pd

from bouncing_ball import exact
from bouncing_ball.bins import linear_grid, log_grid
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.workflow.io import write_tables
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    settings, outputs = snakemake.params.settings, snakemake.output
    value = parse_restitution(snakemake.params.restitution)
    label = restitution_label(value)
    r = float(value)
    output_speeds = log_grid(settings["output_speeds"])
    heights = log_grid(settings["position_grid"])
    moments = exact.position_moments(r)
    provenance = {
        "rule": "exact_solution",
        "r": exact_string(value),
        "r_label": label,
        "settings": settings,
        "code": snakemake.params.code,
    }
    table, worst = exact.distribution_table(
        settings["positions"], linear_grid(settings["speeds"]), r
    )
    position = {
        "x": heights,
        "px": exact.position_density(heights, r),
        "v2_given_x": exact.mean_speed_squared_given_position(heights, r),
    }
    summary = {
        "r": r,
        "normalization_constant": exact.normalization_constant(r),
        "mean_x": moments["mean_x"],
        "delta_x": moments["delta_x"],
        "collision_rate": moments["collision_rate"],
    }
    p0v = {"v": output_speeds, "p0v": exact.outgoing_speed_density(output_speeds, r)}
    write_tables(
        {
            outputs.p0v: pd.DataFrame(p0v),
            outputs.position: pd.DataFrame(position),
            outputs.summary: pd.DataFrame([summary]),
            outputs.distribution: table,
        },
        provenance,
    )
    logging.info(
        "r=%s: P(x,v) at %d points, largest estimated relative error %.1e", label, len(table), worst
    )
    if worst > 1e-6:
        logging.warning("r=%s: P(x,v) is less accurate than 1e-6 somewhere (%.1e)", label, worst)
    logging.info(
        "r=%s: A = %.12g, <x> = %.12g, Delta x = %.12g, I = %.12g",
        label,
        exact.normalization_constant(r),
        moments["mean_x"],
        moments["delta_x"],
        moments["collision_rate"],
    )
