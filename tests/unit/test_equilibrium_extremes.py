"""The public methods at the ends of their domains: the asymptotic forms where the numerics end
(P(0, v) ~ A v^-beta, the small-x law of P(x)), <v^2>_x where P(x) underflows, the return-speed
law at huge speeds, the refusals at the bounds, and elementwise independence.  Each against the
exact solutions of r = 1/2 and 1/3, eqs. (P(0,v)), (P(x)2), with tolerances from the term the
asymptotic form leaves out."""

import numpy as np
import pytest
from workflow_support import REPOSITORY

from bouncing_ball import Equilibrium, ExactEquilibrium, distribution, exact, solver
from bouncing_ball.distribution import LARGEST_POSITION, SMALLEST_POSITION
from bouncing_ball.workflow.config import read_yaml

EXACT = ("1/2", "1/3")
ROUNDING = 1e-12  # exp of a logarithm near -700 (about 700 eps)


@pytest.fixture(scope="module", params=EXACT)
def pair(request):
    return request.param, Equilibrium(request.param), ExactEquilibrium(request.param)


@pytest.mark.parametrize("v", [1e-30, 1e-100, 1e-200])
def test_p0v_follows_its_power_law_below_the_lowest_node(pair, v):
    """Below the lowest node u_0, A v^-beta with A matched at u_0: its error is that at u_0
    plus the next term of P(0, v) there, q u_0 (e^(-q v) of the exact solutions)."""
    label, numerical, closed = pair
    u0 = numerical.solution.speeds[0]
    at_node = abs(numerical.p0v(u0) / closed.p0v(u0) - 1.0)
    tolerance = at_node + numerical.q * u0 + ROUNDING
    assert abs(numerical.p0v(v) / closed.p0v(v) - 1.0) <= tolerance


@pytest.mark.parametrize("equilibrium", [Equilibrium, ExactEquilibrium])
def test_p0v_refuses_speeds_where_it_leaves_the_range_of_doubles(equilibrium):
    eq = equilibrium("1/3")
    # A v^(-3/2) = 1.8e308 e^-10 there
    largest = np.finfo(float).max * np.exp(-10.0)
    bound = (exact.normalization_constant("1/3") / largest) ** (2.0 / 3.0)
    assert eq.smallest_speed == pytest.approx(bound, rel=1e-8)
    assert np.isfinite(eq.p0v(eq.smallest_speed))
    with pytest.raises(ValueError, match=r"v = 1e-300 is below smallest_speed"):
        eq.p0v([1.0, 1e-300])
    assert eq.p0v(0.0) == np.inf


@pytest.mark.parametrize("x", [1e-30, 1e-100, 1e-300])
def test_px_and_v2_given_x_follow_the_small_x_law(pair, x):
    """The F integral reaches F ~ 100 / x through the power law of w(F) above F_max, matched
    in value and slope there: its first neglected term is relative F_max^(-2/3)."""
    label, numerical, closed = pair
    tolerance = numerical.weight_function.largest_force ** (-2.0 / 3.0)
    assert numerical.px(x) == pytest.approx(closed.px(x), rel=tolerance)
    assert numerical.v2_given_x(x) == pytest.approx(closed.v2_given_x(x), rel=tolerance)


def test_v2_given_x_is_finite_where_px_underflows(pair):
    """At x = 1e6, P(x) ~ e^(-(2x/3)^(1/2)) underflows; <v^2>_x -> (6 x)^(1/2) (1 + O(x^-1/2))
    is the ratio of the two F integrals, taken in logs."""
    label, numerical, closed = pair
    x = 1e6
    assert numerical.px(x) == 0.0 and closed.px(x) == 0.0
    expected = closed.v2_given_x(x)
    assert expected == pytest.approx(np.sqrt(6.0 * x), rel=3.0 / np.sqrt(6.0 * x))
    assert numerical.v2_given_x(x) == pytest.approx(expected, rel=solver.ACCURACY_TARGET)


@pytest.mark.parametrize("r", [0.3, 0.6])
def test_v2_given_x_is_finite_at_large_x_at_any_r(r):
    eq = Equilibrium(r)
    values = eq.v2_given_x([1e3, 1e6, LARGEST_POSITION])
    assert np.all(np.isfinite(values)) and np.all(np.diff(values) > 0.0)


