"""beta(r), m(r), q(r) of eqs. (asym2)-(asym6), and the solver's P(0, v) approaching them."""

import numpy as np
import pytest

from bouncing_ball import solver
from bouncing_ball.asymptotics import (
    CRITICAL_RESTITUTION,
    exponents_table,
    large_speed_decay_rate,
    large_speed_exponent,
    small_speed_exponent,
)


@pytest.mark.parametrize(
    ("r", "beta"),
    [(CRITICAL_RESTITUTION, 2.0), (0.5, 1.0), (1.0 / 3.0, 1.5), (0.25, 1.75)],
    ids=["r_c", "1/2", "1/3", "1/4"],
)
def test_beta_at_known_points(r, beta):
    assert small_speed_exponent(r) == pytest.approx(beta, abs=1e-10)


def test_critical_restitution():
    assert pytest.approx(np.exp(-np.pi / np.sqrt(3.0)), rel=1e-15) == CRITICAL_RESTITUTION
    assert pytest.approx(0.163, abs=5e-4) == CRITICAL_RESTITUTION


@pytest.mark.parametrize("r", [0.01, 0.1, 0.2, 0.45, 0.6, 0.9, 0.999])
def test_beta_is_the_physical_root_of_asym2(r):
    beta = small_speed_exponent(r)
    assert 0.0 < beta < 2.5 and beta != pytest.approx(2.0)
    # eq. (asym2): r = [2 sin((2 beta + 1) pi / 6)]^(1 / (beta - 2))
    assert (2.0 * np.sin((2.0 * beta + 1.0) * np.pi / 6.0)) ** (
        1.0 / (beta - 2.0)
    ) == pytest.approx(r, rel=1e-10)


def test_beta_decreases_from_five_halves_to_zero():
    r = np.linspace(0.001, 0.999, 300)
    beta = exponents_table(r).beta.to_numpy()
    assert np.all(np.diff(beta) < 0.0)
    assert beta[0] > 2.4 and beta[-1] < 0.02


def _one_sided_derivatives(function, x, h=1e-5):
    left = (function(x) - function(x - h)) / h
    right = (function(x + h) - function(x)) / h
    return left, right


def test_q_and_its_slope_continuous_at_one_half_but_not_its_curvature():
    half = 0.5
    assert large_speed_decay_rate(half - 1e-9) == pytest.approx(
        large_speed_decay_rate(half + 1e-9), abs=1e-7
    )
    left, right = _one_sided_derivatives(large_speed_decay_rate, half, h=1e-6)
    assert left == pytest.approx(-2.0, abs=1e-4) and right == pytest.approx(-2.0, abs=1e-4)

    def second(x, h):
        return (
            large_speed_decay_rate(x + h)
            - 2 * large_speed_decay_rate(x)
            + large_speed_decay_rate(x - h)
        ) / h**2

    below, above = second(half - 0.01, 1e-4), second(half + 0.01, 1e-4)
    assert abs(below - above) > 1.0  # 1/r^3 -> 8 below, -8/3 above


def test_m_jumps_at_one_half():
    assert large_speed_exponent(0.5 - 1e-9) == 1.5
    assert large_speed_exponent(0.5) == 1.0
    above = [large_speed_exponent(0.5 + h) for h in (1e-2, 1e-4, 1e-8)]
    assert np.all(np.diff(above) > 0.0) and above[-1] < 1.0  # tends to 1 from below as r -> 1/2+
    assert large_speed_exponent(0.999) < 1e-3 and large_speed_decay_rate(0.999) < 2e-3


@pytest.mark.parametrize("r", [0.25, 0.75])
def test_solver_large_speed_decay(r):
    """-d ln P / dv = q + m / v + O(1 / v^2): (slope - q) v tends to m of eqs. (asym4)-(asym6)."""
    solution = solver.solve_outgoing_speed_density(r)
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    v = np.array([10.0, 20.0, 40.0, 80.0])
    h = 1e-3 * v
    slope = -(
        np.log(solution.outgoing_speed_density(v + h))
        - np.log(solution.outgoing_speed_density(v - h))
    ) / (2 * h)
    assert np.all(np.diff(np.abs(slope - q)) < 0.0)
    assert abs(slope[-1] - q) < 0.02 * q + 0.02
    approach = (slope - q) * v - m
    assert np.all(np.diff(np.abs(approach)) < 0.0) and abs(approach[-1]) < 0.01
    # the remainder is O(1 / v^2): approach * v settles
    assert approach[-1] * v[-1] == pytest.approx(approach[-2] * v[-2], rel=0.05)


@pytest.mark.parametrize(
    "function", [small_speed_exponent, large_speed_decay_rate, large_speed_exponent]
)
@pytest.mark.parametrize("bad", [1.5, -0.5, 0.0, 1.0])
def test_every_exponent_refuses_an_r_outside_the_unit_interval(function, bad):
    """m(1.5) was 0.295, q(-0.5) was -1 and q(0) a ZeroDivisionError."""
    with pytest.raises(ValueError, match=r"restitution must lie in \(0, 1\)"):
        function(bad)
