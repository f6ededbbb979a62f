"""Free flight, eqs. (xstep), (vstep), and the bridge between step ends, sampled: z-scores
of 200 000 steps against the exact expectations of the free process (no boundary), with
fixed seeds (split from tests/unit/test_free_flight.py, which checks the same functions
deterministically)."""

import numpy as np
from numba import njit

from bouncing_ball.free_flight import (
    free_flight_step,
    hermite_cubic,
    mean_path_integrals,
    quintic_antiderivative_value,
    speed_squared_coefficients,
)


@njit
def _many_steps(x0, v0, dt, n, seed):
    np.random.seed(seed)
    out = np.empty((n, 4))
    for i in range(n):
        x1, v1 = free_flight_step(
            x0, v0, dt, np.random.standard_normal(), np.random.standard_normal()
        )
        a0, a1, a2, a3 = hermite_cubic(x0, v0, x1, v1, dt)
        int_x, int_x2 = mean_path_integrals(a0, a1, a2, a3, dt, dt)
        out[i] = x1, v1, int_x, int_x2
    return out


def _z(samples, expected):
    return (samples.mean() - expected) / (samples.std(ddof=1) / np.sqrt(len(samples)))


def test_free_flight_step_has_the_exact_moments():
    """Free propagator: mean x0 + v0 t - t^2/2, v0 - t; Var x = 2t^3/3, Var v = 2t, Cov = t^2."""
    x0, v0, dt = 1.0, 0.7, 0.9
    s = _many_steps(x0, v0, dt, 200_000, 3)
    x, v = s[:, 0], s[:, 1]
    mean_x, mean_v = x0 + v0 * dt - dt**2 / 2, v0 - dt
    assert abs(_z(x, mean_x)) < 4 and abs(_z(v, mean_v)) < 4
    assert abs(_z((x - mean_x) ** 2, 2 * dt**3 / 3)) < 4
    assert abs(_z((v - mean_v) ** 2, 2 * dt)) < 4
    assert abs(_z((x - mean_x) * (v - mean_v), dt**2)) < 4


def test_bridge_integrals_are_unbiased():
    """Averaged over the step's end, E[int x | ends] and E[int x^2 | ends] give the free values.

    E int_0^T x dt = x0 T + v0 T^2/2 - T^3/6 and
    E int_0^T x^2 dt = int_0^T [(x0 + v0 t - t^2/2)^2 + 2 t^3/3] dt.
    """
    x0, v0, dt = 0.5, -0.3, 1.7
    s = _many_steps(x0, v0, dt, 200_000, 4)
    t = np.linspace(0.0, dt, 20001)
    mean_path = x0 + v0 * t - t**2 / 2
    expected_x2 = np.trapezoid(mean_path**2 + 2 * t**3 / 3, t)
    assert abs(_z(s[:, 2], x0 * dt + v0 * dt**2 / 2 - dt**3 / 6)) < 4
    assert abs(_z(s[:, 3], expected_x2)) < 4
    # the x^2 integral is not the square of the mean path alone: the variance term matters
    assert expected_x2 - np.trapezoid(mean_path**2, t) > 10 * s[:, 3].std() / np.sqrt(len(s))


@njit
def _speed_squared_integrals(x0, v0, dt, n, seed):
    np.random.seed(seed)
    out = np.empty(n)
    for i in range(n):
        x1, v1 = free_flight_step(
            x0, v0, dt, np.random.standard_normal(), np.random.standard_normal()
        )
        a0, a1, a2, a3 = hermite_cubic(x0, v0, x1, v1, dt)
        out[i] = quintic_antiderivative_value(*speed_squared_coefficients(a1, a2, a3, dt), dt)
    return out


def test_bridge_speed_squared_integral_is_unbiased():
    """E int_0^T v^2 dt = int_0^T [(v0 - t)^2 + 2 t] dt, what <v^2>_x of eq. (moment2) needs."""
    x0, v0, dt = 0.5, 1.3, 1.1
    samples = _speed_squared_integrals(x0, v0, dt, 200_000, 5)
    expected = (v0**3 - (v0 - dt) ** 3) / 3 + dt**2
    assert abs(_z(samples, expected)) < 4
