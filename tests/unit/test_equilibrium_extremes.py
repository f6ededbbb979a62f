"""The public methods at the ends of their domains: the asymptotic forms where the numerics end
(P(0, v) ~ A v^-beta, the small-x law of P(x)), <v^2>_x where P(x) underflows, the return-speed
law at huge speeds, the refusals at the bounds, and elementwise independence.  Each against the
exact solutions of r = 1/2 and 1/3, eqs. (P(0,v)), (P(x)2), with tolerances from the term the
asymptotic form leaves out."""

import numpy as np
import pytest
from workflow_support import REPOSITORY

from bouncing_ball import Equilibrium, ExactEquilibrium, exact, solver
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
    speeds = defs["properties"]["solver"]["properties"]["output_speeds"]["allOf"][1]
    assert speeds["properties"]["min"]["minimum"] == solver.SMALLEST_OUTPUT_SPEED
    # every r the solver answers writes a finite P(0, v) there (beta < 5/2)
    assert exact.normalization_constant("1/3") * solver.SMALLEST_OUTPUT_SPEED**-2.5 < 1e251
