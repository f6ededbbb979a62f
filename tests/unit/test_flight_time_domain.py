"""nu(T) and rho(T) over the whole domain of T: each T on its own, eq. (short) at the shortest
flights against the exact r = 1/2 and 1/3 solutions, exactly 0 beyond the underflow at bounded
cost, and the solve rule's tables refusing infinities."""

import functools
import tracemalloc

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bouncing_ball import Equilibrium, ExactEquilibrium, exact
from bouncing_ball import flight_time as ft
from bouncing_ball.workflow import solver_tables

EXACT = ["1/2", "1/3"]
# the extremes of eq. (short): the switch to it, far below, the smallest normal double and the
# smallest double
SHORTEST = [ft.SHORT_FLIGHT_TIME, 1e-100, 1e-300, 5e-324]
LONGEST = [1e12, 1e20, 1e300]
# nu(T) from the solver's P(0, u) against the exact solutions: the quadrature's ~1e-9
SOLVER_TOLERANCE = 1e-9
# the exact quadrature of eq. (rate) (epsrel 1e-12 and rounding in f(T | u))
QUADRATURE_TOLERANCE = 1e-11


@pytest.fixture(scope="module", params=EXACT)
def pair(request):
    return Equilibrium(request.param), ExactEquilibrium(request.param)


def _short_law_coefficients(beta, q, step=0.02):
    """C_beta and c1 of nu(T) = A C_beta T^(-beta/2) (1 + c1 T^(1/2) + O(T)) for
    P(0, u) = A u^-beta e^(-q u) (eq. (P(0,v))), from the gravity-free law alone.

    With u = T^(1/2) s, v = T^(1/2) w, p_0(T, v | u) dv = T^-1 p_0(1, w | s) dw, and to first
    order in T^(1/2) gravity's factor e^((u + v)/2 - T/4) (eq. (0g)) is 1 + T^(1/2) (s + w)/2
    and e^(-q u) is 1 - q T^(1/2) s, so ::

        C_beta = int ds s^(1-beta) f_0(1 | s),
        c1 C_beta = int ds s^(1-beta) [(1/2 - q) s f_0(1 | s) + (1/2) int dw w p_0(1, w | s)].

    The trapezoidal rule in ln s and ln w (exponentially convergent) over e^-30 .. e^3."""
    x = np.arange(-30.0, 3.0 + 0.5 * step, step)
    s, w = np.exp(x)[:, None], np.exp(x)[None, :]
    p = ft.free_first_passage_density(1.0, w, s)
    f0 = step * (p * w).sum(axis=1)
    mean_w = step * (p * w * w).sum(axis=1)
    s = s[:, 0]
    constant = step * np.sum(s ** (2.0 - beta) * f0)
    first = step * np.sum((0.5 - q) * s ** (3.0 - beta) * f0 + 0.5 * s ** (2.0 - beta) * mean_w)
    return constant, first / constant


@pytest.fixture(scope="module", params=EXACT)
def short_law(request):
    """(ExactEquilibrium, Equilibrium, A C_beta, c1) with A of eq. (constants)."""
    eq = ExactEquilibrium(request.param)
    constant, first = _short_law_coefficients(eq.beta, eq.q)
    amplitude = exact.normalization_constant(request.param) * constant
    return eq, Equilibrium(request.param), amplitude, first


# --- one T never changes another's value -----------------------------------------------------


def _single_values(eq, times):
    return np.array([eq.flight_rate_density(t) for t in times]), np.array(
        [eq.flight_time_density(t) for t in times]
    )


@pytest.mark.parametrize("which", ["solver", "exact"])
def test_a_tiny_or_a_huge_flight_time_leaves_the_others_alone(pair, which):
    """[1, 0.5, 1e-240, 1e12] together give what each gives alone, in every method."""
    eq = pair[0] if which == "solver" else pair[1]
    times = np.array([1.0, 0.5, 1e-240, 1e12])
    rate, density = _single_values(eq, times)
    assert np.all(np.isfinite(rate)) and np.all(np.isfinite(density))
    np.testing.assert_allclose(eq.flight_rate_density(times), rate, rtol=1e-13, atol=0.0)
    np.testing.assert_allclose(eq.flight_time_density(times), density, rtol=1e-13, atol=0.0)
    if which == "solver":
        table = solver_tables.flight_time_table(eq, times)
        np.testing.assert_allclose(table["rate_density"], rate, rtol=1e-13, atol=0.0)
        np.testing.assert_allclose(table["density"], density, rtol=1e-13, atol=0.0)
    assert density[0] == pytest.approx(0.1968319839929876 if eq.r == 0.5 else 0.14509449, 1e-7)


@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.lists(st.floats(-323.0, 20.0), min_size=1, max_size=6))
def test_every_flight_time_is_evaluated_on_its_own(log_times):
    """Any array of T from 1e-323 to 1e20: each value as it is alone."""
    eq = Equilibrium("1/2")
    times = 10.0 ** np.array(log_times)
    alone = np.array([eq.flight_rate_density(t) for t in times])
    together = eq.flight_rate_density(times)
    assert np.all(np.isfinite(together))
    np.testing.assert_allclose(together, alone, rtol=1e-13, atol=0.0)


# --- the shortest flights: eq. (short) --------------------------------------------------------


def test_the_short_law_constant_is_the_gravity_free_one(short_law):
    """C_beta of ``short_time_constant`` (hypergeometric form) = int ds s^(1-beta) f_0(1 | s)."""
    eq, _, amplitude, _ = short_law
    constant = amplitude / exact.normalization_constant(eq.restitution)
    assert ft.short_time_constant(eq.beta) == pytest.approx(constant, rel=1e-12, abs=0.0)


