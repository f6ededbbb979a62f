"""The public API gives the workflow's numbers: Equilibrium(r) with the config's solver
settings against the tables the solve rule writes (results/solver/r{r}/), at the first r of
the small config, in a temporary copy of the repository (one solve job)."""

import numpy as np
import pytest
from workflow_support import SMALL, copy_repository, snakemake

import bouncing_ball as bb
from bouncing_ball.restitution import parse_restitution, restitution_label
from bouncing_ball.workflow.io import read_table

R = SMALL["restitution"][0]
LABEL = restitution_label(parse_restitution(R))
TABLES = ("p0v", "summary", "flight_time", "position", "distribution", "weight")


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    directory = copy_repository(tmp_path_factory.mktemp("solve"), SMALL)
    targets = [f"results/solver/r{LABEL}/{name}.parquet" for name in TABLES]
    result = snakemake(directory, *targets)
    assert result.returncode == 0, result.stderr[-3000:]
    tables = {name: read_table(directory / target)[0] for name, target in zip(TABLES, targets)}
    equilibrium = bb.Equilibrium(
        R,
        quadrature_step=SMALL["solver"]["quadrature_step"],
        weight_panel_nodes=SMALL["solver"]["weight_panel_nodes"],
    )
    return tables, equilibrium


def _same(ours, theirs, atol=0.0):
    np.testing.assert_allclose(ours, np.asarray(theirs, dtype=float), rtol=1e-12, atol=atol)


# the residuals and the accuracy estimate are differences of numbers near 1: equal to the
# rounding of those (their last bits vary with the LAPACK thread count between processes)
RESIDUAL = 1e-13


def test_position_quantities_are_the_workflow_tables(solved):
    tables, eq = solved
    position = tables["position"]
    _same(eq.px(position["x"]), position["px"])
    _same(eq.v2_given_x(position["x"]), position["v2_given_x"])


def test_joint_distribution_is_the_workflow_table(solved):
    tables, eq = solved
    joint = tables["distribution"]
    positive = joint["x"] > 0.0  # at x = v = 0 the table has NaN, the API inf
    _same(eq.pxv(joint["x"][positive], joint["v"][positive]), joint["pxv"][positive])
    at_floor = (joint["x"] == 0.0) & (joint["v"] != 0.0)
    _same(eq.pxv(0.0, joint["v"][at_floor]), joint["pxv"][at_floor])


def test_speed_force_and_flight_quantities_are_the_workflow_tables(solved):
    tables, eq = solved
    _same(eq.p0v(tables["p0v"]["v"]), tables["p0v"]["p0v"])
    _same(eq.weight(tables["weight"]["F"]), tables["weight"]["w"])
    flights = tables["flight_time"]
    _same(eq.flight_rate_density(flights["t"]), flights["rate_density"])
    _same(eq.flight_time_density(flights["t"]), flights["density"])


def test_scalars_are_the_workflow_summary(solved):
    tables, eq = solved
    row = tables["summary"].iloc[0]
    for name in ("collision_rate", "mean_x", "delta_x", "mean_flight_time"):
        _same(getattr(eq, name), row[name])
    _same(eq.flight_time_second_moment, row["flight_time_second_moment"])
    _same(eq.accuracy, row["accuracy_estimate"], atol=RESIDUAL)
    summary = eq.summary()
    assert set(summary) == set(tables["summary"].columns)
    for name, value in summary.items():
        _same(value, row[name], atol=RESIDUAL if "residual" in name or "accuracy" in name else 0.0)
