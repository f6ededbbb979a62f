"""The studies' analysis (bouncing_ball.workflow.studies) on hand-computed cases, and their config
(bouncing_ball.workflow.config.study_runs)."""

import copy
from dataclasses import replace
from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy import stats
from workflow_support import REPOSITORY, SMALL

from bouncing_ball.bins import LinearBins, LogBins
from bouncing_ball.tallies import ShardTallies
from bouncing_ball.workflow import studies
from bouncing_ball.workflow.config import shard_settings, study_runs

BINS = LogBins(1.0, 10.0, 1)
STUDIES = yaml.safe_load((REPOSITORY / "config" / "studies.yaml").read_text())


BIN_SET = SimpleNamespace(
    speed_bins=BINS,
    position_bins=BINS,
    velocity_bins=LinearBins(-1.0, 1.0, 1.0),
    flight_time_bins=BINS,
)


def shard(collisions, int_x=1.0, int_x2=2.0, time=1.0):
    empty = ShardTallies.from_loop(BIN_SET, ShardTallies.loop_arrays(BIN_SET))
    return replace(empty, time=time, collisions=collisions, int_x=int_x, int_x2=int_x2)


def test_batch_errors_are_the_scatter_of_batch_means_against_the_single_shard_jackknife():
    # I of the shards: 1, 2, 3, 4, 5 (unit time); batches of 2: means 1.5 and 3.5, the fifth
    # shard left out; batch error sd(1.5, 3.5) / sqrt(2) = 1; jackknife (= standard error of
    # the mean for equal times) of 1, 2, 3, 4: sqrt(5/3) / 2
    shards = [shard(c) for c in (1, 2, 3, 4, 5)]
    batches, batch_error, single = studies.batch_errors(shards, 0.5, 2)["collision_rate"]
    assert batches == 2
    assert batch_error == pytest.approx(1.0)
    assert single == pytest.approx(np.sqrt(5.0 / 3.0) / 2.0)
    # <x>: int_x 1, 3, 1, 3 -> batch means 2, 2: no scatter between batches
    shards = [shard(1, int_x=x, int_x2=20.0) for x in (1.0, 3.0, 1.0, 3.0)]
    _, batch_error, single = studies.batch_errors(shards, 0.5, 2)["mean_x"]
    assert batch_error == 0.0 and single == pytest.approx(np.sqrt(4.0 / 3.0) / 2.0)
    assert np.isnan(studies.batch_errors(shards, 0.5, 3)["mean_x"][1])  # one batch: no error


def test_against_reference_gives_the_relative_deviation_and_z():
    summary = studies.position_moments_summary([shard(1, 10.0, 200.0), shard(3, 12.0, 300.0)], 0.5)
    row = summary.iloc[0]
    compared = studies.against_reference(
        row, {"mean_x": 10.0, "delta_x": 1.0, "collision_rate": 1.0}
    )
    # <x> = 22 / 2 = 11, jackknife error of (10, 12) = 1: +10%, z = +1
    assert compared["mean_x"]["value"] == pytest.approx(11.0)
    assert compared["mean_x"]["rel_deviation"] == pytest.approx(0.1)
    assert compared["mean_x"]["rel_error"] == pytest.approx(0.1)
    assert compared["mean_x"]["z"] == pytest.approx(1.0)
    # I = 4 / 2 = 2 +- 1 against 1: z = +1
    assert compared["collision_rate"]["z"] == pytest.approx(1.0)


def test_group_statistics_are_each_groups_z_and_the_spread_of_their_means():
    # groups of 2 with I = (1, 3) and (5, 7): each 1 +- 1 off the references 1 and 5 below
    shards = [shard(c) for c in (1, 3, 5, 7)]
    stats = studies.group_statistics(
        shards, 0.5, {"mean_x": 1.0, "delta_x": 1.0, "collision_rate": 4.0}, 2
    )["collision_rate"]
    # group means 2 and 6 against 4: relative deviations -0.5, +0.5, errors 1 / 4
    assert stats["groups"] == 2
    assert stats["z"] == pytest.approx([-2.0, 2.0])
    assert stats["spread"] == pytest.approx(np.std([-0.5, 0.5], ddof=1))
    assert stats["mean_error"] == pytest.approx(0.25)
    assert stats["ratio"] == pytest.approx(np.sqrt(0.5) / 0.25)
    assert studies.jackknife_error_uncertainty(32) == pytest.approx(0.127, abs=1e-3)


