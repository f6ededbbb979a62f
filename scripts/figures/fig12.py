"""Rule fig12 (past the paper): the relaxation of the bounce chain, n_c = -1 / ln lambda_2 from
the solver's matrix over r (results/theory/relaxation.parquet) against the simulated decay
rates, and the simulated correlations over lags against lambda_2^k, at every simulated r."""

from bouncing_ball.restitution import parse_restitution
from bouncing_ball.workflow import plotting
from bouncing_ball.workflow.io import RELAXATION, SIMULATED_BOUNCE_CHAIN, read_table
from bouncing_ball.workflow.jobs import job_log

with job_log(snakemake.log[0], exit_when_done=True):
    theory, _ = read_table(snakemake.input.relaxation, RELAXATION)
    simulated_theory = theory[theory.simulated]
    panels = []
    for path in snakemake.input.simulation:
        table, provenance = read_table(path, SIMULATED_BOUNCE_CHAIN)
        restitution = parse_restitution(provenance["r"])
        match = simulated_theory[(simulated_theory.r - float(restitution)).abs() < 1e-12]
        if len(match) != 1:
            raise ValueError(
                f"{snakemake.input.relaxation}: no relaxation eigenvalue at r = {provenance['r']} "
                f"of {path}; re-run rule relaxation"
            )
        panels.append(
            {
                "restitution": restitution,
                "eigenvalue": float(match.relaxation_eigenvalue.iloc[0]),
                "simulated": table,
            }
        )
    plotting.save_figure(
        plotting.relaxation_figure(theory, panels),
        *snakemake.output,
        snakemake.params.dpi,
        {
            "figure": snakemake.rule,
            "inputs": list(snakemake.input),
            "params": dict(snakemake.params.items()),
        },
    )
