"""The workflow as a user runs it, in a temporary copy of the repository."""

import copy
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate
from workflow_support import (
    FIGURES,
    REPOSITORY,
    SMALL,
    TEST_CONFIG,
    copy_repository,
    planned_jobs,
    snakemake,
    two_at_a_time,
)

from bouncing_ball.validation import MOMENT_COLUMNS, VALIDATION_CHECKS, VALIDATION_COLUMNS
from bouncing_ball.workflow.config import check_config, read_yaml
from bouncing_ball.workflow.io import read_table


def test_run_produces_the_documented_tables(finished_run):
    for label, shards, batches in (("0.5", 3, ["0-1", "2-2"]), ("0.333333", 2, ["0-1"])):
        folder = finished_run / "results" / "simulation" / f"r{label}"
        assert sorted(p.name for p in folder.glob("shard*.parquet")) == [
            f"shards{batch}.parquet" for batch in batches
        ]  # simulation.shards_per_job: 2
        p0v, provenance = read_table(folder / "p0v.parquet")
        assert list(p0v.columns) == [
            "v_lo",
            "v_hi",
            "v",
            "p0v",
            "p0v_err",
            "count",
            "p0v_martingale",
            "p0v_martingale_err",
            "p0v_controlled",
            "p0v_controlled_err",
        ]
        assert provenance["r_label"] == label and provenance["shards"] == shards
        position, _ = read_table(folder / "position.parquet")
        assert list(position.columns) == [
            "x_lo",
            "x_hi",
            "x",
            "px",
            "px_err",
            "v2_given_x",
            "v2_given_x_err",
            "px_controlled",
            "px_controlled_err",
            "v2_given_x_controlled",
            "v2_given_x_controlled_err",
        ]
        summary, _ = read_table(folder / "summary.parquet")
        for column in (
            "r",
            "mean_x",
            "mean_x_err",
            "delta_x",
            "delta_x_err",
            "collision_rate",
            "collision_rate_err",
            "total_time",
            "collisions",
            "shards",
        ):
            assert column in summary.columns
        assert summary.total_time.iloc[0] == pytest.approx(shards * 2.0e3)
        assert p0v["count"].sum() == summary.collisions.iloc[0]
    batch, provenance = read_table(finished_run / "results/simulation/r0.333333/shards0-1.parquet")
    assert provenance["r"] == "1/3" and provenance["seed"] == 5
    assert (provenance["first_shard"], provenance["last_shard"]) == (0, 1)
    assert list(batch.columns) == ["shard", "tally", "lo", "hi", "lo2", "hi2", "value"]
    assert sorted(batch["shard"].unique()) == [0, 1]
    log = (finished_run / "logs/simulation/r0.333333/shards0-1.log").read_text()
    assert "shard 0: time 2000," in log and "shard 1: time 2000," in log
    # no measured cost in a pipeline shard's provenance: the same config, the same file
    assert "cpu_seconds" not in provenance
    assert (finished_run / "logs/simulation/r0.5/merge.log").read_text().startswith("r=0.5")
    for label in ("0.5", "0.333333"):
        p0v, provenance = read_table(finished_run / f"results/solver/r{label}/p0v.parquet")
        assert list(p0v.columns) == ["v", "p0v"] and len(p0v) == 41
        assert provenance["r_label"] == label
        summary, _ = read_table(finished_run / f"results/solver/r{label}/summary.parquet")
        for column in (
            "r",
            "mean_x",
            "delta_x",
            "collision_rate",
            "momentum_balance_residual",
            "energy_balance_residual",
            "grid_size",
            "accuracy_estimate",
        ):
            assert column in summary.columns
        assert summary.accuracy_estimate.iloc[0] < 1e-8
        distribution, _ = read_table(finished_run / f"results/exact/r{label}/distribution.parquet")
        assert list(distribution.columns) == ["x", "v", "pxv"] and len(distribution) == 12
        for table in ("p0v", "position", "summary"):
            assert (finished_run / f"results/exact/r{label}/{table}.parquet").exists()
    solved, _ = read_table(finished_run / "results/solver/r0.5/summary.parquet")
    assert solved.mean_x.iloc[0] == pytest.approx(6.0, rel=1e-8)
    exponents, _ = read_table(finished_run / "results/theory/exponents.parquet")
    assert list(exponents.columns) == ["r", "beta", "m", "q"] and len(exponents) == 9
    assert exponents.beta[exponents.r.round(9) == 0.5].iloc[0] == pytest.approx(1.0)
    for label in ("0.5", "0.333333"):
        fitted, provenance = read_table(finished_run / f"results/fits/r{label}.parquet")
        assert list(fitted.columns) == [
            "source",
            "window",
            "fit",
            "parameter",
            "value",
            "error",
            "lower_95",
            "upper_95",
            "theory",
            "joint_p_value",
            "chi2_per_dof",
            "dof",
            "v_min",
            "v_max",
        ]
        assert len(fitted) == 20 and provenance["shards"] == {"0.5": 3, "0.333333": 2}[label]


