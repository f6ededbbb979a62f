"""Rule fig11 (past the paper): the return-speed law v G_g(v, u) of eq. (kernel3), averaged over
outgoing-speed bins, against the simulated (outgoing, return) pairs at the r of figures.fig11,
one panel per speed of figures.return_speeds."""

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import (
    SIMULATED_RETURN_SPEED,
    SOLVER_RETURN_SPEED,
    read_tables_of_one_restitution,
)
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    panels = []
    for paths in zip(snakemake.input.solver, snakemake.input.simulation, strict=True):
        (solved, provenance), (simulated, _) = read_tables_of_one_restitution(
            *paths, kinds=(SOLVER_RETURN_SPEED, SIMULATED_RETURN_SPEED)
        )
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "solver": solved,
                "simulated": simulated,
            }
        )
    plotting.save_figure(
        plotting.return_speed_figure(panels, snakemake.params.outgoing_speeds),
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
