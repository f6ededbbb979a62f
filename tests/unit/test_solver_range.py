"""The solver and the distribution over their documented range: what they refuse, by name, and
the checks every table of rule solve passes before it is written."""

from fractions import Fraction

import numpy as np
import pandas as pd
import pytest
from distribution_support import check_position_moments

from bouncing_ball import distribution, exact, kernel, solver
from bouncing_ball.restitution import (
    DISTRIBUTION_RESTITUTION_RANGE,
    SOLVER_RESTITUTION_RANGE,
    check_distribution_range,
    in_range,
)
from bouncing_ball.workflow import solver_tables

LOW, HIGH = DISTRIBUTION_RESTITUTION_RANGE


# ---- the range of r, its bounds read as exact decimals


def test_the_bounds_of_a_range_are_exact_decimals():
    """0.02 is 1/50, whose float lies a little above 1/50: the exact r = 1/50 is in the range
    that starts at 0.02, not refused as outside it."""
    assert in_range(Fraction(1, 50), SOLVER_RESTITUTION_RANGE)
    assert not in_range(Fraction(1, 50) - Fraction(1, 10**12), SOLVER_RESTITUTION_RANGE)
    for bound in ("1/50", "9/10", 0.02, LOW, HIGH):
        assert check_distribution_range(bound) == Fraction(str(bound))


@pytest.mark.parametrize("r", [0.91, 0.95, 0.99, "199/200", 0.998, 0.999, "999/1000"])
def test_a_run_near_one_inside_the_range_of_the_whole_distribution_is_accepted(r):
    """Up to r = 0.999 w(F) is taken along the ray of P(0, v) (bouncing_ball.distribution), and
    P(x), P(x, v) meet 1e-8 (tests/numerical/test_distribution_any_r.py)."""
    assert check_distribution_range(r, "restitution[0]") == Fraction(str(r))


@pytest.mark.parametrize("r", [0.015, "1/100", 0.9991, "1999/2000", 0.9999])
def test_a_run_outside_the_range_of_the_whole_distribution_is_refused(r):
    """Every r of a run is solved by rule solve, whose P(x) and P(x, v) hold to 1e-8 only in
    DISTRIBUTION_RESTITUTION_RANGE: outside, the refusal names the key, both ranges and why."""
    with pytest.raises(ValueError, match=rf"restitution\[0\]: r = .* {LOW} <= r <= {HIGH}.*0.9999"):
        check_distribution_range(r, "restitution[0]")


@pytest.mark.parametrize("r", [0.9995, 0.9999, 0.015])
def test_the_distribution_refuses_r_where_it_misses_its_accuracy(r):
    """Outside DISTRIBUTION_RESTITUTION_RANGE w(F), P(x) and P(x, v) are refused at once, with
    the range."""
    with pytest.raises(ValueError, match=rf"{LOW} <= r <= {HIGH}"):
        distribution.outgoing_speed_solution(r)


def test_the_lower_bound_of_the_solver_is_solved():
    """r = 1/50, given as the fraction string the pipeline accepts, is solved (to its energy
    balance)."""
    solution = solver.solve_outgoing_speed_density("1/50")
    assert solution.restitution == 0.02
    assert abs(solver.energy_balance_residual(solution)) < 1e-8


# ---- the library refuses what it cannot compute


def test_a_quadrature_step_that_wrecks_the_accuracy_is_refused():
    """step = 5 gave <x> = 5.21 (exact 6) and Delta x NaN with only a RuntimeWarning."""
    with pytest.raises(ValueError, match=r"step = 5"):
        solver.solve_outgoing_speed_density(0.5, step=5)
    with pytest.raises(ValueError, match=r"step = -0.1"):
        solver.solve_outgoing_speed_density(0.5, step=-0.1)


