"""The quasi-elastic forms of bouncing_ball.quasi_elastic on their own: the return-speed moments
of eq. (returnlaw) against the kernel of eq. (kernel3), the moment recursion against the
expansions of SCALINGS, the limiting law's normalisation, the decay rate of eq. (asym4), the
continuous-time relaxation mode, and the refusals.  The solver comparison is in
tests/numerical/test_quasi_elastic_limit.py."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from bouncing_ball import quasi_elastic as qe
from bouncing_ball.asymptotics import large_speed_decay_rate
from bouncing_ball.flight_time import conditional_moment, mean_flight_time_given_speed

# a fast outgoing speed: the terms O(e^(-u/2)) of eq. (returnlaw) are below e^-20 there
FAST = 40.0


@pytest.mark.parametrize("k", range(1, len(qe.RETURN_SPEED_MOMENTS)))
def test_return_speed_moments_match_the_kernel(k):
    """E[V^k | u] of eq. (returnlaw) against the v-integral of eq. (kernel3), to e^(-u/2)."""
    polynomial = np.polynomial.Polynomial(qe.RETURN_SPEED_MOMENTS[k])
    kernel = conditional_moment(FAST, 0, k)
    assert kernel / polynomial(FAST) - 1.0 == pytest.approx(0.0, abs=math.exp(-FAST / 2.0))


@pytest.mark.parametrize("k", range(2, len(qe.RETURN_SPEED_MOMENTS)))
def test_return_speed_moments_lead_as_the_diffusion(k):
    """The two leading coefficients: (2/3) k (k + 1) (mean 4/3, variance 4u/3) and
    (2/9) k^2 (k^2 - 1) (the O(1) and third-cumulant parts)."""
    coefficients = qe.RETURN_SPEED_MOMENTS[k]
    assert coefficients[k] == 1.0
    assert coefficients[k - 1] == pytest.approx(2.0 * k * (k + 1) / 3.0, rel=1e-15)
    assert coefficients[k - 2] == pytest.approx(2.0 * k**2 * (k**2 - 1) / 9.0, rel=1e-15)


def test_first_two_moments_are_the_ito_identities():
    """E[V | u] = E[T | u] - u, E[V^2 | u] = u^2 + 2 E[T | u], with E[T | u] of eq. (meanT), to
    its terms O(e^(-u/2))."""
    mean_time = float(mean_flight_time_given_speed(FAST))
    assert np.polynomial.Polynomial(qe.RETURN_SPEED_MOMENTS[1])(FAST) == pytest.approx(
        mean_time - FAST, rel=math.exp(-FAST / 2.0)
    )
    assert np.polynomial.Polynomial(qe.RETURN_SPEED_MOMENTS[2])(FAST) == pytest.approx(
        FAST**2 + 2.0 * mean_time, rel=math.exp(-FAST / 2.0)
    )


def _chain_moments(r):
    """m_k = E[u^k] of the bounce chain's stationary law from the recursion
    (1 - r^k) m_k = r^k sum_(j<k) c_kj m_j of the module's docstring."""
    moments = [1.0]
    for k in range(1, len(qe.RETURN_SPEED_MOMENTS)):
        lower = sum(c * m for c, m in zip(qe.RETURN_SPEED_MOMENTS[k][:k], moments, strict=True))
        moments.append(r**k * lower / (1.0 - r**k))
    return moments


def _recursion_averages(r):
    """I, <x>, Delta x from the chain's moments by the Ito identities (solver.time_averages)."""
    m = _chain_moments(r)
    rate = r / ((1.0 + r) * m[1])
    mean_x = (1.0 + r**3) * rate * m[3] / (3.0 * r**3)
    mean_x_squared = 2.0 / 3.0 * ((1.0 + r**5) * rate * m[5] / (5.0 * r**5) - 8.0 * mean_x)
    return {
        "collision_rate": rate,
        "mean_x": mean_x,
        "delta_x": math.sqrt(mean_x_squared - mean_x**2),
    }


@pytest.mark.parametrize("name", ["collision_rate", "mean_x", "delta_x"])
def test_scalings_expand_the_moment_recursion(name):
    """The first correction of SCALINGS is the recursion's: (recursion / leading - 1) / epsilon
    at epsilon = 1e-3 is c1 plus the recursion's own epsilon^2 term (c2 less the flights from
    u = O(1), which add 1 to I's c2 only), within the epsilon^3 term's size (2 |c2| epsilon^2)."""
    r, epsilon = 0.999, 1e-3
    scaling = qe.SCALINGS[name]
    second = scaling.second - (1.0 if name == "collision_rate" else 0.0)
    measured = (
        _recursion_averages(r)[name] / qe.quasi_elastic_form(name, r, order=0) - 1.0
    ) / epsilon
    assert measured == pytest.approx(
        scaling.first + second * epsilon, abs=2.0 * abs(scaling.second) * epsilon**2
    )


def test_limiting_law_is_normalised_under_the_paper_conventions():
    """The flux-weighted law integrates to 1 with mean 4/3 (m_1 epsilon -> 4/3); the scaled
    P(0, v) has M_2 -> 1/2 (momentum balance) and epsilon M_3 -> 1 (energy balance), and
    M_1 / epsilon -> 3/8 (I)."""
    inf = float("inf")
    assert quad(qe.outgoing_speed_law, 0.0, inf)[0] == pytest.approx(1.0, rel=1e-12)
    assert quad(lambda w: w * qe.outgoing_speed_law(w), 0.0, inf)[0] == pytest.approx(4 / 3)
    density = qe.scaled_speed_density
    assert quad(lambda w: w**2 * density(w), 0.0, inf)[0] == pytest.approx(0.5, rel=1e-12)
    assert quad(lambda w: w**3 * density(w), 0.0, inf)[0] == pytest.approx(1.0, rel=1e-12)
    assert quad(lambda w: w * density(w), 0.0, inf)[0] == pytest.approx(
        qe.SCALINGS["collision_rate"].limit, rel=1e-12
    )