def test_run_draws_every_figure_and_writes_the_moments_table(finished_run):
    for name in FIGURES:
        content = (finished_run / name).read_bytes()
        assert content.startswith(b"%PDF" if name.endswith(".pdf") else b"\x89PNG"), name
        assert (finished_run / "logs/figures" / (Path(name).stem + ".log")).exists()
    table = pd.read_csv(finished_run / "results/tables/moments.csv")
    assert list(table.columns) == list(MOMENT_COLUMNS) and len(table) == 6
    assert sorted(table.r_label.astype(str).unique()) == ["0.333333", "0.5"]
    assert (table.reference == "exact").all()
    # two or three shards: too few for any control, the plain estimate, no eq. (kernel3) one
    assert (table.estimator == "plain").all() and table.kernel3_controlled.isna().all()
    for label, paper in (
        ("0.5", {"mean_x": 6.0, "delta_x": 10.4}),
        ("0.333333", {"mean_x": 3.89, "delta_x": 7.68}),
    ):
        summary, _ = read_table(finished_run / f"results/simulation/r{label}/summary.parquet")
        exact, _ = read_table(finished_run / f"results/exact/r{label}/summary.parquet")
        rows = table[table.r_label.astype(str) == label].set_index("quantity")
        for quantity in ("mean_x", "delta_x", "collision_rate"):
            row = rows.loc[quantity]
            assert row.exact == pytest.approx(exact[quantity].iloc[0], rel=1e-11)
            assert row.solver == pytest.approx(row.exact, rel=1e-8)
            assert row.simulation == pytest.approx(summary[quantity].iloc[0], rel=1e-11)
            z = (summary[quantity].iloc[0] - exact[quantity].iloc[0]) / summary[
                f"{quantity}_err"
            ].iloc[0]
            assert row.z == pytest.approx(z, rel=1e-9)
            if quantity in paper:
                assert row.paper == paper[quantity]
    markdown = (finished_run / "results/tables/moments.md").read_text()
    assert markdown.count("(vs exact)") == 6 and "±" in markdown
    grid, _ = read_table(finished_run / "results/solver/time_averages.parquet")
    assert grid.r.tolist() == pytest.approx([0.1, 0.3, 0.5, 0.7, 0.9])
    assert grid.collision_rate.iloc[0] == float("inf")  # r = 0.1 < r_c
    assert grid.mean_x.iloc[2] == pytest.approx(6.0, rel=1e-8)
    assert grid.collision_rate.iloc[2] == pytest.approx(1.0 / 3.0, rel=1e-8)


def test_run_writes_the_validation_table(finished_run):
    table = pd.read_csv(finished_run / "results/tables/validation.csv")
    assert list(table.columns) == list(VALIDATION_COLUMNS)
    assert sorted(table.r_label.astype(str).unique()) == ["0.333333", "0.5"]
    for label in ("0.5", "0.333333"):
        rows = table[table.r_label.astype(str) == label].set_index("check")
        assert list(rows.index) == list(VALIDATION_CHECKS), label  # every check, in order
        for check in ("p0v", "px", "v2_given_x"):
            row = rows.loc[f"{check}_chi2_per_bin"]
            assert row.reference == "exact" and row.bins > 5, (label, check)
            assert np.isfinite(row.value) and row.value > 0.0, (label, check)
            assert np.isfinite(rows.loc[f"{check}_worst_bin", "bin_centre"]), (label, check)
        chi2_rows = [
            check
            for check in rows.index
            if check.endswith("chi2_per_bin")
            and not check.startswith(("p0v_controlled", "p0v_martingale"))
        ]
        assert rows.loc[chi2_rows, "p_sign_flip"].between(0.0, 1.0, inclusive="right").all()
        # two or three shards: too few for the controlled P(0, v)s, whose rows stay empty
        controlled = rows[rows.index.str.startswith(("p0v_controlled", "p0v_martingale"))]
        assert len(controlled) == 6 and controlled.value.isna().all()
        assert rows.drop(index=chi2_rows).p_sign_flip.isna().all()
        assert rows.loc["p0v_largest_relative_error", "value"] > 0.0
    markdown = (finished_run / "results/tables/validation.md").read_text()
    assert markdown.count("\n") == len(table) + 2 and "P(0,v): chi^2/n" in markdown
    assert (finished_run / "logs/tables/validation.log").exists()