def test_shape_of_a_symmetric_two_point_sample():
    skewness, kurtosis = studies.shape([-1.0, 1.0, -1.0, 1.0])
    assert skewness == pytest.approx(0.0) and kurtosis == pytest.approx(-2.0)
    assert np.isnan(studies.shape([1.0, 2.0])[0])


def test_cpu_seconds_only_when_every_shard_recorded_it():
    assert studies.cpu_seconds([{"cpu_seconds": 1.5}, {"cpu_seconds": 2.0}]) == 3.5
    assert np.isnan(studies.cpu_seconds([{"cpu_seconds": 1.5}, {}]))


def test_the_studies_file_plans_the_readme_runs():
    runs = study_runs(copy.deepcopy(STUDIES), SMALL)
    bias = runs["criterion_bias"]
    assert list(bias) == ["r0.5_c3", "r0.5_c5", "r0.333333_c3", "r0.333333_c5"]
    assert bias["r0.333333_c5"].restitution == Fraction(1, 3)
    assert bias["r0.333333_c5"].settings.shard_time == 8.5e6
    assert bias["r0.5_c5"].settings.criterion_c == 5.0
    assert {run.seed for run in bias.values()} == {31415926}
    r075 = runs["r075"]
    assert {name: (run.seed, run.shards) for name, run in r075.items()} == {
        "c3": (20240931, 128),
        "c5": (55501, 64),
    }
    # what the study does not set comes from the main config (here the small one)
    expected = shard_settings(SMALL, "0.75").replace(shard_time=3.1e7, criterion_c=3.0)
    assert r075["c3"].settings == expected
    coverage = runs["coverage"]
    assert len(coverage) == 2 * 48
    assert coverage["r0.5_run00"].seed == 271828 and coverage["r0.333333_run47"].seed == 271875
    assert {run.shards for run in coverage.values()} == {64}
    assert coverage["r0.333333_run05"].settings == shard_settings(SMALL, "1/3").replace(
        shard_time=2.4e5
    )


@pytest.mark.parametrize(
    "change, message",
    [
        ({"criterion_bias": {"restitution": [0.5, 0.25]}}, "r = 1/4 has no exact solution"),
        ({"criterion_bias": {"shard_time": {"1/2": 1.0e3}}}, "no shard_time for r = 1/3"),
        (
            {
                "r075": {
                    "runs": {
                        "a": {"criterion_c": 3.0, "seed": 1, "shards": 2},
                        "b": {"criterion_c": 5.0, "seed": 1, "shards": 2},
                    }
                }
            },
            "r075.runs.b: seed 1",
        ),
        ({"r075": {"simulation": {"equilibration_time": -1.0}}}, "r075.runs.c3: shard settings"),
        ({"coverage": {"restitution": ["1/3", 0.75]}}, "coverage.restitution: r = 3/4"),
        ({"coverage": {"shard_time": {"1/3": 1.0e3}}}, "coverage.shard_time: no shard_time"),
    ],
)
def test_inconsistent_studies_are_refused_naming_the_key(change, message):
    bad = copy.deepcopy(STUDIES)
    for study, values in change.items():
        bad[study].update(values)
    with pytest.raises(ValueError, match=message):
        study_runs(bad, SMALL)


def test_student_t_coverage_is_scipys_t_distribution():
    for shards in (4, 8, 64):
        mean_square, miss = studies.student_t_coverage(shards)
        assert mean_square == pytest.approx(stats.t.var(shards - 1), rel=1e-12)
        assert miss == pytest.approx(2.0 * stats.t.sf(2.0, shards - 1), rel=1e-12)
    assert np.isnan(studies.student_t_coverage(3)[0])  # E[t_2^2] is infinite
    with pytest.raises(ValueError, match="shards"):
        studies.student_t_coverage(1)
    with pytest.raises(ValueError, match="limit"):
        studies.student_t_coverage(8, limit=0.0)


