"""The studies (workflow/rules/studies.smk) as a user runs them: `snakemake studies` in a
temporary copy of the repository, with a tiny config/studies.yaml (seconds, not hours)."""

import math

import pandas as pd
import pytest
import yaml
from workflow_support import (
    SMALL,
    TINY,
    copy_with_studies,
    planned_jobs,
    snakemake,
    two_at_a_time,
)

from bouncing_ball.simulation.equilibration import default_equilibration_time
from bouncing_ball.workflow.io import read_table


def finite(table, columns):
    return all(math.isfinite(value) for value in table[columns].to_numpy().ravel())


def test_criterion_bias_report_has_every_r_and_c(studies_run):
    table = pd.read_csv(studies_run / "results/studies/criterion_bias.csv")
    assert sorted(zip(table.r, table.criterion_c)) == [
        ("1/2", 3.0),
        ("1/2", 5.0),
        ("1/3", 3.0),
        ("1/3", 5.0),
    ]
    assert (table.shards == 2).all()
    columns = ["cpu_seconds", "steps_per_collision", "rel_error_I_squared_cpu"]
    for quantity in ("mean_x", "delta_x", "collision_rate"):
        columns += [quantity, f"{quantity}_err", f"{quantity}_rel_deviation", f"{quantity}_z"]
    columns += ["p0v_chi2_per_bin", "p0v_max_abs_z"]
    assert finite(table, columns)
    assert (table.p0v_bins > 0).all()
    # the exact values, not the solver's
    assert table.set_index("r").loc["1/2", "collision_rate_exact"].tolist() == pytest.approx(
        [1 / 3, 1 / 3]
    )
    markdown = (studies_run / "results/studies/criterion_bias.md").read_text()
    assert markdown.count("\n| 1/") == 4
    _, provenance = read_table(
        studies_run / "results/studies/criterion_bias/r0.5_c5/shards0-1.parquet"
    )
    assert provenance["rule"] == "study_batch" and provenance["seed"] == 7
    assert provenance["criterion_c"] == 5.0 and provenance["shard_time"] == 2.0e3
    # the test config's equilibration_time: auto, at r = 1/2 the least, 1e3
    assert SMALL["simulation"]["equilibration_time"] == "auto"
    assert provenance["equilibration_time"] == default_equilibration_time("1/2") == 1.0e3
    # a batch of the test config's shards_per_job = 2 shards (scripts/simulate_shards.py): its
    # cost, one entry per shard
    assert (provenance["first_shard"], provenance["last_shard"]) == (0, 1)
    assert len(provenance["cpu_seconds"]) == 2 and min(provenance["cpu_seconds"]) > 0


def test_r075_report_compares_every_run_and_all_with_the_solver(studies_run):
    table = pd.read_csv(studies_run / "results/studies/r075.csv")
    assert sorted(set(table.run)) == ["all", "c3", "c5"]
    assert table.groupby("run").size().tolist() == [3, 3, 3]
    assert table.set_index("run").shards.to_dict() == {"all": 6, "c3": 4, "c5": 2}
    assert finite(table, ["value", "error", "rel_deviation", "z", "shard_rel_spread"])
    pooled = table[table.run.isin(["c3", "all"])]
    assert finite(
        pooled,
        ["batch_error_ratio", "group_spread_ratio", "skewness", "excess_kurtosis", "cpu_seconds"],
    )
    solver, provenance = read_table(studies_run / "results/solver/r0.75/summary.parquet")
    assert provenance["r_label"] == "0.75"
    for row in table.itertuples():
        assert row.solver == pytest.approx(float(solver[row.quantity].iloc[0]), rel=1e-11)
    assert "r = 0.75" in (studies_run / "results/studies/r075.md").read_text()


def test_coverage_report_scatters_every_moment_and_estimator_against_students_t(studies_run):
    table = pd.read_csv(studies_run / "results/studies/coverage.csv", dtype={"r_label": str})
    moments = [
        "mean_x",
        "delta_x",
        "collision_rate",
        "mean_flight_time",
        "flight_time_second_moment",
    ]
    assert list(zip(table.r_label, table.moment, table.estimator)) == [
        (label, moment, estimator)
        for label in ("0.5", "0.333333")
        for moment in moments
        for estimator in ("plain", "martingale", "controlled")
    ]
    # t with 3 degrees of freedom: E[t^2] = 3, P(|t| > 2) = 0.1393
    assert table.expected_mean_z2.tolist() == pytest.approx([3.0] * 30)
    assert table.expected_miss.tolist() == pytest.approx([0.139326] * 30, abs=1e-6)
    plain, controlled = table[table.estimator == "plain"], table[table.estimator != "plain"]
    assert (plain.runs == 2).all() and (plain.shards == 4).all()
    assert finite(plain, ["mean_z", "mean_z_err", "mean_z2", "mean_z2_err", "miss", "miss_err"])
    # 4 shards are too few to fit the control slopes: no martingale or controlled z
    assert (controlled.runs == 0).all() and controlled.mean_z2.isna().all()
    markdown = (studies_run / "results/studies/coverage.md").read_text()
    assert "r = 0.5: 2 runs" in markdown and markdown.count("\n| 0.") == 30
    _, provenance = read_table(
        studies_run / "results/studies/coverage/r0.333333_run1/shards2-3.parquet"
    )
    assert provenance["seed"] == 4 and provenance["r_label"] == "0.333333"


def test_the_studies_are_not_part_of_the_default_target(tmp_path):
    directory = copy_with_studies(tmp_path, TINY)
    jobs = planned_jobs(directory)
    assert "simulate_shards" in jobs
    reports = {"criterion_bias_report", "r075_report", "coverage_report"}
    assert not {"study_batch", "studies", *reports} & set(jobs)


# a bad studies file, and a part of the message that names what is wrong
BAD_STUDIES = {
    "typo": (("criterion_bias", "seeed", 7), "'seeed' was unexpected"),
    "range": (("r075", "batch_size", 0), "batch_size"),
    "typo-in-a-run": (
        ("r075", "runs", {"c3": {"criterion_c": 3.0, "seed": 1, "shard": 2}}),
        "'shard' was unexpected",
    ),
    "beyond-the-schema": (
        ("criterion_bias", "restitution", ["1/2", 0.25]),
        "r = 1/4 has no exact solution",
    ),
}


@pytest.fixture(scope="module")
def refused_studies(tmp_path_factory):
    """{case: (directory, snakemake --dry-run studies)} for each of BAD_STUDIES, in a copy of
    its own, the starts two at a time."""
    directories = {}
    for case, ((study, key, value), _) in BAD_STUDIES.items():
        bad = yaml.safe_load(yaml.safe_dump(TINY))
        bad[study][key] = value
        directories[case] = copy_with_studies(tmp_path_factory.mktemp(case), bad)
    results = two_at_a_time(
        snakemake, [(directory, "--dry-run", "studies") for directory in directories.values()]
    )
    return {case: (directories[case], result) for case, result in zip(directories, results)}


@pytest.mark.parametrize("case", list(BAD_STUDIES))
def test_a_bad_studies_file_is_refused_naming_the_key(refused_studies, case):
    directory, result = refused_studies[case]
    message = BAD_STUDIES[case][1]
    assert result.returncode != 0
    output = result.stderr + result.stdout
    assert message in output and "config/studies.yaml" in output, output[-2000:]
    assert not (directory / "results").exists()