def test_the_report_has_every_figure_and_table_with_its_caption(finished_run, tmp_path):
    report = tmp_path / "report.html"
    result = snakemake(finished_run, "--report", str(report))
    assert result.returncode == 0, result.stderr[-3000:]
    text = report.read_text()
    for name in [*(f"fig{n}.png" for n in range(1, 14)), "moments.csv", "validation.csv"]:
        assert name in text, name
    for phrase in (
        "The exponents beta(r)",
        "The decay rate q(r)",
        "The exact P(x,v) against v",
        "Double-logarithmic plot of P(0,v)",
        "exact solution, eq. (P(0,v))",
        "The mean height",
        "Residuals (simulation - solver) / sigma",
        "The time averages of eq. (xandDeltax)",
        "The run held against the exact solutions",
        "Figs. 6-11 go past it",
    ):
        assert phrase in text, phrase


# the targets the workflow refuses before any job, with a part of the message naming the reason
UNANSWERABLE = [
    # outside the range where rule solve's tables are verified
    (
        "results/solver/r0.001/summary.parquet",
        "target results/solver/r0.001: r = '0.001' is outside the range of r where P(x, v) is verified",
    ),
    (
        "results/fits/r1e-07.parquet",
        "r = '1e-07' is outside the range of r where P(x, v) is verified",
    ),
    # a label that rounds to 1 (it would read back as r = 1)
    ("results/simulation/r0.9999999/p0v.parquet", "r = '0.9999999' rounds to 1"),
    # a batch of shards that is not one of the config's (its list of shards: no memory)
    (
        "results/simulation/r0.5/shards0-99999999999.parquet",
        "shards0-99999999999.parquet: not a batch of the config's shards of r = 0.5 "
        "(simulation.shards and shards_per_job): shards0-1, shards2-2",
    ),
    ("results/simulation/r0.5/shards00-1.parquet", "not a batch of the config's shards"),
    # a label that is not the canonical one of its r, an exact solution the paper has not
    ("results/simulation/r0.50/summary.parquet", "use r0.5"),
    (
        "results/exact/r0.6/summary.parquet",
        "exact solutions exist only for r0.5 (r = 1/2) and r0.333333 (r = 1/3)",
    ),
]


@pytest.fixture(scope="module")
def dry_runs(finished_run):
    """{target: snakemake --dry-run target} in the finished run, for "all" and each of
    UNANSWERABLE (dry runs take no lock: the starts run two at a time)."""
    targets = ["all", *(target for target, _ in UNANSWERABLE)]
    results = two_at_a_time(snakemake, [(finished_run, "--dry-run", target) for target in targets])
    return dict(zip(targets, results))


def test_second_run_has_nothing_to_do(dry_runs):
    result = dry_runs["all"]
    assert result.returncode == 0
    assert "Nothing to be done" in result.stdout + result.stderr


def test_an_r_not_in_the_config_is_a_valid_target(finished_run, tmp_path):
    finished_run = shutil.copytree(finished_run, tmp_path / "copy")  # the shared run stays as it is
    target = "results/simulation/r0.6/summary.parquet"
    result = snakemake(finished_run, target)
    assert result.returncode == 0, result.stderr[-3000:]
    summary = pd.read_parquet(finished_run / target)
    assert summary.r.iloc[0] == pytest.approx(0.6)
    assert summary.shards.iloc[0] == 3
    solved = "results/solver/r0.6/summary.parquet"
    result = snakemake(finished_run, solved)
    assert result.returncode == 0, result.stderr[-3000:]
    assert pd.read_parquet(finished_run / solved).r.iloc[0] == pytest.approx(0.6)


def test_exact_one_third_does_not_need_one_third_in_the_config(finished_run, tmp_path):
    """rule all always asks for r0.333333: its value is 1/3 exactly, not the label read as a number."""
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    config = yaml.safe_load(yaml.safe_dump(SMALL))
    config["restitution"] = [0.5]
    (directory / "config" / "config.yaml").write_text(yaml.safe_dump(config))
    shutil.rmtree(directory / "results" / "exact" / "r0.333333")
    result = snakemake(directory, "exact")
    assert result.returncode == 0, result.stderr[-3000:]
    _, provenance = read_table(directory / "results/exact/r0.333333/summary.parquet")
    assert provenance["r"] == "1/3"
    # Fig. 5 still shows r = 1/3 (figures.fig5): its shards keep the exact value, nothing re-runs
    assert planned_jobs(directory, None, "results/figures/fig5.pdf") == {}