def test_return_speed_density_is_never_nan():
    eq = ExactEquilibrium("1/2")
    values = eq.return_speed_density([1.0, 1e155, 1e200, 1e300], 1.0)
    assert values[0] == pytest.approx(0.429368, abs=1e-6)
    np.testing.assert_array_equal(values[1:], 0.0)  # e^(-(3/4) v) underflows
    at_huge_u = eq.return_speed_density([1.0, 1e300], 1e300)
    assert at_huge_u[0] == 0.0
    # v G_g(v, v) -> 0.345494149471 v^(-1/2) at large v (a Gaussian of width ~v^(1/2))
    assert at_huge_u[1] * 1e150 == pytest.approx(0.345494149471, rel=1e-9)


@pytest.mark.parametrize("name", ["px", "v2_given_x"])
@pytest.mark.parametrize("x", [1e-310, 2e12])
def test_heights_outside_the_domain_are_refused_naming_x(pair, name, x):
    label, numerical, closed = pair
    for eq in (numerical, closed):
        with pytest.raises(ValueError, match=r"x = .* is outside the heights computed"):
            getattr(eq, name)([1.0, x])


def test_one_value_never_changes_anothers_result(pair):
    label, numerical, _ = pair
    extremes = [1e-300, 1e-30, 1.0, 1e6, LARGEST_POSITION]
    for method in (numerical.px, numerical.v2_given_x):
        together = method(extremes)
        alone = [method(x) for x in extremes]
        np.testing.assert_array_equal(together, alone)
    speeds = [numerical.smallest_speed, 1e-30, 1e-12, 1.0, 1e3]
    np.testing.assert_array_equal(numerical.p0v(speeds), [numerical.p0v(v) for v in speeds])


def test_the_schema_bounds_are_the_librarys():
    defs = read_yaml(REPOSITORY / "workflow/schemas/config.schema.yaml")
    bounds = defs["$defs"]["position_grid"]["allOf"][1]["properties"]
    assert bounds["min"]["minimum"] == SMALLEST_POSITION
    assert bounds["max"]["maximum"] == LARGEST_POSITION
    assert defs["$defs"]["positions"]["items"]["anyOf"][1]["maximum"] == LARGEST_POSITION
    velocities = defs["$defs"]["velocity_grid"]["allOf"][1]["properties"]
    assert velocities["max"]["maximum"] == -velocities["min"]["minimum"]
    assert velocities["max"]["maximum"] == distribution.LARGEST_VELOCITY
    forces = defs["$defs"]["force_grid"]["allOf"][1]["properties"]
    assert forces["min"]["minimum"] == distribution.SMALLEST_WEIGHT_FORCE
    speeds = defs["properties"]["solver"]["properties"]["output_speeds"]["allOf"][1]
    assert speeds["properties"]["min"]["minimum"] == solver.SMALLEST_OUTPUT_SPEED
    # every r the solver answers writes a finite P(0, v) there (beta < 5/2)
    assert exact.normalization_constant("1/3") * solver.SMALLEST_OUTPUT_SPEED**-2.5 < 1e251


@pytest.mark.parametrize("force", [1e-3, 1e10, 1e100, 1e300, 1.7e308])
def test_weight_follows_the_exact_solution_to_its_largest_forces(pair, force):
    """Above F_max, w(F) is its power law matched in value and slope at F_max: the first
    neglected term is relative F_max^(-2/3); below, the interpolation error."""
    label, numerical, closed = pair
    weight = numerical.weight_function
    tolerance = weight.largest_force ** (-2.0 / 3.0) + 10.0 * weight.interpolation_error
    assert numerical.weight(force) == pytest.approx(closed.weight(force), rel=tolerance)


@pytest.mark.parametrize("force", [5e-324, 1e-300, 1e-10])
def test_weight_underflows_to_zero_at_tiny_forces(pair, force):
    """w(F) < e^(-S/F) with S = 1/12: below the smallest double."""
    label, numerical, closed = pair
    with np.errstate(over="raise", invalid="raise"):
        assert numerical.weight(force) == 0.0 and closed.weight(force) == 0.0


