"""Numerical claims over the whole range of r that the unit tier's modules rely on, each a
solve at many r or a large array against the direct computation (split from
tests/unit/test_equilibration.py, test_flight_time.py, test_equilibrium_extremes.py and
test_equilibrium.py: each costs seconds, not the unit tier's fractions of one; the solves near
r = 1 are shared with test_quasi_elastic_limit.py and test_distribution_any_r.py)."""

from fractions import Fraction

import numpy as np
import pytest
from scipy import integrate

import bouncing_ball as bb
from bouncing_ball import Equilibrium, distribution, solver
from bouncing_ball import flight_time as ft
from bouncing_ball.restitution import DISTRIBUTION_RESTITUTION_RANGE, SOLVER_RESTITUTION_RANGE
from bouncing_ball.simulation.equilibration import (
    EQUILIBRATION_RELAXATION_TIMES,
    MIN_EQUILIBRATION_TIME,
)
from bouncing_ball.solver import solve_outgoing_speed_density


def test_the_relaxation_time_bound_lies_above_the_relaxation_time_at_every_r():
    """7.5 / (1 - r)^2 against the solver's relaxation time 1 / gamma from just above r_c to
    0.9999 (and the quasi-elastic form beyond): above it by the stated margin, so that the
    checks it answers without a solve answer as the solve would; and 20 of it below the least
    equilibration time up to r = 0.6, so that the exact solutions' r = 1/2, 1/3 (the studies',
    the workflow tests') and the default config's r up to 1/2 need no solve.  At r = 0.75 no
    bound can spare the solve: 20 / gamma there (1.8e3) is itself above the least time."""
    from bouncing_ball.asymptotics import CRITICAL_RESTITUTION
    from bouncing_ball.simulation.equilibration import (
        RELAXATION_BOUND_MARGIN,
        equilibration_relaxation_time,
        relaxation_time_bound,
    )

    near_critical = CRITICAL_RESTITUTION + np.array([1e-5, 1e-3])
    # each r is an eigenvalue search on a matrix that grows like 1/(1 - r); above 0.995 the ratio is
    # the quasi-elastic one, 7.5 / ((64/9) (1 - eps)) > 1.054 (tests/numerical holds 1/gamma to
    # (64/9) eps^-2 (1 - eps) at eps = 0.01 and 0.005), and 0.99999 takes the quasi-elastic form
    grid = [*near_critical, *np.linspace(0.17, 0.99, 15)]
    for r in [*grid, 0.995, 0.99999]:
        assert relaxation_time_bound(r) >= RELAXATION_BOUND_MARGIN * equilibration_relaxation_time(
            r
        ), r
    assert EQUILIBRATION_RELAXATION_TIMES * relaxation_time_bound(0.6) < MIN_EQUILIBRATION_TIME
    assert (
        EQUILIBRATION_RELAXATION_TIMES * equilibration_relaxation_time(0.75)
        > MIN_EQUILIBRATION_TIME
    )
    with pytest.raises(ValueError, match="r_c"):
        relaxation_time_bound(0.1)


def test_flight_time_bins_sum_to_one():
    solution = solve_outgoing_speed_density(0.5)
    edges = np.concatenate([[0.0], np.geomspace(1e-3, 50.0, 15)])
    average = ft.flight_time_bin_average(solution, edges[:-1], edges[1:])
    beyond, _ = integrate.quad(
        lambda t: ft.flight_rate_density(solution, np.array([t]))[0], 50.0, 300.0, epsrel=1e-12
    )
    total = average @ np.diff(edges) + beyond / solution.moment(1)
    assert total == pytest.approx(1.0, abs=1e-8)


@pytest.mark.parametrize("restitution", [0.1, 0.5, 0.95])
def test_interpolated_return_speed_law_is_the_direct_one_to_rounding(restitution):
    # the return-law control's case: four points in each of the fine 2.3 % bins of the
    # outgoing speeds, from 1e-10 to 1000, on a simulation's speed bins / r
    fine = np.geomspace(1e-10, 1e3, 1301)
    u, _ = ft._log_gauss(fine[:-1], fine[1:], 4)
    speed_edges = np.geomspace(1e-4, 100.0, 61) / restitution
    v_lower = np.concatenate([[0.0], speed_edges])
    v_upper = np.concatenate([speed_edges, [np.inf]])
    direct = ft.return_speed_bin_law(u.ravel(), v_lower, v_upper)
    interpolated = ft.return_speed_bin_law(u.ravel(), v_lower, v_upper, interpolated=True)
    np.testing.assert_allclose(direct.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(interpolated, direct, rtol=0, atol=1e-14)
    # each point's value whatever the others asked for (fixed panels): a few points, every
    # other point
    np.testing.assert_array_equal(
        ft.return_speed_bin_law(u.ravel()[::2], v_lower, v_upper, interpolated=True),
        interpolated[::2],
    )
    few = u.ravel()[1000:1010]
    np.testing.assert_array_equal(
        ft.return_speed_bin_law(few, v_lower, v_upper, interpolated=True),
        ft.return_speed_bin_law(few, v_lower, v_upper),
    )


def test_pxv_is_zero_beyond_the_largest_velocity_at_every_r():
    """P(0, r v) at the upper end of DISTRIBUTION_RESTITUTION_RANGE (the smallest r q of the
    range) underflows at v = LARGEST_VELOCITY."""
    r = DISTRIBUTION_RESTITUTION_RANGE[1]
    eq = Equilibrium(r)
    assert eq.p0v(r * distribution.LARGEST_VELOCITY) == 0.0


def test_the_upper_end_of_the_solver_range_is_solved():
    """r = 0.9999, the solver's upper bound (given as the exact fraction, and as the decimal):
    the solution balances energy to the solver's target."""
    eq = bb.Equilibrium("9999/10000")
    assert eq.restitution == Fraction(9999, 10000) and not eq.distribution_available
    assert bb.Equilibrium(0.9999).solution is eq.solution
    assert abs(solver.energy_balance_residual(eq.solution)) < solver.ACCURACY_TARGET
    assert np.isfinite(eq.mean_x) and np.isfinite(eq.mean_flight_time)
    with pytest.raises(
        ValueError,
        match=rf"{SOLVER_RESTITUTION_RANGE[0]} <= r <= {DISTRIBUTION_RESTITUTION_RANGE[1]}",
    ):
        eq.px(1.0)