def test_adding_a_shard_runs_only_the_batch_it_joins(finished_run, tmp_path):
    """Shards 0-1 and 2 of r = 1/2 in batches of 2: a fourth shard re-runs only the batch of
    shards 2-3 (the full batch 0-1 stays), then what shows r = 1/2."""
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)  # results, logs and .snakemake, mtimes kept
    config = yaml.safe_load(yaml.safe_dump(SMALL))
    config["simulation"]["per_restitution"]["0.5"] = {"shards": 4}
    (directory / "config" / "config.yaml").write_text(yaml.safe_dump(config))
    assert planned_jobs(directory) == {
        "simulate_shards": 1,
        "merge_shards": 1,
        "fit": 1,
        "fig4": 1,
        "fig5": 1,
        "fig8": 1,  # r = 1/2 is also a panel of Figs. 8 and 10 in the small config
        "fig10": 1,
        **AGGREGATES,
    }


# what shows every simulated r
AGGREGATES = {
    "fig6": 1,
    "fig7": 1,
    "fig9": 1,
    "fig12": 1,
    "moments_table": 1,
    "validation_table": 1,
    "all": 1,
}


def test_adding_an_r_runs_only_its_jobs_and_the_aggregates(finished_run, tmp_path):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    config = yaml.safe_load(yaml.safe_dump(SMALL))
    config["restitution"].append(0.6)
    (directory / "config" / "config.yaml").write_text(yaml.safe_dump(config))
    planned = planned_jobs(directory)
    assert planned == {
        "simulate_shards": 2,
        "merge_shards": 1,
        "solve": 1,
        "fit": 1,
        "position_asymptotics": 1,
        "relaxation": 1,  # its table holds lambda_2 at every simulated r
        **AGGREGATES,
    }, planned
    before = {
        path: path.stat().st_mtime_ns
        for path in (directory / "results").rglob("*")
        if path.is_file()
    }
    result = snakemake(directory)
    assert result.returncode == 0, result.stderr[-3000:]
    changed = sorted(
        str(path.relative_to(directory))
        for path in (directory / "results").rglob("*")
        if path.is_file() and before.get(path) != path.stat().st_mtime_ns
    )
    assert changed == sorted(
        [
            *(
                f"results/simulation/r0.6/{name}.parquet"
                for name in (
                    "shards0-1",
                    "shards2-2",
                    "p0v",
                    "position",
                    "distribution",
                    "flight_time",
                    "return_speed",
                    "summary",
                    "bounce_chain",
                )
            ),
            *(
                f"results/solver/r0.6/{name}.parquet"
                for name in (
                    "p0v",
                    "summary",
                    "flight_time",
                    "return_speed",
                    "position",
                    "distribution",
                    "weight",
                )
            ),
            "results/fits/r0.6.parquet",
            *(f"results/figures/fig{n}.{ext}" for n in (6, 7, 9, 12) for ext in ("pdf", "png")),
            "results/theory/relaxation.parquet",
            "results/tables/position_asymptotics.csv",
            "results/tables/position_asymptotics.md",
            "results/tables/moments.csv",
            "results/tables/moments.md",
            "results/tables/validation.csv",
            "results/tables/validation.md",
        ]
    )
    assert len(pd.read_csv(directory / "results/tables/moments.csv")) == 9
    validation = pd.read_csv(directory / "results/tables/validation.csv")
    added = validation[validation.r_label.astype(str) == "0.6"]
    assert "px_chi2_per_bin" not in set(added.check)  # no exact P(x) at r = 0.6
    assert (added[added.check.str.startswith("p0v_chi2")].reference == "solver").all()


def test_touching_every_script_reruns_nothing(finished_run, tmp_path):
    """A checkout or branch switch rewrites scripts unchanged: it re-ran every shard."""
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    for script in (directory / "scripts").rglob("*.py"):
        script.touch()
    assert planned_jobs(directory) == {}
    with open(directory / "scripts/simulate_shards.py", "a") as handle:
        handle.write("\n# an edit\n")
    planned = planned_jobs(directory)
    assert planned["simulate_shards"] == 3, planned  # batches 0-1, 2-2 of r = 1/2, 0-1 of 1/3
    assert not {"solve", "solve_grid", "exact_solution", "theory"} & set(planned)


