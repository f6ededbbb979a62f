"""The time averages <x>, Delta x, I of eq. (xandDeltax) for every simulated r: the paper's
value where it gives one, the exact and solver values, the simulation's with its error,
and the z-score against the exact value (or the solver's where there is none).

Writes results/tables/moments.csv (one row per r and quantity) and moments.md.
Run by Snakemake (rule moments_table), or by hand (one simulation and one solver
summary per r, in order; exact summaries in any order):
    python scripts/moments_table.py --simulation results/simulation/r0.5/summary.parquet \
        --solver results/solver/r0.5/summary.parquet --exact results/exact/r*/summary.parquet \
        --csv moments.csv --md moments.md
"""

import argparse
import logging
from pathlib import Path

from bouncing_ball.comparison import QUANTITIES, moment_rows, moments_markdown, moments_table
from bouncing_ball.io import atomic_path, read_table, require_columns
from bouncing_ball.restitution import parse_restitution


def main(simulation_paths, solver_paths, exact_paths, csv_path, md_path):
    exact = {}
    for path in exact_paths:
        summary, provenance = read_table(path)
        require_columns(summary, path, QUANTITIES)
        exact[parse_restitution(provenance["r"])] = summary.iloc[0]
    rows = []
    for simulation, solver in zip(simulation_paths, solver_paths, strict=True):
        simulated, provenance = read_table(simulation)
        require_columns(
            simulated, simulation, [*QUANTITIES, *(f"{name}_err" for name in QUANTITIES)]
        )
        solved, solver_provenance = read_table(solver)
        require_columns(solved, solver, QUANTITIES)
        restitution = parse_restitution(provenance["r"])
        if parse_restitution(solver_provenance["r"]) != restitution:
            raise ValueError(
                f"{simulation} (r = {provenance['r']}) and {solver} "
                f"(r = {solver_provenance['r']}) are not the same r"
            )
        rows += moment_rows(
            provenance["r_label"],
            restitution,
            simulated.iloc[0],
            solved.iloc[0],
            exact.get(restitution),
        )
    table = moments_table(rows)
    with atomic_path(csv_path) as path:
        table.to_csv(path, index=False, float_format="%.12g")
    with atomic_path(md_path) as path:
        Path(path).write_text(moments_markdown(table))
    for row in table.itertuples():
        logging.info(
            "r=%s %s: simulation %.6g +- %.2g, %s %.10g, z = %+.2f",
            row.r_label,
            row.quantity,
            row.simulation,
            row.simulation_err,
            row.reference,
            getattr(row, row.reference),
            row.z,
        )


if "snakemake" in globals():
    logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(message)s")  # noqa: F821
    main(
        snakemake.input.simulation,
        snakemake.input.solver,
        snakemake.input.exact,  # noqa: F821
        snakemake.output.csv,
        snakemake.output.md,
    )  # noqa: F821
elif __name__ == "__main__":
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--simulation", nargs="+", required=True, help="results/simulation/r{r}/summary.parquet"
    )
    parser.add_argument(
        "--solver", nargs="+", required=True, help="results/solver/r{r}/summary.parquet"
    )
    parser.add_argument("--exact", nargs="*", default=[], help="results/exact/r{r}/summary.parquet")
    parser.add_argument("--csv", required=True)
    parser.add_argument("--md", required=True)
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(args.simulation, args.solver, args.exact, args.csv, args.md)
