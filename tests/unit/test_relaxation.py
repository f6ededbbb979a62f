"""The relaxation of the bounce-speed chain: the solver's matrix read as the chain's transition
operator, its eigenvalues against exact identities, and the refusals below r_c."""

import math
from fractions import Fraction

import numpy as np
import pytest
from test_solver_range import _passing_tables

from bouncing_ball import Equilibrium, ExactEquilibrium, relaxation, solver
from bouncing_ball.asymptotics import CRITICAL_RESTITUTION, small_speed_exponent
from bouncing_ball.flight_time import mean_flight_time_given_speed
from bouncing_ball.time_relaxation import TIME_RELAXATION_COLUMNS
from bouncing_ball.workflow import solver_tables
from bouncing_ball.workflow.solver_tables import _relaxation_columns

TARGET = solver.ACCURACY_TARGET


@pytest.fixture(scope="module", params=[0.75, 0.9])
def isolated(request):
    return relaxation.bounce_chain_relaxation(request.param)


@pytest.mark.parametrize("r", [Fraction(1, 2), Fraction(1, 3), Fraction(9, 10)])
def test_the_scale_free_eigenvalue_is_one_at_beta_and_at_two(r):
    """Phi(b) = 1 is eq. (asym2): roots b = beta(r) and b = 2 (probability conserved)."""
    beta = small_speed_exponent(float(r))
    values = relaxation.scale_free_eigenvalue([beta, 2.0], float(r))
    assert np.max(np.abs(values - 1.0)) <= 1e-12


@pytest.mark.parametrize("r", [0.2, 0.5, 0.9, 0.9999])
def test_the_continuum_edge_is_the_minimum_between_beta_and_two(r):
    edge = relaxation.continuum_edge(r)
    beta = small_speed_exponent(r)
    grid = relaxation.scale_free_eigenvalue(np.linspace(beta, 2.0, 2001), r)
    # Phi is smooth at its minimum: the grid's spacing misses it by O(spacing^2)
    assert 0.0 < edge <= grid.min() <= edge * (1.0 + 1e-6)


@pytest.mark.parametrize("r", [0.5, 0.9])
def test_the_matrix_has_the_stationary_eigenvalue_one(r):
    """The continuum-limit eigenvalue 1 (the solver's) is the matrix's leading one."""
    assert abs(relaxation.bounce_chain_relaxation(r).leading_eigenvalue - 1.0) <= TARGET


def test_the_matrix_is_the_chain_transition_operator():
    """E[u_{n+1} | u_n = u] = r E[v | u] = r (E[T | u] - u): Ito on v + t over one flight
    (dv = -dt + noise), an identity of the exact chain.  The backward operator read off the
    solver's matrix, sum_i w_i p(u_i | u_j) u_i with p(u' | u) = r^-2 u' G_g(u' / r, u),
    gives it at every node from 1e-3 to 20."""
    r = 0.75
    _, _, u, log_scale, scaled = solver._scaled_operator(r, solver.DEFAULT_STEP, None, None)
    weights = solver.DEFAULT_STEP * solver._jacobian(u)
    with np.errstate(divide="ignore"):
        log_a = np.log(scaled) + log_scale[:, None] - log_scale[None, :]  # A = S scaled S^-1
    inside = np.flatnonzero((u >= 1e-3) & (u <= 20.0))
    # (Q h)_j = sum_i A_ij w_i u_i h_i / (w_j u_j), h = u
    backward = np.exp(log_a[:, inside]).T @ (weights * u * u) / (weights * u)[inside]
    expected = r * (mean_flight_time_given_speed(u[inside]) - u[inside])
    assert np.max(np.abs(backward / expected - 1.0)) <= TARGET


def test_at_one_half_the_relaxation_is_the_continuum_edge():
    """At r = 1/2 no eigenvalue stands above the continuum: the matrix's second eigenvalue is
    a discretised continuum, below lambda_c and creeping up to it as the lowest node goes down."""
    default = relaxation.bounce_chain_relaxation(0.5)
    deeper = relaxation.bounce_chain_relaxation(0.5, lowest_speed=1e-30)
    edge = default.continuum_edge
    assert not default.isolated and not deeper.isolated
    assert default.matrix_eigenvalue.real < deeper.matrix_eigenvalue.real < edge
    assert default.eigenvalue == edge == relaxation.continuum_edge("1/2")


def test_an_isolated_eigenvalue_is_real_and_converged(isolated):
    assert isolated.isolated and not isolated.oscillating
    assert isolated.matrix_eigenvalue.imag == 0.0 and isolated.eigenvalue > isolated.continuum_edge
    assert relaxation.relaxation_accuracy(isolated) <= TARGET
    assert isolated.correlation_bounces == pytest.approx(-1.0 / math.log(isolated.eigenvalue))


