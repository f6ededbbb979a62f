"""The solver of eq. (inteq) against the exact solutions and the exact identities."""

import numpy as np
import pytest
from exact_results import TIME_AVERAGES

from bouncing_ball import exact, solver
from bouncing_ball.asymptotics import small_speed_exponent

# the solver is held to ACCURACY_TARGET over CHECKED_SPEEDS
SPEEDS, TARGET = solver.CHECKED_SPEEDS, solver.ACCURACY_TARGET


@pytest.fixture(scope="module", params=list(TIME_AVERAGES), ids=str)
def exact_case(request):
    r = request.param
    return r, solver.solve_outgoing_speed_density(float(r))


def test_matches_exact_outgoing_speed_density(exact_case):
    """eq. (P(0,v)) with eq. (constants): relative error within the target over the checked speeds."""
    r, solution = exact_case
    relative = (
        solution.outgoing_speed_density(SPEEDS) / exact.outgoing_speed_density(SPEEDS, r) - 1.0
    )
    assert np.max(np.abs(relative)) <= TARGET
    # also at the nodes themselves, over the whole grid where P is a normal number
    nodes = solution.speeds[(solution.speeds >= 1e-10) & (solution.speeds <= 40.0)]
    exact_at_nodes = exact.outgoing_speed_density(nodes, r)
    at_nodes = np.interp(np.log(nodes), np.log(solution.speeds), solution.density)
    assert np.max(np.abs(at_nodes / exact_at_nodes - 1.0)) <= TARGET


@pytest.mark.parametrize("quantity", ["mean_x", "delta_x", "collision_rate"])
def test_time_averages_match_paper(exact_case, quantity):
    r, solution = exact_case
    assert solver.time_averages(solution)[quantity] == pytest.approx(
        TIME_AVERAGES[r][quantity], rel=TARGET
    )


@pytest.mark.parametrize("r", [0.2, 0.4, 0.6, 0.8])
def test_energy_balance(r):
    """M_3 = 2 r^2 / (1 - r^2); the solver normalises with M_2 = r / (1 + r), so this is a check."""
    solution = solver.solve_outgoing_speed_density(r)
    assert abs(solver.energy_balance_residual(solution)) <= TARGET


@pytest.mark.parametrize("r", [0.05, 0.1, 0.25, 0.75, 0.9])
def test_converged_in_its_settings(r):
    """Any r: a finer step, a deeper lowest node and a higher top change P(0, v) by less than the target."""
    default = solver.solve_outgoing_speed_density(r)
    q = solver.large_speed_decay_rate(r)
    fine = solver.solve_outgoing_speed_density(
        r,
        step=0.18,
        lowest_speed=1e-4 * default.speeds[0],
        highest_speed=min(1.3 * default.speeds[-1], 690.0 / q),
    )
    relative = default.outgoing_speed_density(SPEEDS) / fine.outgoing_speed_density(SPEEDS) - 1.0
    assert np.max(np.abs(relative)) <= TARGET
    assert abs(default.eigenvalue - 1.0) <= 1e-9


@pytest.mark.parametrize("r", [0.25, 0.75])
def test_small_speed_power_law(r):
    """The local log-slope of P(0, v) tends to -beta of eq. (asym2) as v -> 0."""
    solution = solver.solve_outgoing_speed_density(r)
    v = np.array([1e-8, 1e-6, 1e-4])
    slope = np.log(
        solution.outgoing_speed_density(1.01 * v) / solution.outgoing_speed_density(v)
    ) / np.log(1.01)
    beta = small_speed_exponent(r)
    deviation = np.abs(slope + beta)
    # the approach is O(v): ~100 times closer per two decades
    assert deviation[0] < 1e-6, f"slopes {slope}, beta {beta}"
    assert np.all(
        (deviation[1:] / deviation[:-1] > 30.0) & (deviation[1:] / deviation[:-1] < 300.0)
    ), deviation


@pytest.mark.parametrize("r", [0.03, 0.5, 0.9])
def test_density_off_the_nodes_is_the_nystrom_formula(r):
    """P(0, v) off the nodes (which skips the terms below e^-60 of the largest bound) against
    the full Nystrom formula, the operator's rows times P at the nodes (the operator the
    solver solves): to 1e-14, up to the highest node, where P(0, v) nears underflow."""
    solution = solver.solve_outgoing_speed_density(r)
    v = np.geomspace(1e-12, solution.speeds[-1], 400)
    ours = solution.outgoing_speed_density(v)
    full = solution._rows(v / r) @ solution.density / r**2
    assert np.max(np.abs(ours / full - 1.0)) < 1e-14


def test_collision_rate_diverges_below_critical():
    """r = 0.1 < r_c: int v P(0, v) dv over v > v_min grows like v_min^(2 - beta) as v_min -> 0,
    while both balances still hold."""
    solution = solver.solve_outgoing_speed_density(0.1)
    beta = solution.small_speed_exponent
    assert beta > 2.0
    x, w = np.polynomial.legendre.leggauss(40)

    def rate_between(lo, hi):  # int v P(0, v) dv = int v^2 P d(ln v), Gauss-Legendre in ln v
        log_v = 0.5 * np.log(hi / lo) * x + 0.5 * np.log(hi * lo)
        v = np.exp(log_v)
        return 0.5 * np.log(hi / lo) * np.sum(w * v * v * solution.outgoing_speed_density(v))

    # each factor 1e4 down in v_min adds (1e4)^(beta - 2) times what the previous one added
    deep, shallow = rate_between(1e-16, 1e-12), rate_between(1e-12, 1e-8)
    assert deep / shallow == pytest.approx(1e4 ** (beta - 2.0), rel=1e-3)
    assert np.isinf(solver.time_averages(solution)["collision_rate"])
    assert abs(solver.energy_balance_residual(solution)) <= TARGET


@pytest.mark.parametrize("bad", [0.0, 1.0, -0.5, 1.5])
def test_refuses_restitution_outside_unit_interval(bad):
    with pytest.raises(ValueError, match="restitution"):
        solver.solve_outgoing_speed_density(bad)


def test_refuses_restitution_too_close_to_one():
    with pytest.raises(
        ValueError,
        match=r"the solver's range of r, 0.02 <= r <= 0.9999.*above it the solver's dense grid",
    ):
        solver.solve_outgoing_speed_density(0.99999)


@pytest.mark.parametrize("small", [0.015, 1e-3, 1e-7])
def test_refuses_restitution_below_its_accurate_range(small):
    """Below 0.02 P(0, v) ~ exp(-v / (2r)) leaves the range of doubles within the speeds that
    matter, so no answer meets the accuracy target: the solver refuses, naming its range."""
    with pytest.raises(
        ValueError, match=r"the solver's range of r, 0.02 <= r <= 0.9999.*below it P\(0, v\)"
    ):
        solver.solve_outgoing_speed_density(small)


def test_accuracy_estimate_is_small_and_reported_in_the_summary():
    """The estimate of rule solve's summary (a finer solve) meets the target at r = 0.3."""
    row = solver.solution_summary(solver.solve_outgoing_speed_density(0.3))
    assert 0.0 < row["accuracy_estimate"] <= TARGET
    assert abs(row["momentum_balance_residual"]) < 1e-12  # the normalisation itself