def test_editing_a_plotting_script_reruns_only_figures(finished_run, tmp_path):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    with open(directory / "scripts/figures/fig4.py", "a") as handle:
        handle.write("\n# an edit\n")
    assert planned_jobs(directory) == {"fig4": 1, "all": 1}
    package, env = _packagecopy_repository(tmp_path)
    with open(package / "workflow" / "plotting.py", "a") as handle:
        handle.write("\n# an edit\n")
    assert planned_jobs(finished_run, env) == {f"fig{n}": 1 for n in range(1, 14)} | {"all": 1}


def test_one_target_builds_only_what_it_needs(tmp_path):
    directory = copy_repository(tmp_path, SMALL)
    assert planned_jobs(directory, None, "results/figures/fig5.pdf") == {
        "simulate_shards": 3,
        "merge_shards": 2,
        "exact_solution": 2,
        "fig5": 1,
    }
    assert planned_jobs(directory, None, "tables") == {
        "simulate_shards": 3,
        "merge_shards": 2,
        "solve": 2,
        "fit": 2,
        "exact_solution": 2,
        "moments_table": 1,
        "validation_table": 1,
        "position_asymptotics": 1,
        "tables": 1,
    }
    result = snakemake(directory, "results/figures/fig1.png")
    assert result.returncode == 0, result.stderr[-3000:]
    built = sorted(
        str(path.relative_to(directory))
        for path in (directory / "results").rglob("*")
        if path.is_file()
    )
    assert built == [
        "results/figures/fig1.pdf",
        "results/figures/fig1.png",
        "results/theory/exponents.parquet",
    ]


def _packagecopy_repository(tmp_path):
    """A copy of the library that PYTHONPATH puts in front of the installed one."""
    shutil.copytree(
        REPOSITORY / "bouncing_ball",
        tmp_path / "lib" / "bouncing_ball",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    return tmp_path / "lib" / "bouncing_ball", {**os.environ, "PYTHONPATH": str(tmp_path / "lib")}


def _edited_library(tmp_path, *modules):
    """A copy of the library (``_packagecopy_repository``) in a folder of its own under
    ``tmp_path``, with an edit appended to each of ``modules`` (paths in the package), and the
    environment that puts it first."""
    folder = tmp_path / "-".join(("library", *modules))
    package, env = _packagecopy_repository(folder)
    for module in modules:
        with open(package / module, "a") as handle:
            handle.write("\n# an edit\n")
    return env


def test_editing_library_code_reruns_only_its_stage(finished_run, tmp_path):
    # everything drawn from the simulation
    downstream = {"fig4": 1, "fig5": 1, "fig8": 1, "fig10": 1, "fig11": 1, **AGGREGATES}
    expected_after = {
        (): {},
        ("estimators/histograms.py",): {"merge_shards": 2, "fit": 2, **downstream},
        ("estimators/histograms.py", "free_flight.py"): {
            "simulate_shards": 3,
            "merge_shards": 2,
            "fit": 2,
            **downstream,
        },
    }
    solved = {
        "solve": 2,
        "fit": 2,
        "solve_grid": 1,
        "fig4": 1,
        "fig6": 1,
        "fig7": 1,
        "fig8": 1,
        "fig9": 1,
        "fig10": 1,
        "fig11": 1,
        "moments_table": 1,
        "validation_table": 1,
        "position_asymptotics": 1,
    }
    # the merge's controls of P(0, v) and the flight moments read the return-speed law and the
    # solver's P(0, v): the merged tables and what draws them (Fig. 5 besides the solved ones)
    solved_and_merged = {
        **solved,
        "merge_shards": 2,
        "fig5": 1,
        "relaxation": 1,  # lambda_2 from the solver's matrix
        "fig12": 1,
        "quasi_elastic": 1,  # the solver's P(0, v) near r = 1
        "fig13": 1,
    }
    for module, expected in (
        ("kernel", solved_and_merged),
        ("solver", solved_and_merged),
        (
            "exact",
            {
                "exact_solution": 2,
                "fig3": 1,
                "fig5": 1,
                "fig6": 1,
                "fig8": 1,
                "fig9": 1,
                "moments_table": 1,
                "validation_table": 1,  # the exact bin averages
            },
        ),
        # the validation uses fits
        (
            "fits",
            {
                "fit": 2,
                "fig4": 1,
                "fig7": 1,
                "moments_table": 1,
                "validation_table": 1,
                "position_asymptotics": 1,
            },
        ),
        ("asymptotics", {**solved_and_merged, "theory": 1, "fig1": 1, "fig2": 1}),
        (
            "validation/moments",
            {"fig7": 1, "moments_table": 1, "validation_table": 1, "position_asymptotics": 1},
        ),
    ):
        expected_after[(f"{module}.py",)] = {**expected, "all": 1}
    # each edit in a copy of its own: the dry runs (no lock) two at a time
    edits = list(expected_after)
    planned = two_at_a_time(
        planned_jobs, [(finished_run, _edited_library(tmp_path, *modules)) for modules in edits]
    )
    for modules, jobs in zip(edits, planned):
        assert jobs == expected_after[modules], modules


def test_results_do_not_depend_on_cores_or_on_the_batching_of_shards(finished_run, tmp_path):
    """The same config with --cores 1 and one shard per job (r = 1/2: shards 0-0, 1-1, 2-2,
    not 0-1 and 2-2) gives bit-identical tables."""
    config = copy.deepcopy(SMALL)
    config["simulation"]["shards_per_job"] = 1
    directory = copy_repository(tmp_path, config)
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakemake",
            "--cores",
            "1",
            "results/simulation/r0.5/p0v.parquet",
            "results/simulation/r0.5/summary.parquet",
            "results/simulation/r0.5/position.parquet",
        ],
        cwd=directory,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    folder = directory / "results/simulation/r0.5"
    assert sorted(path.name for path in folder.glob("shards*")) == [
        f"shards{k}-{k}.parquet" for k in range(3)
    ]
    for table in ("p0v", "position", "distribution", "flight_time", "return_speed", "summary"):
        one, _ = read_table(directory / f"results/simulation/r0.5/{table}.parquet")
        two, _ = read_table(finished_run / f"results/simulation/r0.5/{table}.parquet")
        pd.testing.assert_frame_equal(one, two, check_exact=True)


