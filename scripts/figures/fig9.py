"""Rule fig9 (past the paper): P(x) for every r of restitution: the solver through w(F), the
simulation and the exact eq. (P(x)2) at r = 1/2, 1/3."""

from bouncing_ball import plotting
from bouncing_ball.io import (
    EXACT_POSITION,
    SIMULATED_POSITION,
    SOLVER_POSITION,
    read_table,
    read_tables_of_one_restitution,
)
from bouncing_ball.jobs import job_log
from bouncing_ball.restitution import parse_restitution

with job_log(snakemake.log[0]):
    exact = {}
    for path in snakemake.input.exact:
        table, provenance = read_table(path, EXACT_POSITION)
        exact[provenance["r"]] = table
    panels = []
    for paths in zip(snakemake.input.solver, snakemake.input.simulation, strict=True):
        (solved, provenance), (simulated, _) = read_tables_of_one_restitution(
            *paths, kinds=(SOLVER_POSITION, SIMULATED_POSITION)
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
        plotting.position_density_figure(panels),
        *snakemake.output,
        snakemake.params.dpi,
        {"figure": snakemake.rule, "inputs": list(snakemake.input)},
    )
