"""The slowest decay rate of the process in time (``time_relaxation``) against independent
computations: the tilted operator built by quadrature of the joint law eq. (joint) over t
(not the closed-form tilt of eq. (tilted)), and the large-speed edge against a numerical
saddle of that law."""

import math

import numpy as np
import pytest
from scipy import linalg, optimize

from bouncing_ball import Equilibrium, time_relaxation
from bouncing_ball.asymptotics import CRITICAL_RESTITUTION
from bouncing_ball.flight_time import joint_density

#: The quadrature rule below against one with step 0.2, lowest node 1e-8, highest 55 and 800
#: times: 1 / gamma = 19.3446368 against 19.3446339 (1.5e-7); the tolerance allows 10 times it.
DIRECT_TOLERANCE = 1.5e-6


def _direct_second_eigenvalue(r, rate, step=0.3, lowest=1e-6, highest=45.0, times=500):
    """The second real eigenvalue of Q_gamma h(u) = int dt dv e^(gamma t) p(t, v | u) h(r v),
    with p of eq. (joint) integrated over t on a log grid and v on nodes uniform in ln u."""
    u = np.exp(np.arange(math.log(lowest), math.log(highest) + step / 2, step))
    t = np.geomspace(1e-16, 600.0, times)
    t_weights = np.gradient(np.log(t)) * t
    density = joint_density(t[None, None, :], u[:, None, None] / r, u[None, :, None])
    kernel = (density * (np.exp(rate * t) * t_weights)).sum(axis=2)  # over t, at (V_i, u_j)
    operator = (kernel * (step * u)[:, None] / r).T  # dV = du / r at V = u / r
    values = linalg.eigvals(operator)
    return np.sort(values.real[np.abs(values.imag) < 1e-9])[::-1][1]


def test_the_rate_at_one_half_is_the_direct_quadratures():
    rate = optimize.brentq(
        lambda g: _direct_second_eigenvalue(0.5, g) - 1.0, 0.03, 0.06, xtol=1e-12
    )
    relaxation = time_relaxation.time_relaxation(0.5)
    assert relaxation.isolated
    assert relaxation.rate == pytest.approx(rate, rel=DIRECT_TOLERANCE)


def _saddle_exponent(rate, s):
    """max over tau, nu of the exponent of e^(gamma t + s v) p(t, v | u) at t = tau u,
    v = nu u, u -> inf (eq. (joint)), numerically."""

    def minus(point):
        tau, nu = np.exp(point)
        return -(rate * tau + s * nu - ((tau - 1 - nu) ** 2 + 3 * (nu - 1) ** 2) / (4 * tau))

    return -optimize.minimize(
        minus, [math.log(2.0), 0.0], method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-15}
    ).fun


@pytest.mark.parametrize("r", [0.3, 0.75])
def test_the_large_speed_edge_is_where_the_saddles_roots_merge(r):
    """Below gamma_e some kappa has Lambda(gamma, kappa r) < kappa; at gamma_e the least of
    Lambda(gamma, kappa r) - kappa is 0 (the merged root kappa = q / 2 of eq. (edge))."""
    edge = time_relaxation.large_speed_edge(r)
    kappa = 0.75 * (1 - r) / (1 - r + r * r)
    assert _saddle_exponent(edge, kappa * r) - kappa == pytest.approx(0.0, abs=1e-9)
    for shift in (-1e-3, 1e-3):
        assert _saddle_exponent(edge, (kappa + shift) * r) - (kappa + shift) > 0.0
    assert _saddle_exponent(0.9 * edge, kappa * r) - kappa < 0.0


def test_the_relaxation_time_is_the_inverse_rate_and_the_chain_time_is_separate():
    eq = Equilibrium("1/2")
    assert eq.relaxation_time == pytest.approx(1.0 / eq.relaxation_rate, rel=1e-14)
    assert eq.bounce_chain_time == pytest.approx(eq.correlation_bounces / eq.collision_rate)
    assert eq.relaxation_time > eq.bounce_chain_time
    assert eq.relaxation_rate < eq._time_relaxation.large_speed_edge


@pytest.mark.parametrize("r", [0.1, CRITICAL_RESTITUTION, 0.99999])
def test_the_rate_is_refused_outside_its_range(r):
    with pytest.raises(ValueError, match=r"r_c|restitution"):
        time_relaxation.time_relaxation(r)
