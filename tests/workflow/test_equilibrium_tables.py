"""The solve rule is Equilibrium: a fresh Equilibrium(r) in the test process, with the settings
the rule's files record, against the tables the rule writes (results/solver/r{r}/) at the
first r of the small config, in a temporary copy of the repository (one solve job).  The rule
builds its tables with the same functions (``workflow.solver_tables``), so this checks that they are reproduced in another
process (the solve, w(F) and the quadratures are deterministic), and that the pointwise methods
(px, pxv, weight, ...) give the tables' rows."""

import numpy as np
import pandas as pd
import pytest
from workflow_support import SMALL, copy_repository, snakemake

import bouncing_ball as bb
from bouncing_ball.bins import linear_grid, log_bins, log_grid
from bouncing_ball.restitution import parse_restitution, restitution_label
from bouncing_ball.workflow import solver_tables
from bouncing_ball.workflow.io import read_table

R = SMALL["restitution"][0]
LABEL = restitution_label(parse_restitution(R))
TABLES = ("p0v", "summary", "flight_time", "return_speed", "position", "distribution", "weight")


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    directory = copy_repository(tmp_path_factory.mktemp("solve"), SMALL)
    targets = [f"results/solver/r{LABEL}/{name}.parquet" for name in TABLES]
    result = snakemake(directory, *targets)
    assert result.returncode == 0, result.stderr[-3000:]
    read = {name: read_table(directory / target) for name, target in zip(TABLES, targets)}
    tables = {name: table for name, (table, _) in read.items()}
    provenance = read["summary"][1]
    assert provenance["quadrature_step"] == SMALL["solver"]["quadrature_step"]
    assert provenance["weight_panel_nodes"] == SMALL["solver"]["weight_panel_nodes"]
    equilibrium = bb.Equilibrium(
        R,
        quadrature_step=provenance["quadrature_step"],
        weight_panel_nodes=provenance["weight_panel_nodes"],
    )
    tables["provenance"] = provenance
    return tables, equilibrium


def _same(ours, theirs, atol=0.0):
    np.testing.assert_allclose(ours, np.asarray(theirs, dtype=float), rtol=1e-12, atol=atol)


# the residuals, the accuracy estimate and (at r = 1/2, where w(F) is smooth) the interpolation
# error of w are differences of numbers near 1: equal to the rounding of those (their last bits
# vary with the LAPACK thread count between processes)
RESIDUAL = 1e-13
ROUNDING_COLUMNS = ("residual", "accuracy", "interpolation_error")


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
    summary = solver_tables.summary(eq)
    assert set(summary) == set(tables["summary"].columns)
    for name, value in summary.items():
        rounding = any(part in name for part in ROUNDING_COLUMNS)
        _same(value, row[name], atol=RESIDUAL if rounding else 0.0)


def test_the_rule_tables_are_the_table_methods_with_its_settings(solved):
    """Every frame the rule writes is the table function's (``workflow.solver_tables``) for the grids its provenance records,
    column by column to rtol 1e-12 (the summary's residual and accuracy columns, above, and the
    return-speed law to their rounding), and the solution reaches the highest speed it
    records."""
    tables, eq = solved
    settings, provenance = tables["provenance"]["settings"], tables["provenance"]
    assert float(eq.solution.speeds[-1]) == provenance["highest_speed"]
    joint, _ = solver_tables.distribution_table(
        eq, settings["positions"], linear_grid(settings["speeds"])
    )
    ours = {
        "p0v": solver_tables.p0v_table(eq, log_grid(settings["output_speeds"])),
        "flight_time": solver_tables.flight_time_table(eq, log_grid(settings["flight_times"])),
        "return_speed": solver_tables.return_speed_table(eq, log_bins(provenance["speed_bins"])),
        "position": solver_tables.position_table(eq, log_grid(settings["position_grid"])),
        "distribution": joint,
        "weight": solver_tables.weight_table(eq, log_grid(settings["forces"])),
    }
    for name, table in ours.items():
        # the return-speed probabilities are differences of the cumulative law, of order 1: the
        # far bins' are its rounding (-5.6e-13 at r = 1/2), equal to the rounding of the law
        atol = RESIDUAL if name == "return_speed" else 0.0
        pd.testing.assert_frame_equal(
            table, tables[name], check_exact=False, rtol=1e-12, atol=atol, obj=name
        )
    assert list(solver_tables.summary(eq)) == list(tables["summary"].columns)