@pytest.mark.parametrize(
    "nodes, name",
    [({"highest_speed": 1.0}, "highest_speed"), ({"lowest_speed": 1e-3}, "lowest_speed")],
)
def test_a_grid_that_cuts_the_density_short_is_refused(nodes, name):
    """highest_speed = 1 gave <x> = 0.34 (exact 6)."""
    with pytest.raises(ValueError, match=name):
        solver.solve_outgoing_speed_density(0.5, **nodes)


def test_restitution_as_a_fraction_string():
    """The public entry points take r as the pipeline does: "1/3" is 1/3."""
    from_string = solver.solve_outgoing_speed_density("1/3")
    from_float = solver.solve_outgoing_speed_density(1.0 / 3.0)
    assert np.array_equal(from_string.density, from_float.density)
    assert exact.normalization_constant("1/3") == exact.normalization_constant(1.0 / 3.0)
    assert distribution.predicted_exponents("1/3") == distribution.predicted_exponents(1.0 / 3.0)


def test_negative_speeds_are_refused():
    """exact.outgoing_speed_density(-1, 0.5) gave -0.906; the incoming side is eq. (bc)."""
    with pytest.raises(ValueError, match="v: P\\(0, v\\) is the density of outgoing speeds"):
        exact.outgoing_speed_density(-1.0, 0.5)
    solution = solver.solve_outgoing_speed_density(0.5)
    with pytest.raises(ValueError, match="v: P\\(0, v\\) is the density of outgoing speeds"):
        solution.outgoing_speed_density(np.array([1.0, -1.0]))


@pytest.mark.parametrize(("x", "v"), [(1e-8, 2.0), (1e-9, 2.0), (1e-6, 6.0)])
def test_heights_below_the_reach_of_the_force_integral_take_the_near_wall_series(x, v):
    """exact.distribution(1e-8, 2, 1/2) gave -0.418 and distribution.distribution(1e-9, 2, ...)
    0.0509 (the true value is near P(0, 2) = 0.02256): there the F integral of eq. (fpsol)
    oscillates too fast on the outgoing side.  The F integral itself refuses, naming x; P(x, v)
    there is the near-wall series of eq. (fp), the exact P(x, v) on the rotated F ray to 1e-12;
    at v <= 0 the F integral converges and is computed."""
    with pytest.raises(ValueError, match=f"x = {x}: at v = {v}"):
        exact.distribution_by_force_integral(x, v, 0.5)
    with pytest.raises(ValueError, match=f"x = {x}: at v = {v}"):
        distribution.distribution_by_force_rule(x, [v], None)
    near_floor = exact.distribution(x, v, 0.5) / exact.distribution_on_ray(x, v, 0.5)
    assert abs(near_floor - 1.0) < 1e-12
    at_rest = exact.distribution(x, -0.5, 0.5)
    assert np.isfinite(at_rest) and at_rest > 0.0


def test_the_kernel_constants_have_one_home():
    """The complex continuation of the kernel uses kernel.py's rule, not a copy of it."""
    assert distribution.TAU_NODES is kernel.TAU_NODES
    assert distribution.KERNEL_TAIL is kernel.TAIL


# ---- the noise limit of w(F)


def test_the_smallest_force_is_not_a_lone_accurate_point(monkeypatch):
    """Near r = 1 a lone F far below the noise limit passed the rounding check (w(2e-4) at
    r = 0.95), the bisection settled there and the interpolation took NaN nodes above it.  With
    a stand-in check that passes at every F below 5e-4 and above 3e-3 only, the smallest force
    is 3e-3 (to the factor 10^(1/8) of the search)."""

    def accurate(density, force):
        return bool(force >= 3e-3 or 1e-5 < force < 5e-4)

    monkeypatch.setattr(distribution.interpolated_weight, "_accurate", accurate)
    smallest = distribution._smallest_force(None, 2e-6)
    assert 3e-3 <= smallest <= 3e-3 * 10.0 ** (1.0 / 8.0)


# ---- the checks of rule solve's tables


