"""Rule theory: beta(r), m(r), q(r) of eqs. (asym2)-(asym6) on the config's r grid
-> results/theory/exponents.parquet (r, beta, m, q)."""

import logging

from bouncing_ball.asymptotics import CRITICAL_RESTITUTION, exponents_table
from bouncing_ball.bins import linear_grid
from bouncing_ball.workflow.io import write_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    grid = snakemake.params.grid
    table = exponents_table(linear_grid(grid))
    provenance = {
        "rule": "theory",
        "restitution_grid": grid,
        "critical_restitution": CRITICAL_RESTITUTION,
        "code": snakemake.params.code,
    }
    write_table(table, snakemake.output[0], provenance)
    logging.info(
        "beta, m, q at %d values of r in [%g, %g]; r_c = %.12g",
        len(table),
        table.r.min(),
        table.r.max(),
        CRITICAL_RESTITUTION,
    )
