"""Rule fit: the asymptotic forms of P(0, v) fitted at one r, to the simulation and to the
solver -> results/fits/r{r}.parquet (one row per source, window, fit and parameter)."""

import logging

import numpy as np

from bouncing_ball import fits
from bouncing_ball.estimators import outgoing_speed_histogram
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.workflow.io import SOLVER_P0V, UnreadableFileError, read_table, write_table
from bouncing_ball.workflow.jobs import job_log
from bouncing_ball.workflow.shards import read_shards

with job_log(snakemake.log[0], exit_when_done=True):
    settings = snakemake.params.settings
    value = parse_restitution(snakemake.params.restitution)
    label, r = restitution_label(value), float(value)
    shards, provenances = read_shards(list(snakemake.input.shards), label, snakemake.params.batch)
    table = outgoing_speed_histogram(shards)
    times = np.array([s.time for s in shards])
    curve, solver_provenance = read_table(snakemake.input.solver, SOLVER_P0V)
    if solver_provenance.get("r_label") != label:
        raise UnreadableFileError(
            f"{snakemake.input.solver}: solved for r = {solver_provenance.get('r_label')}, not r = {label}"
        )
    # the solver's output speeds up to where its P(0, v) underflows
    speeds, density = fits.usable_curve(curve.v.to_numpy(), curve.p0v.to_numpy())
    chosen = fits.select_fit_bins(table, speeds, density, times.sum(), settings["minimum_count"])
    if chosen.beyond:
        logging.warning(
            "r=%s: %d populated bins above v = %g, where the solver's curve ends, are left out",
            label,
            chosen.beyond,
            speeds[-1],
        )
    jackknife_errors = table.p0v_err.to_numpy()[chosen.rows]
    errors = fits.fit_errors(jackknife_errors, chosen.reference, chosen.expected)
    replaced = int(np.sum(errors != jackknife_errors))
    if replaced:
        logging.warning(
            "r=%s: %d bins without a jackknife error (too few shards?) are weighted by their "
            "Poisson error",
            label,
            replaced,
        )
    counts = np.stack([s.speed_counts[chosen.rows] for s in shards])
    windows = {
        fits.SMALL_SPEED: settings["small_speed_window"],
        fits.LARGE_SPEED: settings["large_speed_window"],
    }
    result, problems = fits.asymptotic_fits(
        chosen.lower,
        chosen.upper,
        counts,
        times,
        errors,
        chosen.reference,
        r,
        windows,
        settings["max_bias"],
    )
    for problem in problems:
        logging.warning("r=%s: no fit (%s); its rows are NaN", label, problem)
    provenance = {
        "rule": "fit",
        "r": exact_string(value),
        "r_label": label,
        "shards": len(shards),
        "settings": settings,
        "code": snakemake.params.code,
        "simulation_code": provenances[0]["code"],
        "solver_code": solver_provenance.get("code"),
    }
    write_table(result, snakemake.output[0], provenance)
    free = result[(result.source == "simulation") & (result.fit == "free_exponents")]
    for row in free[free.parameter != "prefactor"].itertuples():
        logging.info(
            "r=%s %s [%.3g, %.3g]: %s = %.5g +- %.2g (95%%: %.5g .. %.5g), theory %.5g; "
            "theory's exponents together: p = %.3g; chi2/dof %.2f",
            label,
            row.window,
            row.v_min,
            row.v_max,
            row.parameter,
            row.value,
            row.error,
            row.lower_95,
            row.upper_95,
            row.theory,
            row.joint_p_value,
            row.chi2_per_dof,
        )