def test_weight_refuses_forces_where_it_exceeds_the_largest_double():
    eq = Equilibrium(0.9)  # S < 0: w grows like e^(|S|/F) as F -> 0
    assert np.isfinite(eq.weight(eq.smallest_force))
    assert eq.weight(eq.smallest_force) > np.finfo(float).max * np.exp(-10.5)
    with pytest.raises(ValueError, match=r"F = 1e-300 is below smallest_force"):
        eq.weight([1.0, 1e-300])
    assert Equilibrium(0.6).smallest_force == 0.0
    # the config's solver.forces bound lies above it at every r of the range (the largest, 0.9)
    assert eq.smallest_force < distribution.SMALLEST_WEIGHT_FORCE


@pytest.mark.parametrize("x", [1e4, 1e5])
def test_pxv_at_large_heights_matches_the_exact_solution(pair, x):
    """Both F integrals span the saddle of e^(-1/(6F) - F x) (beyond the fixed ends there);
    good to DISTRIBUTION_NOISE of the largest P(x, v) at that x."""
    label, numerical, closed = pair
    speeds = np.array([-100.0, -1.0, 0.0, 1.0, 100.0])
    expected = closed.pxv(x, speeds)
    assert np.all(expected >= 0.0)
    scale = distribution.DISTRIBUTION_NOISE * np.max(expected)
    np.testing.assert_allclose(numerical.pxv(x, speeds), expected, rtol=0.0, atol=scale)


def test_pxv_is_zero_beyond_the_largest_velocity_and_refuses_heights_outside(pair):
    label, numerical, closed = pair
    huge = distribution.LARGEST_VELOCITY
    for eq in (numerical, closed):
        with np.errstate(over="raise", invalid="raise"):
            values = eq.pxv([0.0, 1e-300, 1.0, LARGEST_POSITION], [[-1e300], [-2.0 * huge]])
            np.testing.assert_array_equal(values, 0.0)
            np.testing.assert_array_equal(eq.pxv([0.0, 1.0, LARGEST_POSITION], 1e300), 0.0)
            # at |v| = LARGEST_VELOCITY itself P(x, v) is computed, and already 0
            np.testing.assert_array_equal(eq.pxv([0.0, 1.0, 0.0], [-huge, -huge, huge]), 0.0)
        with pytest.raises(ValueError, match=r"x = 1e\+20 is outside the heights computed"):
            eq.pxv(1e20, -1.0)


def test_bin_averages_never_depend_on_the_other_bins(pair):
    label, numerical, _ = pair
    weight = numerical.weight_function
    lo, hi = np.array([0.0, 1e-30, 0.5, 1e6]), np.array([1e-3, 1e-29, 1.0, 1.1e6])
    for average in (
        distribution.position_bin_average,
        distribution.speed_squared_given_position_bin_average,
    ):
        together = average(lo, hi, weight)
        alone = [average(a, b, weight) for a, b in zip(lo, hi)]
        np.testing.assert_array_equal(together, np.ravel(alone))


def test_bin_averages_match_the_exact_solution_at_the_extremes(pair):
    """<v^2> over a bin at x = 1e6 is a ratio of two integrals that underflow: in logs."""
    label, numerical, _ = pair
    weight = numerical.weight_function
    lo, hi = np.array([0.0, 1e-300, 1e-3, 1e6]), np.array([1e-3, 1e-3, 2e-3, 1.1e6])
    tolerance = weight.largest_force ** (-2.0 / 3.0)
    for average, exact_average in (
        (distribution.position_bin_average, exact.position_bin_average),
        (
            distribution.speed_squared_given_position_bin_average,
            exact.speed_squared_given_position_bin_average,
        ),
    ):
        expected = exact_average(lo, hi, label)
        assert np.all(np.isfinite(expected))
        positive = expected > 0.0
        np.testing.assert_allclose(
            average(lo, hi, weight)[positive], expected[positive], rtol=tolerance
        )
    with pytest.raises(ValueError, match=r"lo = 1e-310: bins need lo = 0"):
        distribution.position_bin_average(1e-310, 1.0, weight)


def test_pxv_never_depends_on_the_other_values(pair):
    label, numerical, closed = pair
    speeds = [-1e300, -50.0, -1.0, 0.0, 0.5, 1e300]
    for eq in (numerical, closed):
        together = eq.pxv(1.0, speeds)
        np.testing.assert_array_equal(together, [eq.pxv(1.0, v) for v in speeds])