def test_coverage_rows_are_the_moments_of_z_over_the_runs():
    z = [1.0, -3.0, 2.5, 0.0, np.nan]  # the NaN (no estimate) is left out
    frame = pd.DataFrame(
        {"r_label": "0.5", "run": range(5), "moment": "mean_x", "estimator": "plain", "z": z}
    )
    row = studies.coverage_rows(frame, 8).set_index(["moment", "estimator"]).loc["mean_x", "plain"]
    assert row.runs == 4
    assert row.mean_z == pytest.approx(0.125)
    assert row.mean_z2 == pytest.approx((1.0 + 9.0 + 6.25) / 4)
    assert row.mean_z2_err == pytest.approx(np.std([1.0, 9.0, 6.25, 0.0], ddof=1) / 2.0)
    assert row.expected_mean_z2 == pytest.approx(7.0 / 5.0)
    # the binomial error of the fraction at t_7's P(|t| > 2) = 0.0856
    assert row.miss == 0.5
    assert row.miss_err == pytest.approx(np.sqrt(row.expected_miss * (1 - row.expected_miss) / 4))
    assert row.expected_miss == pytest.approx(2.0 * stats.t.sf(2.0, 7), rel=1e-12)
    # every moment and estimator has a row; those without a z have none of the statistics
    table = studies.coverage_rows(frame, 8)
    assert len(table) == len(studies.COVERAGE_MOMENTS) * len(studies.COVERAGE_ESTIMATORS)
    assert (table.runs[1:] == 0).all() and table.mean_z2[1:].isna().all()


def test_coverage_of_normal_shards_is_students_t():
    # 4000 runs of 8 normal shards, z = mean / standard error: mean z^2 and the fraction of
    # |z| > 2 match t_7 within 4 of their standard errors
    values = np.random.default_rng(5).normal(size=(4000, 8))
    z = values.mean(axis=1) / (values.std(axis=1, ddof=1) / np.sqrt(8))
    frame = pd.DataFrame(
        {"r_label": "0.5", "run": range(len(z)), "moment": "mean_x", "estimator": "plain", "z": z}
    )
    row = studies.coverage_rows(frame, 8).iloc[0]
    assert abs(row.mean_z2 - row.expected_mean_z2) < 4 * row.mean_z2_err
    assert abs(row.miss - row.expected_miss) < 4 * row.miss_err
    # the normal law's 1 and 0.0455 are rejected by the same test: t_7 is heavier
    assert abs(row.mean_z2 - 1.0) > 4 * row.mean_z2_err
    assert abs(row.miss - 0.0455) > 4 * row.miss_err


def test_run_z_scores_of_both_estimators_and_none_without_an_estimate():
    summary = pd.Series(
        {
            **dict.fromkeys(studies.COVERAGE_MOMENTS, 2.0),
            **{f"{moment}_err": 0.5 for moment in studies.COVERAGE_MOMENTS},
            **{f"{moment}_controlled": 1.0 for moment in studies.COVERAGE_MOMENTS},
            **{f"{moment}_controlled_err": np.nan for moment in studies.COVERAGE_MOMENTS},
        }
    )
    reference = dict.fromkeys(studies.COVERAGE_MOMENTS, 1.5)
    z = studies.run_z_scores(summary, reference)
    assert z["flight_time_second_moment", "plain"] == pytest.approx(1.0)
    assert np.isnan(z["mean_x", "controlled"])


def test_exact_moments_are_the_closed_forms_at_one_half():
    # <x> = 6, Delta x = 6 sqrt(3), I = 1/3 (exact.position_moments), <T> = 1 / I
    moments = studies.exact_moments("1/2")
    assert moments["mean_x"] == pytest.approx(6.0, rel=1e-10)
    assert moments["delta_x"] == pytest.approx(6.0 * np.sqrt(3.0), rel=1e-10)
    assert moments["mean_flight_time"] == pytest.approx(3.0, rel=1e-10)
