"""Rule fig9 (past the paper): P(x) for every r of restitution: the solver through w(F), the
simulation and the exact eq. (P(x)2) at r = 1/2, 1/3."""

from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import (
    EXACT_POSITION,
    SIMULATED_POSITION,
    SOLVER_POSITION,
    comparison_panels,
)
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    inputs = snakemake.input
    panels = comparison_panels(
        inputs.solver,
        inputs.simulation,
        inputs.exact,
        (SOLVER_POSITION, SIMULATED_POSITION, EXACT_POSITION),
    )
    plotting.save_figure(
        plotting.position_density_figure(panels),
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