@pytest.mark.parametrize("target, message", UNANSWERABLE)
def test_a_target_the_workflow_cannot_answer_is_refused_before_any_job(dry_runs, target, message):
    result = dry_runs[target]
    assert result.returncode != 0
    assert message in result.stdout + result.stderr


def _with(path, value):
    config = yaml.safe_load(yaml.safe_dump(SMALL))
    *parents, last = path
    node = config
    for key in parents:
        node = node[key]
    node[last] = value
    return config


BAD = [
    (
        _with(["restitution"], [0.5, 0.0]),
        "restitution[1]: r = 0.0 is outside the allowed range 0 < r < 1",
    ),
    (_with(["restitution"], [1.0]), "restitution[0]: r = 1.0 is outside"),
    (_with(["restitution"], ["1/0"]), "restitution[0]: '1/0' divides by zero"),
    (_with(["restitution"], ["half"]), "restitution[0]: 'half' is not a number"),
    (_with(["restitution"], [0.5, "1/2"]), "restitution[1]: r = '1/2' repeats"),
    (_with(["restitution"], []), "instance['restitution']"),
    (_with(["restitution"], [[0.5]]), "instance['restitution'][0]"),
    (_with(["simulation", "shards"], 0), "shards"),
    (_with(["simulation", "shards"], -3), "-3 is less than the minimum of 2"),
    (_with(["simulation", "equilibration_time"], -1.0), "equilibration_time"),
    (_with(["simulation", "max_steps"], 0), "max_steps"),
    (_with(["simulation", "min_step_floor"], -1.0e-12), "min_step_floor"),
    (_with(["simulation", "min_step_floor"], 1.0e-3), "0.001 is greater than the maximum of 1e-06"),
    (_with(["simulation", "per_restitution"], {"0.5": {"min_step_floor": -1}}), "min_step_floor"),
    (
        _with(["simulation", "per_restitution"], {"0.5": {"shard_tme": 5}}),
        "'shard_tme' was unexpected",
    ),
    (_with(["simulation", "shard_time"], -1.0), "shard_time"),
    (_with(["simulation", "criterion_c"], 0.0), "criterion_c"),
    (_with(["simulation", "shard_time"], "1e5"), "shard_time"),
    (
        _with(["simulation", "speed_bins"], {"lo": 1.0e3, "hi": 1.0e2, "per_decade": 10}),
        "simulation.speed_bins at r = 0.5: lo = 1000 must be smaller than hi = 100",
    ),
    (
        _with(["simulation", "speed_bins"], {"lo": 1.0e3, "per_decade": 10}),
        "simulation.speed_bins at r = 0.5: lo = 1000 must be smaller than hi = 25.1189 (an end "
        "not given follows r's scales)",
    ),
    (_with(["simulation", "shardz"], 4), "'shardz' was unexpected"),
    (_with(["sead"], 4), "'sead' was unexpected"),
    (_with(["simulation", "per_restitution"], {"2": {"shards": 2}}), "per_restitution.2"),
    (_with(["solver", "quadrature_step"], 0.05), "quadrature_step"),
    (_with(["solver", "quadrature_step"], 0.7), "quadrature_step"),
    (
        _with(["solver", "output_speeds", "min"], 0.0),
        "0.0 is less than the minimum of 1e-100\n\nFailed validating 'minimum' in schema['properties']['solver']['properties']['output_speeds']['allOf'][1]['properties']['min']",
    ),
    (_with(["exact", "speeds", "max"], -3), "exact.speeds: min = -2 must be smaller"),
    (_with(["exact", "positions"], [-0.1]), "positions"),
    (_with(["exact", "positions"], [0, 1.0e-5]), "positions"),
    (_with(["solvr"], {}), "'solvr' was unexpected"),
    (
        _with(["theory", "restitution_grid", "max"], 1.0),
        "theory.restitution_grid: need 0 < min < max < 1",
    ),
    (_with(["fits", "small_speed_window"], "automatic"), "small_speed_window"),
    (_with(["fits", "max_bias"], 2.0), "max_bias"),
    (_with(["simulation", "shards"], 1), "shards"),
    (
        _with(["fits", "large_speed_window"], {"min": 5, "max": 2}),
        "fits.large_speed_window: min = 5",
    ),
    (
        _with(["solver", "restitution_grid", "min"], 0.01),
        "solver.restitution_grid: need 0.02 <= min",
    ),
    (_with(["figures", "fig4"], [0.6, "3/5"]), "figures.fig4[1]: r = '3/5' repeats"),
    (
        _with(["figures", "fig4"], [0.3333333]),
        "figures.fig4[0]: r = 3333333/10000000 and r = 1/3 share the label",
    ),
    (_with(["figures", "fig5"], [0.5, 0.5]), "figures.fig5[1]: r = 0.5 repeats"),
    (_with(["figures", "fig5"], [0.25]), "figures.fig5[0]: r = 0.25 has no exact solution"),
    (_with(["figures", "png_dpi"], 10), "png_dpi"),
    (_with(["figures", "fig6"], [0.5]), "'fig6' was unexpected"),
    # integers that are floats, a step budget beyond the loop's counter
    (_with(["seed"], 1.0), "config: seed: 1.0 is not of type 'integer'"),
    (_with(["simulation", "max_steps"], 1.0e20), "greater than the maximum of 1000000000000000"),
    (
        _with(["simulation", "max_steps"], 1.0e9),
        "simulation.max_steps: 1000000000.0 is not of type",
    ),
    (
        _with(["simulation", "per_restitution"], {"0.5": {"shards": 3.0}}),
        "config: simulation.per_restitution.0.5.shards: 3.0 is not of type 'integer'",
    ),
    # r the solver cannot answer to its accuracy, r whose label is not an r
    (
        _with(["restitution"], [0.99995]),
        "restitution[0]: r = 0.99995 is outside the range of r where P(x, v) is verified, 0.02 <= r <= 0.999",
    ),
    (
        _with(["restitution"], [0.001]),
        "restitution[0]: r = 0.001 is outside the range of r where P(x, v) is verified",
    ),
    (
        _with(["figures", "fig4"], [0.01]),
        "figures.fig4[0]: r = 0.01 is outside the range of r where P(x, v) is verified",
    ),
    (_with(["restitution"], [0.9999999]), "restitution[0]: r = 0.9999999 rounds to 1"),
    # different r with one label
    (
        _with(["restitution"], [0.5000001, 0.5]),
        "restitution[1]: r = 1/2 and r = 5000001/10000000 share the label 0.5",
    ),
    (
        _with(["simulation", "per_restitution"], {"0.5000001": {"shards": 3}}),
        "simulation.per_restitution.0.5000001: r = 5000001/10000000 and r = 1/2 share the label",
    ),
    (
        _with(["simulation", "per_restitution"], {"0.6000001": {"shards": 3}}),
        "simulation.per_restitution.0.6000001: r = 0.6000001 is not an r of the config",
    ),
]


