"""Rule quasi_elastic: the solver's P(0, v) in the quasi-elastic scaling, epsilon^-3 P(0, w /
epsilon) with epsilon = 1 - r, at every r of figures.fig13 on the scaled speeds
figures.fig13_scaled_speeds, beside the limit and its first correction
(``quasi_elastic.scaled_speed_curves``) -> results/theory/quasi_elastic.parquet (Fig. 13); and
the scaled I, <x>, Delta x and P(0, v) against their limits (``quasi_elastic.quasi_elastic_table``)
-> results/tables/quasi_elastic.csv and .md."""

import logging

from bouncing_ball.bins import log_grid
from bouncing_ball.quasi_elastic import quasi_elastic_table, scaled_speed_curves
from bouncing_ball.restitution import exact_string, parse_restitution
from bouncing_ball.workflow.io import write_csv_and_markdown, write_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    restitutions = [
        parse_restitution(value, "figures.fig13") for value in snakemake.params.restitution
    ]
    curves = scaled_speed_curves(
        restitutions,
        log_grid(snakemake.params.scaled_speeds),
        snakemake.params.quadrature_step,
    )
    provenance = {
        "rule": "quasi_elastic",
        "r": [exact_string(value) for value in restitutions],
        "scaled_speeds": snakemake.params.scaled_speeds,
        "quadrature_step": snakemake.params.quadrature_step,
        "code": snakemake.params.code,
    }
    write_table(curves, snakemake.output.curves, provenance)
    table = quasi_elastic_table(restitutions)
    write_csv_and_markdown(
        table,
        snakemake.output.csv,
        snakemake.output.md,
        "# The quasi-elastic limit r -> 1\n\n"
        "Each scaled solver quantity against its limit, the first coefficient c1 = "
        "(scaled / limit - 1) / (1 - r) measured and predicted, and the predicted c2 "
        "(docs/quasi_elastic.md; rule quasi_elastic).\n\n"
        + table.to_markdown(index=False, floatfmt=".6g")
        + "\n",
    )
    logging.info(
        "quasi-elastic scaling at r = %s: largest |c1 measured - c1 predicted| of P(0,v) %.3g",
        ", ".join(provenance["r"]),
        float((curves.c1_measured - curves.c1_predicted).abs().max()),
    )
