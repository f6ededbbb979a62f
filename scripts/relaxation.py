"""Rule relaxation: the relaxation eigenvalue lambda of the bounce chain and its correlation
length n_c = -1 / ln lambda (``relaxation.bounce_chain_relaxation``), that length in time
n_c <T> (``Equilibrium.bounce_chain_time``) at r = 1 - eps on the log grid of eps
figures.fig12_inelasticity, and the slowest time of the process 1 / gamma
(``time_relaxation.time_relaxation``, ``Equilibrium.relaxation_time``) on the grid
figures.fig12_time_inelasticity (NaN at the other points: each is an eigenvalue search), both at
each simulated r -> results/theory/relaxation.parquet
(r, relaxation_eigenvalue, correlation_bounces, isolated, bounce_chain_time, relaxation_time,
relaxation_time_isolated, simulated)."""

import logging

import pandas as pd

from bouncing_ball.bins import log_grid
from bouncing_ball.equilibrium import Equilibrium
from bouncing_ball.relaxation import bounce_chain_relaxation
from bouncing_ball.workflow.io import write_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    chain = {1.0 - float(eps) for eps in log_grid(snakemake.params.inelasticity)}
    times = {1.0 - float(eps) for eps in log_grid(snakemake.params.time_inelasticity)}
    grid = [(r, False) for r in sorted(chain | times)]
    rows = []
    for r, simulated in [*grid, *((value, True) for value in snakemake.params.simulated)]:
        relaxation = bounce_chain_relaxation(r)
        equilibrium = Equilibrium(r)
        timed = simulated or r in times
        rows.append(
            {
                "r": relaxation.restitution,
                "relaxation_eigenvalue": relaxation.eigenvalue,
                "correlation_bounces": relaxation.correlation_bounces,
                "isolated": relaxation.isolated,
                "bounce_chain_time": equilibrium.bounce_chain_time,
                "relaxation_time": equilibrium.relaxation_time if timed else float("nan"),
                "relaxation_time_isolated": (
                    equilibrium._time_relaxation.isolated if timed else False
                ),
                "simulated": simulated,
            }
        )
    table = pd.DataFrame(rows)
    provenance = {
        "rule": "relaxation",
        "inelasticity_grid": snakemake.params.inelasticity,
        "time_inelasticity_grid": snakemake.params.time_inelasticity,
        "simulated": list(snakemake.params.simulated),
        "code": snakemake.params.code,
    }
    write_table(table, snakemake.output[0], provenance)
    logging.info(
        "lambda_2 and 1 / gamma at %d values of r in [%g, %g]",
        len(table),
        table.r.min(),
        table.r.max(),
    )