NAN, INF = float("nan"), float("inf")
# numbers that are not finite, sizes beyond a job's memory, what a figure would draw wrongly
BAD += [
    (_with(["fits", "max_bias"], NAN), "config: fits.max_bias: nan is not a finite number"),
    (_with(["solver", "forces", "max"], INF), "config: solver.forces.max: inf is not a finite"),
    (_with(["solver", "positions"], [INF]), "On instance['solver']['positions'][0]"),
    (_with(["exact", "positions"], [NAN]), "config: exact.positions.0: nan is not a finite"),
    (_with(["simulation", "shard_time"], INF), "config: simulation.shard_time: inf is not a"),
    (_with(["simulation", "criterion_c"], INF), "config: simulation.criterion_c: inf is not a"),
    (_with(["figures", "return_speeds"], [NAN]), "config: figures.return_speeds.0: nan is not"),
    (_with(["figures", "return_speeds"], [1.0e6]), "figures.return_speeds[0]: u = 1000000.0 is"),
    (
        _with(["solver", "position_grid", "points"], 10_000_000),
        "instance['solver']['position_grid']['points']",
    ),
    (_with(["solver", "flight_times", "points"], 20_000), "solver.flight_times: 20000 points"),
    (
        _with(["simulation", "velocity_bins", "width"], 1.0e-4),
        "simulation.velocity_bins and simulation.position_bins: the tallies of a shard have",
    ),
    (
        _with(["solver", "restitution_grid", "points"], 100_000_000),
        "instance['solver']['restitution_grid']['points']",
    ),
    (_with(["solver", "positions"], [0, 2.0e3]), "solver.positions[1]: x = 2000.0 is outside"),
    (_with(["solver", "positions"], [0, 0.1, 0]), "solver.positions[2]: x = 0 repeats"),
]