def test_the_second_eigenfunction_is_a_backward_eigenfunction():
    """h of the left eigenvector: sum_i w_i p(u_i | u_j) h(u_i) = lambda h(u_j)."""
    r = 0.9
    speeds, h, value = relaxation.second_eigenfunction(r)
    _, _, u, log_scale, scaled = solver._scaled_operator(r, solver.DEFAULT_STEP, None, None)
    weights = solver.DEFAULT_STEP * solver._jacobian(u)
    with np.errstate(divide="ignore"):
        a = np.exp(np.log(scaled) + log_scale[:, None] - log_scale[None, :])
    inside = np.flatnonzero((u >= 1e-3) & (u <= 20.0))
    backward = a[:, inside].T @ (weights * u * h) / (weights * u)[inside]
    assert np.max(np.abs(backward - value * h[inside])) <= TARGET


@pytest.mark.parametrize("r", [0.1, CRITICAL_RESTITUTION, Fraction(1, 7)])
def test_at_or_below_r_c_the_relaxation_is_refused(r):
    with pytest.raises(ValueError, match="at or below r_c .* collapse to 0"):
        relaxation.bounce_chain_relaxation(r)
    with pytest.raises(ValueError, match="at or below r_c"):
        relaxation.continuum_edge(r)


@pytest.mark.parametrize(
    "arguments, match",
    [
        ((0.99999,), "outside the solver's range"),
        ((0.01,), "outside the solver's range"),
        ((0.9, 0.0), "step = 0.0"),
        ((0.9, 0.6), "step = 0.6"),
    ],
)
def test_arguments_outside_their_range_are_refused(arguments, match):
    with pytest.raises(ValueError, match=match):
        relaxation.bounce_chain_relaxation(*arguments)


def test_the_scale_free_eigenvalue_refuses_b_outside_its_strip():
    with pytest.raises(ValueError, match="b: "):
        relaxation.scale_free_eigenvalue(2.5, 0.5)
    with pytest.raises(ValueError, match="restitution"):
        relaxation.scale_free_eigenvalue(1.0, 1.0)


def test_equilibrium_gives_the_relaxation_and_exact_equilibrium_the_same():
    numerical, exact = Equilibrium("1/2"), ExactEquilibrium("1/2")
    for eq in (numerical, exact):
        assert eq.relaxation_eigenvalue == relaxation.continuum_edge(0.5)
        assert eq.correlation_bounces == pytest.approx(-1.0 / math.log(eq.relaxation_eigenvalue))
        assert eq.bounce_chain_time == pytest.approx(eq.correlation_bounces / eq.collision_rate)
    assert numerical.bounce_chain_time == pytest.approx(exact.bounce_chain_time, rel=TARGET)
    assert numerical.relaxation_time == pytest.approx(exact.relaxation_time, rel=TARGET)


def test_equilibrium_refuses_the_relaxation_below_r_c():
    eq = Equilibrium(0.1)
    names = ("relaxation_eigenvalue", "correlation_bounces", "bounce_chain_time")
    for name in (*names, "relaxation_rate", "relaxation_time"):
        with pytest.raises(ValueError, match="at or below r_c"):
            getattr(eq, name)


def test_the_summary_relaxation_columns_may_be_nan_only_below_r_c():
    summary, tables = _passing_tables()
    columns = relaxation.RELAXATION_COLUMNS + TIME_RELAXATION_COLUMNS
    summary.update(dict.fromkeys(columns, math.nan))
    defects = solver_tables.solve_table_defects(summary, tables)
    assert defects == [f"summary: {key} is NaN" for key in columns]
    summary["collision_rate"] = math.inf
    assert solver_tables.solve_table_defects(summary, tables) == []


def test_the_summary_has_the_relaxation_columns_and_nan_below_r_c():
    columns = _relaxation_columns(Equilibrium("1/2"))
    assert tuple(columns) == relaxation.RELAXATION_COLUMNS + TIME_RELAXATION_COLUMNS
    assert columns["relaxation_eigenvalue"] == columns["continuum_edge"]
    assert columns["relaxation_time"] == Equilibrium("1/2").relaxation_time
    assert columns["bounce_chain_time"] == Equilibrium("1/2").bounce_chain_time
    below = _relaxation_columns(Equilibrium(0.1))
    assert tuple(below) == relaxation.RELAXATION_COLUMNS + TIME_RELAXATION_COLUMNS
    assert all(math.isnan(value) for value in below.values())
