"""Rule fig8 (past the paper): the paper's Fig. 3 for any r: P(x, v) against v at
solver.positions from the solver, with the simulation's cells and the exact curve at r = 1/2,
1/3, one panel per r of figures.fig8."""

from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import (
    EXACT_DISTRIBUTION,
    SIMULATED_DISTRIBUTION,
    SOLVER_DISTRIBUTION,
    comparison_panels,
)
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    inputs = snakemake.input
    panels = comparison_panels(
        inputs.solver,
        inputs.simulation,
        inputs.exact,
        (SOLVER_DISTRIBUTION, SIMULATED_DISTRIBUTION, EXACT_DISTRIBUTION),
    )
    plotting.save_figure(
        plotting.joint_distribution_figure(panels),
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