def _passing_tables():
    """A summary row and tables that pass every check (values of the r = 1/2 solution)."""
    predicted = distribution.predicted_exponents(0.5)
    summary = {
        "r": 0.5,
        "mean_x": 6.0,
        "delta_x": 108.0**0.5,
        "collision_rate": 1.0 / 3.0,
        "accuracy_estimate": 2e-11,
        "highest_speed": 65.0,
        "position_normalization": 1.0 + 1e-13,
        "mean_x_from_position": 6.0 * (1.0 + 1e-12),
        "delta_x_from_position": 108.0**0.5,
        "large_x_window_lo": 384.0,
        "large_x_window_hi": 33750.0,
    }
    for key, value in predicted.items():
        summary[f"{key}_measured"], summary[f"{key}_predicted"] = value, value
    summary["small_x_power_measured"] = -0.06  # the log at r = 1/2
    tables = {
        "p0v": pd.DataFrame({"v": [0.1, 1.0], "p0v": [3.0, 0.12]}),
        "flight_time": pd.DataFrame({"t": [1.0], "density": [0.1], "rate_density": [0.03]}),
        "position": pd.DataFrame({"x": [1e-3, 1.0], "px": [0.5, 0.2], "v2_given_x": [1.0, 2.0]}),
        "distribution": pd.DataFrame(
            {"x": [0.0, 0.0, 0.1, 0.1], "v": [0.0, 1.0, 0.0, 6.0], "pxv": [np.nan, 0.1, 0.2, 1e-9]}
        ),
        "weight": pd.DataFrame({"F": [1.0], "w": [0.1], "log_w": [-2.3]}),
        "return_speed": pd.DataFrame(
            {"u_lo": [1.0, 70.0], "u_hi": [2.0, 80.0], "probability": [0.5, np.nan]}
        ),
    }
    return summary, tables


def test_tables_that_hold_pass():
    """P(0, 0) (NaN, undefined) and the log correction at r = 1/2 are no defects."""
    summary, tables = _passing_tables()
    assert solver_tables.solve_table_defects(summary, tables) == []
    solver_tables.check_solve_tables("0.5", summary, tables)


def test_nan_in_a_table_is_an_error_naming_r_and_the_table():
    """At r = 0.95 every P(x) was NaN and the job succeeded."""
    summary, tables = _passing_tables()
    tables["position"]["px"] = np.nan
    summary["position_normalization"] = np.nan
    with pytest.raises(ValueError, match=r"r = 0.95: .*position: 2 of 2 px are NaN") as error:
        solver_tables.check_solve_tables("0.95", summary, tables)
    assert "summary: position_normalization is NaN" in str(error.value)
    assert "int P dx" in str(error.value)


def test_the_flight_time_density_may_be_undefined_only_below_r_c():
    summary, tables = _passing_tables()
    tables["flight_time"]["density"] = np.nan
    assert solver_tables.solve_table_defects(summary, tables) == [
        "flight_time: 1 of 1 density are NaN"
    ]
    summary["collision_rate"] = np.inf
    assert solver_tables.solve_table_defects(summary, tables) == []


@pytest.mark.parametrize(
    "key, value, check",
    [
        ("position_normalization", 1.0 + 1.4e-4, "int P dx - 1 = 1.40e-04"),
        ("mean_x_from_position", 6.0 * (1.0 + 3e-8), "<x> from P(x)"),
        ("delta_x_from_position", 108.0**0.5 * (1.0 - 3e-8), "Delta x from P(x)"),
        ("large_x_power_measured", -0.25 + 0.02, "large_x_power measured -0.23"),
        ("large_x_rate_measured", 0.8165 * 1.01, "large_x_rate measured"),
        ("small_x_power_at_zero_speed_measured", -1.0 / 3.0 + 0.05, "small_x_power_at_zero"),
    ],
)
def test_a_table_off_its_accuracy_is_an_error_naming_the_check(key, value, check):
    """A table whose P(x) misses its normalisation or whose large-x power misses the theory's
    (as at r = 0.99, outside the distribution's range) is an error that names the check."""
    summary, tables = _passing_tables()
    summary[key] = value
    with pytest.raises(ValueError, match="r = 0.5: ") as error:
        solver_tables.check_solve_tables("0.5", summary, tables)
    assert check in str(error.value)


