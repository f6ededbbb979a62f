"""The equilibrium distribution (bouncing_ball.distribution) at any r: the moments of P(x) of
eq. (P(x)1) against the solver's Ito time averages (moments of P(0, v) only), and the moment
identities eqs. (moment1), (moment2) of P(x, v) of eq. (fpsol).  Split from test_distribution.py
because every r costs a build of w(F) (``python -m benchmarks`` times it)."""

from fractions import Fraction

import numpy as np
import pytest
from distribution_support import build, check_moment_identities, check_position_moments

from bouncing_ball import distribution, exact

# 0.15 < r_c: beta > 2; 0.75, 0.9 > sqrt(3) - 1: q < 1/2 (the contour continues the real-axis
# integral of eq. (weightfunc), which diverges there); 0.95, 0.99, 0.999 > RAY_RESTITUTION: the
# contour is the ray arg v = RAY_ANGLE, with P(0, v) solved on it (0.999: the upper end of
# DISTRIBUTION_RESTITUTION_RANGE, a sparse band of ~(1 - r)^(-1/2) nodes)
OTHERS = [0.15, 0.25, 0.6, 0.75, 0.9, 0.95, 0.99, 0.999]


@pytest.fixture(scope="module")
def built():
    return build


@pytest.mark.parametrize("r", OTHERS)
def test_position_moments_match_the_ito_time_averages(r):
    """int P dx = 1, <x> and <x^2> from P(x) against the solver's Ito identities, to 1e-8."""
    check_position_moments(r)


@pytest.mark.parametrize("r", [r for r in OTHERS if r < 0.999])
def test_distribution_obeys_the_moment_identities(r):
    """int P(x, v) dv = P(x), <v>_x = 0, int v^2 P(x, v) dv = int_x^inf P, to 1e-6: at x = 0.5,
    and where r > 0.9 at x = 1e3 (the speeds of P(x, v) reach ~40 / q, whose Airy phase of
    eq. (fpsol) stays below its limit only from x = 60 (v^(3/2) / 6e4)^2 on).  Not at 0.999,
    where that x is 1e6 and the speed integral spans 1e5 (its P(x) is tested above)."""
    check_moment_identities(r, x=0.5 if r <= 0.9 else 1e3)


def test_weight_function_grows_where_q_is_below_one_half(built):
    """At r = 0.9, q < 1/2: w(F) ~ F^(m - 3/2) e^(-S/F) with S < 0 grows without bound as F -> 0
    (ln w + S/F stays moderate), while F^(-1/2) w e^(-1/(12F)) still vanishes."""
    _, weight = built(0.9)
    forces = np.array([2e-3, 5e-3])
    assert weight.small_force_decay < 0.0
    assert np.all(weight.log(forces) > 10.0)
    assert np.all(np.abs(weight.log(forces) + weight.small_force_decay / forces) < 20.0)


# the ray's solve checked where the exact solution continues to it (split from
# tests/unit/test_distribution.py: it compiles and solves the ray's band, as 0.95 - 0.999 above do)
def test_ray_density_matches_the_exact_one_at_one_half(built):
    """P(0, v) solved from eq. (inteq) on the ray arg v = RAY_ANGLE (the sparse band of the ray's
    operator, its LU, the rotated momentum balance) against eq. (P(0,v)) continued to the ray,
    A e^(-v) / v: to 1e-12 from the lowest node u_0 up to the largest |v| used (the rule's error
    exp(-2 pi^2 / (3 h)) is below rounding at the ray's step h = 0.125), and within 2 u_0 below
    it, where the power law C v^-beta drops the next term of P(0, v), of relative order u_0."""
    solution, _ = built(Fraction(1, 2))
    density = distribution._ray_density(solution)
    lowest = solution.speeds[0]
    rho = np.geomspace(1e-3 * lowest, density.largest, 60)
    v = rho * density.ray
    expected = np.log(exact.normalization_constant("1/2")) - v - np.log(v)
    deviation = np.abs(np.expm1(density.log_density(rho) - expected))
    assert np.max(deviation[rho >= lowest]) < 1e-12
    assert np.max(deviation[rho < lowest]) < 2.0 * lowest
    assert abs(density.eigenvalue - 1.0) < 1e-12 and density.error < 1e-12