def test_first_correction_carries_the_decay_rate_of_asym4():
    """-3w/2 in p1(w) is the first correction of q(r) = (3/2) epsilon (1 + epsilon + ...):
    d p1 / dw = -(q / epsilon - 3/2) / epsilon + O(epsilon^2), eq. (asym4) giving
    q / epsilon = (3/2) / (1 - epsilon + epsilon^2) = (3/2) (1 + epsilon - epsilon^3 + ...): within
    twice that term, 3 epsilon^2."""
    epsilon = 1e-3
    slope = qe.speed_density_first_correction(1.0) - qe.speed_density_first_correction(0.0)
    rate = large_speed_decay_rate(1.0 - epsilon)
    assert slope == pytest.approx(-(rate / epsilon - 1.5) / epsilon, abs=3.0 * epsilon**2)


def test_correlation_bounces_expands_as_scaled():
    """-1/ln r = (1/epsilon) (1 - epsilon/2 - epsilon^2/12 + O(epsilon^3))."""
    r, epsilon = 0.999, 1e-3
    form = qe.quasi_elastic_form("correlation_bounces", r)
    assert qe.correlation_bounces(r) / form - 1.0 == pytest.approx(-(epsilon**2) / 12, rel=0.01)


def test_relaxation_mode_is_the_second_hydrogen_level():
    """f(w) = (1 - 3w/8) e^(3w/8) solves (2/3) f'' + (4/(3w) - 1) f' = -(9/32) f and is
    orthogonal to the constants under the time-weighted law w^2 e^(-3w/2): the rate 9 eps^2/64
    of ``relaxation_time``."""
    w = np.linspace(0.1, 20.0, 50)
    a = 3.0 / 8.0
    f = (1.0 - a * w) * np.exp(a * w)
    first = -(a * a) * w * np.exp(a * w)
    second = -(a * a) * (1.0 + a * w) * np.exp(a * w)
    generator = (2.0 / 3.0) * second + (4.0 / (3.0 * w) - 1.0) * first
    assert np.allclose(generator, -(9.0 / 32.0) * f, rtol=1e-13, atol=1e-13 * np.abs(f).max())
    overlap = quad(lambda x: (1.0 - a * x) * x**2 * np.exp(-1.125 * x), 0.0, float("inf"))[0]
    assert overlap == pytest.approx(0.0, abs=1e-12)
    epsilon = 0.01
    assert qe.relaxation_time(1.0 - epsilon) == pytest.approx(2.0 / (epsilon**2 * 9.0 / 32.0))


@pytest.mark.parametrize("r", [0.0, 1.0, -0.5, 1.5, float("nan")])
def test_restitution_outside_the_open_unit_interval_is_refused(r):
    for call in (
        qe.quasi_elastic_epsilon,
        qe.correlation_bounces,
        qe.relaxation_time,
        lambda x: qe.quasi_elastic_form("mean_x", x),
    ):
        with pytest.raises(
            ValueError,
            match="restitution: .*(outside the allowed range 0 < r < 1|not a finite number)",
        ):
            call(r)


def test_r_is_parsed_as_equilibrium_parses_it():
    """quasi_elastic_form("mean_x", "1/3") said "could not convert string to float", and
    np.float32(0.99) gave 17600.034 (the float32's binary value) where Equilibrium reads 0.99."""
    import numpy as np

    assert qe.quasi_elastic_form("mean_x", "1/3") == qe.quasi_elastic_form("mean_x", 1 / 3)
    assert qe.quasi_elastic_form("mean_x", np.float32(0.99)) == qe.quasi_elastic_form(
        "mean_x", 0.99
    )
    assert qe.correlation_bounces("99/100") == qe.correlation_bounces(0.99)
    assert qe.quasi_elastic_epsilon(np.float32(0.75)) == 0.25
    for bad in ("half", "1/0"):
        with pytest.raises(ValueError, match="restitution: "):
            qe.quasi_elastic_form("mean_x", bad)


def test_the_table_and_the_curves_take_r_as_equilibrium_does():
    """quasi_elastic_table(["1/2"]) refused while scaled_speed_curves(["1/2"]) took it."""
    import numpy as np

    table = qe.quasi_elastic_table(["1/2", np.float32(0.5)])
    assert list(table.r.unique()) == [0.5]
    first, second = (table[table.index < len(table) // 2], table[table.index >= len(table) // 2])
    assert first.scaled.to_numpy().tolist() == second.scaled.to_numpy().tolist()
    curves = qe.scaled_speed_curves(["1/2", np.float32(0.5)], [1.0])
    assert curves.r.tolist() == [0.5, 0.5]
    for call in (qe.quasi_elastic_table, lambda r: qe.scaled_speed_curves(r, [1.0])):
        with pytest.raises(ValueError, match="outside the allowed range|the solver's range"):
            call(["3/2"])


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="name must be one of"):
        qe.quasi_elastic_form("mean_height", 0.99)
    with pytest.raises(ValueError, match="order must be 0 or 1"):
        qe.quasi_elastic_form("mean_x", 0.99, order=2)
    for law in (qe.outgoing_speed_law, qe.scaled_speed_density, qe.speed_density_first_correction):
        with pytest.raises(ValueError, match="scaled speed w"):
            law([1.0, -0.5])
        with pytest.raises(ValueError, match="scaled speed w"):
            law(float("inf"))