@pytest.mark.parametrize("t", [1e-8, 1e-12, 1e-20, ft.SHORT_FLIGHT_TIME])
def test_the_quadrature_meets_the_short_law_with_its_first_correction(short_law, t):
    """The exact P(0, u) put into eq. (rate) by adaptive quadrature: A C_beta T^(-beta/2)
    (1 + c1 T^(1/2)) up to the second order, T (its coefficient is of order 1: the factors
    expanded above, to second order)."""
    eq, _, amplitude, first = short_law
    nu = eq._direct_flight_rate(np.array([t]))[0]
    relative = nu / (amplitude * t ** (-0.5 * eq.beta)) - 1.0 - first * np.sqrt(t)
    assert abs(relative) <= t + QUADRATURE_TOLERANCE


@pytest.mark.parametrize("t", SHORTEST)
def test_the_shortest_flights_follow_the_exact_short_law(short_law, t):
    """At 1e-30, 1e-100, 1e-300 and 5e-324: nu(T) = A C_beta T^(-beta/2) to the first
    correction |c1| T^(1/2) (1e-16 at most), from the exact solution and from the solver."""
    eq, solver, amplitude, first = short_law
    expected = amplitude * t ** (-0.5 * eq.beta)
    tolerance = abs(first) * np.sqrt(t)
    assert eq.flight_rate_density(t) == pytest.approx(
        expected, rel=tolerance + QUADRATURE_TOLERANCE, abs=0.0
    )
    assert solver.flight_rate_density(t) == pytest.approx(
        expected, rel=tolerance + SOLVER_TOLERANCE, abs=0.0
    )
    assert eq.flight_time_density(t) == pytest.approx(
        expected / eq.collision_rate, rel=tolerance + QUADRATURE_TOLERANCE, abs=0.0
    )


def test_the_switch_to_the_short_law_is_continuous(short_law):
    """Either side of SHORT_FLIGHT_TIME: quadrature and eq. (short) within |c1| T^(1/2)."""
    eq, solver, _, first = short_law
    edge = ft.SHORT_FLIGHT_TIME
    for which, tolerance in ((eq, QUADRATURE_TOLERANCE), (solver, SOLVER_TOLERANCE)):
        below, above = which.flight_rate_density([edge * (1.0 - 1e-12), edge])
        assert below == pytest.approx(above, rel=abs(first) * np.sqrt(edge) + tolerance)


def test_below_the_largest_double_nu_refuses_naming_the_bound():
    """At r = 0.02 (beta = 2.4) nu(T) ~ T^-1.2 exceeds the largest double below T ~ 2e-258:
    a ValueError naming T, r and the bound, not inf (nor an inf in the table)."""
    eq = Equilibrium(0.02)
    shortest = ft.shortest_flight_time(eq._short_flight_amplitude(), eq.beta)
    assert 1e-259 < shortest < 1e-257
    assert np.isfinite(eq.flight_rate_density(1.01 * shortest))
    for method, name in (
        (eq.flight_rate_density, "T"),
        (eq.flight_time_density, "T"),
        (functools.partial(solver_tables.flight_time_table, eq), "times"),
    ):
        with pytest.raises(ValueError, match=rf"^{name} must be 0 or >= 2.4\de-258 at r = 0.02"):
            method([1.0, 1e-300])


# --- the longest flights: 0 beyond the underflow ------------------------------------------------


@pytest.mark.parametrize("r", ["1/2", 0.9])
def test_the_longest_flights_give_zero_at_bounded_cost(r):
    """nu(T) decays like e^(-kappa T) (eqs. (long1), (long2)): at 1e12, 1e20 and 1e300 it is
    exactly 0, computed in a few MB (the rule's nodes grow like T^(1/2))."""
    eq = Equilibrium(r)
    tracemalloc.start()
    try:
        rate = eq.flight_rate_density(LONGEST)
        density = eq.flight_time_density(LONGEST)
        table = solver_tables.flight_time_table(eq, LONGEST)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert np.all(rate == 0.0) and np.all(density == 0.0)
    assert np.all(table[["density", "rate_density", "time_weighted_density"]].to_numpy() == 0.0)
    assert peak < 64 * 2**20


def test_the_underflow_sets_in_where_the_long_flight_law_underflows():
    """At r = 1/2: nu(3000) follows eq. (long1) (e^-562, relative correction O(1/T)); beyond
    underflow_flight_time nu is exactly 0, and so is it where eq. (long1) is below the
    smallest normal double."""
    eq = Equilibrium("1/2")
    long_law = ft.long_flight_rate_density(eq.solution, np.array([3000.0, 4500.0]))
    assert eq.flight_rate_density(3000.0) == pytest.approx(long_law[0], rel=0.01)
    assert long_law[1] < np.finfo(float).tiny and eq.flight_rate_density(4500.0) == 0.0
    beyond = ft.underflow_flight_time(eq.r) * np.array([1.0 + 1e-12, 2.0])
    assert np.all(eq.flight_rate_density(beyond) == 0.0)


# --- the solve rule's checks --------------------------------------------------------------------


def test_the_solve_checks_refuse_an_infinity_naming_table_and_column():
    eq = Equilibrium("1/2")
    table = solver_tables.flight_time_table(eq, [1.0, 2.0, 3.0])
    solver_tables.check(eq, {"flight_time": table})
    table.loc[2, "density"] = -np.inf
    with pytest.raises(ValueError, match=r"r = 0.5: .*flight_time: 1 of 3 density are infinite"):
        solver_tables.check(eq, {"flight_time": table})
