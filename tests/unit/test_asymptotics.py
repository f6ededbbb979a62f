"""beta(r), m(r), q(r) of eqs. (asym2)-(asym6), and the solver's P(0, v) approaching them."""

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import Equilibrium, solver
from bouncing_ball.asymptotics import (
    CRITICAL_RESTITUTION,
    exponents_table,
    large_speed_decay_rate,
    large_speed_exponent,
    small_speed_exponent,
)
from bouncing_ball.kernel import return_speed_density


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


def _mean_over_return(function, u):
    """E[function(ln(v / u)) | u] over the return law v G_g(v, u) of eq. (kernel3)."""

    def integrand(log_ratio):
        v = u * np.exp(log_ratio)
        return function(log_ratio) * v * float(return_speed_density(v, u))

    edges = [-60.0, -3.0, 0.0, 3.0, 60.0]
    return sum(
        integrate.quad(integrand, a, b, epsabs=0.0, epsrel=1e-12, limit=200)[0]
        for a, b in zip(edges[:-1], edges[1:])
    )


def test_the_v_to_the_minus_2_mode_carries_a_flux_of_bounces_through_zero_speed():
    """At small speeds ln u_n is a random walk with steps X = ln(r v / u) (the kernel is
    scale-free), E[e^((b - 2) X)] = Phi(b) = r^(b - 2) / (2 sin((2b + 1) pi / 6)), and the mode
    u P(0, u) ~ u^(1 - b) carries L^(2 - b) (1 - Phi(b)) / (2 - b) bounces per bounce upward
    across a small speed L: none for b = beta (Phi = 1), and for b = 2 (uniform in ln u)
    Phi'(2) = E[X] = ln r + pi / sqrt(3) = ln(r / r_c), from v = 0 above r_c and into it below.
    From the kernel at small u: E[ln(v / u)] = pi / sqrt(3) with gravity's correction of order
    u^(1/2) (the return law's tail beyond v ~ 1), and Phi(beta) = 1 at r = 1/2 and 1/3 (a
    correction of order u)."""
    assert np.log(0.5) + np.pi / np.sqrt(3.0) == pytest.approx(
        np.log(0.5 / CRITICAL_RESTITUTION), rel=1e-14
    )
    gains = {u: _mean_over_return(lambda y: y, u) - np.pi / np.sqrt(3.0) for u in (1e-6, 1e-10)}
    assert abs(gains[1e-10]) < 3.0 * np.sqrt(1e-10)
    assert gains[1e-6] / gains[1e-10] == pytest.approx(100.0, rel=0.01)  # O(u^(1/2))
    for r in (0.5, 1.0 / 3.0):
        beta = small_speed_exponent(r)
        mode = r ** (beta - 2.0) * _mean_over_return(lambda y, b=beta: np.exp((b - 2.0) * y), 1e-10)
        assert mode == pytest.approx(1.0, abs=1e-8)


@pytest.mark.parametrize("delta", [1e-3, 1e-5, 1e-8])
def test_m_approaches_one_only_logarithmically_above_one_half(delta):
    """x(1/2 + delta) = (8/3) delta + O(delta^2) in eq. (asym5), so
    m(1/2 + delta) = 1 - ln 2 / ln(3 / (16 delta)) to relative order delta."""
    gap = 1.0 - large_speed_exponent(0.5 + delta)
    assert gap == pytest.approx(np.log(2.0) / np.log(3.0 / (16.0 * delta)), rel=5.0 * delta)


def _crossover_speed(r):
    """The speed beyond which the large-v form of eqs. (asym3)-(asym6) holds near r = 1/2:
    1 / (1/(2r) - q) above (the end-point term v^(-3/2) e^(-v/(2r)) against v^-m e^(-q v)),
    (1/(2r) - 1)^-2 below (the return law's Gaussian spread against the end point's slope)."""
    q = large_speed_decay_rate(r)
    return 1.0 / (0.5 / r - q) if r > 0.5 else (0.5 / r - 1.0) ** -2


def _local_exponent(equilibrium, v, q):
    """(-d ln P(0, v) / dv - q) v, which tends to m(r) at large v."""
    h = 1e-4 * v
    slope = -(np.log(equilibrium.p0v(v + h)) - np.log(equilibrium.p0v(v - h))) / (2.0 * h)
    return (slope - q) * v


@pytest.mark.parametrize("r", [0.45, 0.49, 0.505, 0.52, 0.55])
def test_large_speed_form_sets_in_beyond_the_crossover_speed(r):
    """Near r = 1/2 the solver's local exponent is that of the r = 1/2 form (1) well below the
    crossover speed v_c (81 at r = 0.45, 2401 at 0.49, 7575 at 0.505, 488 at 0.52, 83 at 0.55)
    and reaches m(r) only beyond it: at v_c / 32 at least a third of the way from m(r) to 1
    remains, at v_c (where the solver's grid reaches it) less than a quarter."""
    equilibrium = Equilibrium(r)
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    crossover = _crossover_speed(r)

    def remaining(v):
        return (_local_exponent(equilibrium, v, q) - m) / (1.0 - m)

    assert remaining(crossover / 32.0) > 1.0 / 3.0
    if crossover < 500.0:
        assert 0.0 <= remaining(crossover) < 0.25