def refusal(config):
    """The message with which the workflow refuses ``config``: the Snakefile's schema
    validation, then common.smk's check_config; None if it is accepted."""
    try:
        validate(copy.deepcopy(config), str(REPOSITORY / "workflow/schemas/config.schema.yaml"))
        check_config(config, read_yaml(REPOSITORY / "workflow/schemas/config.schema.yaml"))
    except (WorkflowError, ValueError) as error:
        return str(error)
    return None


def test_the_small_config_is_accepted():
    assert refusal(SMALL) is None  # so that each bad config below fails for its own reason


@pytest.mark.parametrize("config, key", BAD, ids=[key.split(":")[0] for _, key in BAD])
def test_bad_config_is_refused_with_a_message_naming_the_key(config, key):
    message = refusal(config)
    assert message is not None and key in message, message


# one of each kind, end to end: refused by Snakemake before any job runs, nothing written
# (the messages of every case are checked in-process above; these are the paths through the
# Snakefile's schema check, common.smk's strict types and its consistency checks)
END_TO_END = [BAD[i] for i in (0, 5, 8, 19)] + [
    (config, key)
    for config, key in BAD
    if key.startswith(
        (
            "figures.fig5[0]",
            "solver.restitution_grid",
            "config: seed",
            "simulation.per_restitution.0.5000001",
            "config: fits.max_bias: nan",
            "simulation.velocity_bins and",
        )
    )
]


@pytest.fixture(scope="module")
def refused_end_to_end(tmp_path_factory):
    """{key: (directory, snakemake's result)} for each config of END_TO_END, in a copy of its
    own, the runs two at a time."""
    directories = [
        copy_repository(tmp_path_factory.mktemp("refused"), config) for config, _ in END_TO_END
    ]
    results = two_at_a_time(snakemake, [(directory,) for directory in directories])
    return {key: run for (_, key), run in zip(END_TO_END, zip(directories, results))}


@pytest.mark.parametrize("key", [key for _, key in END_TO_END], ids=lambda key: key.split(":")[0])
def test_bad_config_is_refused_before_any_job_runs(refused_end_to_end, key):
    directory, result = refused_end_to_end[key]
    assert result.returncode != 0
    assert key in result.stderr + result.stdout
    assert not (directory / "results").exists()


def test_a_bad_config_leaves_existing_results_untouched(finished_run, tmp_path):
    directory = tmp_path / "copy"
    shutil.copytree(finished_run, directory)
    before = {path: path.stat().st_mtime_ns for path in (directory / "results").rglob("*")}
    (directory / "config" / "config.yaml").write_text(
        yaml.safe_dump(_with(["restitution"], [0.5, "1/2"]))
    )
    result = snakemake(directory)
    assert (
        result.returncode != 0
        and "restitution[1]: r = '1/2' repeats" in result.stderr + result.stdout
    )
    assert {path: path.stat().st_mtime_ns for path in (directory / "results").rglob("*")} == before


def test_the_quick_look_the_elastic_end_and_the_test_config_plan_a_run():
    """config/quick.yaml and config/elastic.yaml (overlays of config.yaml) and
    .test/config/config.yaml validate."""
    for arguments in (
        ["--configfile", "config/quick.yaml"],
        ["results/tables/moments.md", "--configfile", "config/elastic.yaml"],
        ["--configfile", str(TEST_CONFIG)],
    ):
        planned = subprocess.run(
            [sys.executable, "-m", "snakemake", "--dry-run", *arguments],
            cwd=REPOSITORY,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert planned.returncode == 0, planned.stderr[-2000:]