def test_the_moments_are_held_to_the_target_whatever_the_accuracy_estimate():
    """A solve that estimates its own error above the target is not excused by it."""
    summary, tables = _passing_tables()
    summary["position_normalization"] = 1.0 + 3e-7
    assert len(solver_tables.solve_table_defects(summary, tables)) == 1
    summary["accuracy_estimate"] = 1e-6
    summary["weight_interpolation_error"] = 1e-6
    assert len(solver_tables.solve_table_defects(summary, tables)) == 1


def test_the_large_x_power_is_checked_only_where_it_has_set_in():
    """Close to r = 1/2 the power law of P(x) sets in only for x >> (1 - q)^-4 / 6 (6e4 at
    r = 0.48), beyond the fit window: the power is not held to its tolerance there, the rate is."""
    summary, tables = _passing_tables()
    predicted = distribution.predicted_exponents(0.48)
    summary["r"] = 0.48
    for key, value in predicted.items():
        summary[f"{key}_measured"], summary[f"{key}_predicted"] = value, value
    summary["large_x_power_measured"] = predicted["large_x_power"] + 0.1
    assert solver_tables.solve_table_defects(summary, tables) == []
    summary["large_x_rate_measured"] = predicted["large_x_rate"] * 1.011
    assert len(solver_tables.solve_table_defects(summary, tables)) == 1


def test_the_coordinate_of_the_grid_inverts_beyond_the_overflow_of_its_exponential():
    """u(s) is computed without forming (b / 2) e^(s/2), which overflows above u ~ 2e6, where
    the grid of the far solution at r = 0.9999 reaches."""
    speeds = np.array([1e-12, 1.0, 1e6, 2.1e6, 5e6, 1e8])
    back = solver.speed_of_coordinate(solver.coordinate_of_speed(speeds))
    assert np.max(np.abs(back / speeds - 1.0)) < 1e-14


def test_position_moments_near_the_lower_end_of_the_range():
    """At r = 0.03 (beta = 2.4, near 5/2) int P dx and <x> meet their tolerances: the
    closed-form part of T(G) below the smallest speed keeps the linear term of psi_G(v), which
    matters at the large G that carry B(F) when beta nears 5/2."""
    check_position_moments(0.03)


def test_a_negative_density_beyond_the_noise_is_an_error():
    """P(x, v) from the F integral is accurate to 1e-10 of its largest value at that x: a
    negative value below that (-0.418 came out at x = 1e-8) is an error, one within it noise."""
    summary, tables = _passing_tables()
    tables["distribution"].loc[3, "pxv"] = -1e-11
    assert solver_tables.solve_table_defects(summary, tables) == []
    tables["distribution"].loc[3, "pxv"] = -1e-3
    assert solver_tables.solve_table_defects(summary, tables) == [
        "distribution: 1 of 4 pxv are negative beyond 1e-10 of the largest at their x "
        "(down to -0.001)"
    ]


def test_the_return_speed_law_may_be_undefined_only_above_the_highest_node():
    summary, tables = _passing_tables()
    summary["highest_speed"] = 75.0
    assert solver_tables.solve_table_defects(summary, tables) == [
        "return_speed: 1 of 2 probability are NaN"
    ]


def test_an_infinite_value_is_refused_and_an_overflow_bin_edge_is_not():
    summary, tables = _passing_tables()
    tables["return_speed"] = pd.DataFrame(
        {"u_lo": [1.0], "u_hi": [2.0], "v_lo": [50.0], "v_hi": [np.inf], "probability": [0.01]}
    )
    assert solver_tables.solve_table_defects(summary, tables) == []
    tables["return_speed"].loc[0, "probability"] = np.inf
    assert solver_tables.solve_table_defects(summary, tables) == [
        "return_speed: 1 of 1 probability are infinite"
    ]
