"""Rule fig8 (past the paper): the paper's Fig. 3 for any r: P(x, v) against v at
solver.positions from the solver, with the simulation's cells and the exact curve at r = 1/2,
1/3, one panel per r of figures.fig8."""

from bouncing_ball import plotting
from bouncing_ball.io import (
    EXACT_DISTRIBUTION,
    SIMULATED_DISTRIBUTION,
    SOLVER_DISTRIBUTION,
    read_table,
    read_tables_of_one_restitution,
)
from bouncing_ball.jobs import job_log
from bouncing_ball.restitution import parse_restitution

with job_log(snakemake.log[0]):
    exact = {}
    for path in snakemake.input.exact:
        table, provenance = read_table(path, EXACT_DISTRIBUTION)
        exact[provenance["r"]] = table
    panels = []
    for paths in zip(snakemake.input.solver, snakemake.input.simulation, strict=True):
        (solved, provenance), (simulated, _) = read_tables_of_one_restitution(
            *paths, kinds=(SOLVER_DISTRIBUTION, SIMULATED_DISTRIBUTION)
        )
        panels.append(
            {
                "restitution": parse_restitution(provenance["r"]),
                "solver": solved,
                "simulated": simulated,
                "exact": exact.get(provenance["r"]),
            }
        )
    plotting.save_figure(
        plotting.joint_distribution_figure(panels),
        *snakemake.output,
        snakemake.params.dpi,
        {"figure": snakemake.rule, "inputs": list(snakemake.input)},
    )
