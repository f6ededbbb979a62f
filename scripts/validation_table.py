"""Rule validation_table: the run held against the exact solutions, the solver and the theory
for every simulated r: P(0, v) against eq. (P(0,v)) (r = 1/2, 1/3) or the solver's curve,
P(x) and <v^2>_x against eqs. (P(x)2), (moment2) (r = 1/2, 1/3), and the free-exponent fits
of the asymptotic forms -> results/tables/validation.csv (one row per r and check) and
validation.md.  The shards' batch files give the chi^2/n rows their sign-flip p-values."""

import logging
from pathlib import Path

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.validation import (
    shard_ratios,
    validation_markdown,
    validation_rows,
    validation_table,
)
from bouncing_ball.workflow.io import (
    FITS,
    SIMULATED_P0V,
    SIMULATED_POSITION,
    SOLVER_P0V,
    read_tables_of_one_restitution,
    write_csv_and_markdown,
)
from bouncing_ball.workflow.jobs import job_log
from bouncing_ball.workflow.shards import read_shards

with job_log(snakemake.log[0], exit_when_done=True):
    rows = []
    inputs = zip(
        snakemake.input.p0v,
        snakemake.input.position,
        snakemake.input.solver,
        snakemake.input.fits,
        strict=True,
    )
    for paths in inputs:
        (p0v, provenance), (position, _), (curve, solved), (fits, fit_provenance) = (
            read_tables_of_one_restitution(
                *paths, kinds=(SIMULATED_P0V, SIMULATED_POSITION, SOLVER_P0V, FITS)
            )
        )
        label = provenance["r_label"]
        # the batch files of r (results/simulation/r{label}/shards*.parquet)
        batches = [path for path in snakemake.input.shards if Path(path).parent.name == f"r{label}"]
        shards, _ = read_shards(batches, label)
        if len(shards) != int(provenance["shards"]):
            raise ValueError(
                f"{paths[0]}: merged from {provenance['shards']} shards, but the batch files of "
                f"r = {label} hold {len(shards)}; rerun merge_shards"
            )
        rows += validation_rows(
            label,
            parse_restitution(provenance["r"]),
            p0v,
            position,
            fits,
            len(shards),
            solver_curve=curve,
            per_shard=shard_ratios(shards),
            # the rule the fit's auto windows were chosen by
            max_bias=float(fit_provenance["settings"]["max_bias"]),
            # how much of each distribution the tables leave out (rules merge_shards, solve)
            outside=(provenance.get("outside"), solved.get("outside")),
        )
    table = validation_table(rows)
    write_csv_and_markdown(
        table, snakemake.output.csv, snakemake.output.md, validation_markdown(table)
    )
    for row in table.itertuples():
        logging.info(
            "r=%s %s (vs %s, %d bins): %.4g (p_sign_flip %.3g) at %.3g",
            row.r_label,
            row.check,
            row.reference,
            row.bins,
            row.value,
            row.p_sign_flip,
            row.bin_centre,
        )
