"""Rule fig10 (past the paper): the distribution of the time between bounces from McKean's
law and the solver, with the simulation's flights and the short- and long-time forms, one
panel per r of figures.fig10."""

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import (
    SIMULATED_FLIGHT_TIME,
    SOLVER_FLIGHT_TIME,
    SOLVER_SUMMARY,
    read_tables_of_one_restitution,
)
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    panels = []
    inputs = snakemake.input
    for paths in zip(inputs.solver, inputs.summary, inputs.simulation, strict=True):
        (solved, provenance), (summary, _), (simulated, _) = read_tables_of_one_restitution(
            *paths, kinds=(SOLVER_FLIGHT_TIME, SOLVER_SUMMARY, SIMULATED_FLIGHT_TIME)
        )
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "solver": solved,
                "collision_rate": float(summary.collision_rate.iloc[0]),
                "long_time_decay_rate": float(summary.long_time_decay_rate.iloc[0]),
                "simulated": simulated,
            }
        )
    plotting.save_figure(
        plotting.flight_time_figure(panels),
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
