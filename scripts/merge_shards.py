"""Rule merge_shards: the shards of one r merged into P(0, v), P(x) and <v^2>_x, P(x, v), the
flight-time density, the return speeds, and the summary (<x>, Delta x, I, the flight-time
moments), the bounce chain's autocorrelation and decay rate ->
results/simulation/r{r}/{p0v,position,distribution,flight_time,return_speed,summary,
bounce_chain}.parquet.  Refused where the shards' early parts disagree with the rest beyond doubt
(``simulation.equilibration``), a warning where they disagree less; the check goes into the provenance."""

import logging

from bouncing_ball.estimators import (
    bounce_autocorrelation,
    bounce_chain_decay,
    distribution_histogram,
    flight_time_histogram,
    outgoing_speed_histogram,
    outside_fractions,
    position_histogram,
    position_moments_summary,
    return_speed_table,
)
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.scales import outside_summary
from bouncing_ball.settings import ShardSettings
from bouncing_ball.simulation.equilibration import (
    early_check,
    early_check_message,
    early_check_record,
    relaxation_record,
)
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.workflow.io import write_tables
from bouncing_ball.workflow.jobs import job_log
from bouncing_ball.workflow.shards import read_shards

with job_log(snakemake.log[0], exit_when_done=True):
    exact = parse_restitution(snakemake.params.restitution)
    label = restitution_label(exact)
    shards, provenances = read_shards(list(snakemake.input), label, snakemake.params.batch)
    first = provenances[0]
    provenance = {
        "rule": "merge_shards",
        "r": exact_string(exact),
        "r_label": label,
        "shards": len(shards),
        "code": snakemake.params.code,
        "simulation_code": first["code"],
        **{key: first[key] for key in ("seed", *ShardSettings.names())},
    }
    # the shards' times against the relaxation time at r, and their own evidence of
    # equilibration: the early part of each against the rest
    relaxation = relaxation_record(exact, first["shard_time"], first["equilibration_time"])
    provenance["relaxation"] = relaxation
    for problem in relaxation["problems"]:
        logging.warning(problem)
    equilibration = early_check(shards)
    provenance["equilibration_check"] = early_check_record(equilibration)
    verdict = provenance["equilibration_check"]["verdict"]
    if verdict in ("warn", "refuse"):
        message = (
            f"{early_check_message(equilibration, label)}. The shards "
            f"{'are not' if verdict == 'refuse' else 'may not be'} in equilibrium when they "
            "start recording: raise simulation.equilibration_time for this r "
            f'(simulation.per_restitution: {{"{label}": {{equilibration_time: ...}}}}; the '
            f"relaxation time there is {relaxation['relaxation_time']}) and rerun its shards"
        )
        if verdict == "refuse":
            raise RuntimeError(f"{message}. Their errors cannot be trusted: nothing is written")
        logging.warning(message)
    else:
        logging.info(early_check_message(equilibration, label))
    # how much of each table's distribution lies beyond its bins (the bins follow r's scales)
    provenance["outside"] = outside_fractions(shards)
    logging.info("r=%s: %s", label, outside_summary(provenance["outside"]))
    # the solver's P(0, u), which the controlled estimates lean on (the estimators never solve)
    theory = solved_outgoing_density(exact)
    summary = position_moments_summary(shards, exact, theory)
    write_tables(
        {
            snakemake.output.p0v: outgoing_speed_histogram(shards, exact, theory),
            snakemake.output.position: position_histogram(shards),
            snakemake.output.distribution: distribution_histogram(shards),
            snakemake.output.flight_time: flight_time_histogram(shards),
            snakemake.output.return_speed: return_speed_table(shards),
            snakemake.output.summary: summary,
            snakemake.output.bounce_chain: bounce_autocorrelation(shards).assign(
                **bounce_chain_decay(shards)
            ),
        },
        provenance,
    )
    row = summary.iloc[0]
    logging.info(
        "r=%s: %d shards, time %.6g, <x> = %.5g +- %.2g, Delta x = %.5g +- %.2g, I = %.5g +- %.2g, "
        "mean flight time %.5g +- %.2g",
        label,
        len(shards),
        row.total_time,
        row.mean_x,
        row.mean_x_err,
        row.delta_x,
        row.delta_x_err,
        row.collision_rate,
        row.collision_rate_err,
        row.mean_flight_time,
        row.mean_flight_time_err,
    )
    if row.shards_out_of_budget:
        logging.warning(
            "r=%s: %d of %d shards stopped before shard_time (step budget simulation.max_steps "
            "exhausted, or below/near r_c a speed collapse: see simulation.min_step_floor); the "
            "estimates weight every shard by the time it recorded",
            label,
            row.shards_out_of_budget,
            len(shards),
        )
