"""Fits of the asymptotic forms of P(0, v) at one r, to the simulation and to the solver.

Writes results/fits/r{r}.parquet (long format: one row per source, window,
fit and parameter; see the README).  Run by Snakemake (rule fit), or by hand:
    python scripts/fit.py --restitution 0.25 --solver results/solver/r0.25/p0v.parquet \
        --output fits.parquet [--config config/config.yaml] results/simulation/r0.25/shard*.parquet
"""

import argparse
import logging

import numpy as np

from bouncing_ball import fits, source_digest
from bouncing_ball.config import read_config
from bouncing_ball.histograms import outgoing_speed_histogram
from bouncing_ball.io import read_table, write_table
from bouncing_ball.restitution import exact_string, parse_restitution, restitution_label
from bouncing_ball.shards import read_shards


def main(shard_paths, solver_path, restitution, settings, output):
    value = parse_restitution(restitution)
    label = restitution_label(value)
    r = float(value)
    shards, provenances = read_shards(shard_paths, label)
    table = outgoing_speed_histogram(shards)
    times = np.array([s.time for s in shards])
    curve, solver_provenance = read_table(solver_path)
    if solver_provenance.get("r_label") != label:
        raise ValueError(
            f"{solver_path}: solved for r = {solver_provenance.get('r_label')}, not r = {label}"
        )
    # the solver's output speeds (solver.output_speeds) up to where P(0, v) underflows
    speeds, density = fits.usable_curve(curve.v.to_numpy(), curve.p0v.to_numpy())
    inside = (
        np.isfinite(table.v_hi) & (table.v_lo >= speeds[0]) & (table.v_hi <= speeds[-1])
    ).to_numpy()
    beyond = int(np.sum(np.isfinite(table.v_hi) & (table.v_hi > speeds[-1]) & (table["count"] > 0)))
    if beyond:
        logging.warning(
            "r=%s: %d populated bins above v = %g, where the solver's curve ends, are left out",
            label,
            beyond,
            speeds[-1],
        )
    lower_all, upper_all = table.v_lo.to_numpy()[inside], table.v_hi.to_numpy()[inside]
    reference_all = fits.bin_averages_of_curve(speeds, density, lower_all, upper_all)
    # bins chosen by the collisions they should hold, not by those they happen to hold
    expected = fits.expected_collisions(reference_all, lower_all, upper_all, times.sum())
    keep = expected >= settings["minimum_count"]
    lower, upper, reference = lower_all[keep], upper_all[keep], reference_all[keep]
    rows = np.flatnonzero(inside)[keep]
    jackknife_errors = table.p0v_err.to_numpy()[rows]
    errors = fits.fit_errors(jackknife_errors, reference, expected[keep])
    replaced = int(np.sum(errors != jackknife_errors))
    if replaced:
        logging.warning(
            "r=%s: %d bins without a jackknife error (too few shards?) are weighted by their "
            "Poisson error",
            label,
            replaced,
        )
    counts = np.stack([s.speed_counts[rows] for s in shards])
    windows = {
        fits.SMALL_SPEED: settings["small_speed_window"],
        fits.LARGE_SPEED: settings["large_speed_window"],
    }
    result, problems = fits.asymptotic_fits(
        lower, upper, counts, times, errors, reference, r, windows, settings["max_bias"]
    )
    for problem in problems:
        logging.warning("r=%s: no fit (%s); its rows are NaN", label, problem)
    provenance = {
        "rule": "fit",
        "r": exact_string(value),
        "r_label": label,
        "shards": len(shards),
        "settings": settings,
        "code": source_digest(fits.SOURCES),
        "simulation_code": provenances[0]["code"],
        "solver_code": solver_provenance.get("code"),
    }
    write_table(result, output, provenance)
    for row in result[
        (result.source == "simulation") & (result.fit == "free_exponents")
    ].itertuples():
        if row.parameter != "prefactor":
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


def _command_line():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("shards", nargs="+")
    parser.add_argument("--restitution", required=True)
    parser.add_argument("--solver", required=True, help="the solver's p0v.parquet for this r")
    parser.add_argument("--output", required=True)
    parser.add_argument("--config", default="config/config.yaml", help="fit settings from here")
    args = parser.parse_args()
    config = read_config(args.config)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.shards, args.solver, args.restitution, config["fits"], args.output)


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        list(snakemake.input.shards),  # noqa: F821
        snakemake.input.solver,  # noqa: F821
        snakemake.params.restitution,  # noqa: F821
        snakemake.params.settings,  # noqa: F821
        snakemake.output[0],  # noqa: F821
    )
elif __name__ == "__main__":
    _command_line()
