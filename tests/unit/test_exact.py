"""The exact r = 1/2 and 1/3 solutions: w(F), P(x, v), and the identities they must obey."""

import warnings
from fractions import Fraction

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import exact

EXACT = [Fraction(1, 2), Fraction(1, 3)]


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_weight_function_normalised(r):
    """eq. (normalization2): int dF F^(-3/2) w(F) exp(-1/(12F)) = 1 with w of eq. (weightfunc2)."""

    def integrand(log_f):
        f = np.exp(log_f)
        return f**-0.5 * exact.weight_function(f, r) * np.exp(-1.0 / (12.0 * f))

    value, _ = integrate.quad(integrand, -10.0, 40.0, limit=400, epsrel=1e-12)
    assert value == pytest.approx(1.0, rel=1e-10)


@pytest.mark.parametrize("r", EXACT, ids=str)
@pytest.mark.parametrize("x", [0.05, 3.0])
def test_position_density_from_weight_function(r, x):
    """eq. (P(x)1) with w of eq. (weightfunc2) gives eq. (P(x)2)."""

    def integrand(log_f):
        f = np.exp(log_f)
        return f * f**-0.5 * exact.weight_function(f, r) * np.exp(-1.0 / (12.0 * f) - f * x)

    value, _ = integrate.quad(integrand, -10.0, np.log(80.0 / x), limit=400, epsrel=1e-12)
    assert value == pytest.approx(float(exact.position_density(x, r)), rel=1e-9)


def _speed_moments(x, r):
    """int v^n P(x, v) dv for n = 0, 1, 2 on a composite Gauss-Legendre grid in v."""
    nodes, weights = np.polynomial.legendre.leggauss(24)
    edges = [-80.0, -30.0, -10.0, -3.0, -1.0, 0.0, 1.0, 3.0, 7.0, 14.0, 26.0]
    v = np.concatenate(
        [0.5 * (b - a) * nodes + 0.5 * (b + a) for a, b in zip(edges[:-1], edges[1:])]
    )
    w = np.concatenate([0.5 * (b - a) * weights for a, b in zip(edges[:-1], edges[1:])])
    with warnings.catch_warnings():
        # far out on the outgoing side the F integral cancels to e^{-v/2}; its error there is negligible
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        p = exact.distribution(x, v, r)
    return [float(np.sum(w * v**n * p)) for n in (0, 1, 2)], float(np.sum(w * np.abs(v) * p))


@pytest.mark.parametrize("r", EXACT, ids=str)
@pytest.mark.parametrize("x", [0.1, 1.0])
def test_distribution_obeys_moment_identities(r, x):
    """P(x, v) of eqs. (fpsol), (psi) integrates to P(x), has <v>_x = 0, eq. (moment1),
    and <v^2>_x of eq. (moment2)."""
    (zeroth, first, second), absolute_first = _speed_moments(x, r)
    px = float(exact.position_density(x, r))
    assert zeroth == pytest.approx(px, rel=1e-6)
    assert abs(first) <= 1e-6 * absolute_first
    assert second / zeroth == pytest.approx(
        float(exact.mean_speed_squared_given_position(x, r)), rel=1e-6
    )


@pytest.mark.parametrize("r", EXACT, ids=str)
@pytest.mark.parametrize("v", [-8.0, -3.0, -1.0, -0.2])
def test_weight_function_gives_the_incoming_boundary_values(r, v):
    """At x = 0 on the incoming side the F integral of eq. (fpsol) converges absolutely: with
    w(F) of eq. (weightfunc2) and A of eq. (constants) it must give eq. (bc),
    P(0, -|v|) = r^2 P(0, r |v|), with P(0, .) of eq. (P(0,v))."""
    value, _ = exact.distribution_by_force_integral(0.0, v, r)
    expected = float(r) ** 2 * exact.outgoing_speed_density(-float(r) * v, r)
    assert value == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_distribution_tends_to_boundary_values(r):
    """As x -> 0, P(x, v) tends to eq. (P(0,v)) for v > 0 and to eq. (bc) for v < 0,
    with a difference linear in x."""
    v = np.array([-3.0, -1.0, 1.0, 3.0])
    at_zero = exact.distribution(0.0, v, r)
    errors = [np.max(np.abs(exact.distribution(x, v, r) / at_zero - 1.0)) for x in (1e-4, 1e-5)]
    assert errors[0] < 1e-3 and 8.0 < errors[0] / errors[1] < 12.0, errors


def test_mean_speed_squared_agrees_between_forms():
    # r = 1/2 has the closed form u K1(u) / P(x); the r = 1/3 route (quadrature) must agree with it
    x = np.array([0.01, 1.0, 10.0])
    closed = exact.mean_speed_squared_given_position(x, Fraction(1, 2))
    tail = [
        integrate.quad(lambda y: float(exact.position_density(y, 0.5)), xi, np.inf)[0] for xi in x
    ]
    np.testing.assert_allclose(closed, np.array(tail) / exact.position_density(x, 0.5), rtol=1e-9)


@pytest.mark.parametrize("x", [0.01, 1.0, 100.0, 300.0, 1000.0])
def test_mean_speed_squared_at_one_third_holds_far_out(x):
    """<v^2>_x P(x) = int_x^inf P, eq. (moment2), at r = 1/3 out to the end of the exact
    position grid: the integral taken in ln x' (where P spans its decades evenly).  A
    quadrature of P over [x, inf) in x' is 7% off at x = 1000 and 1e-5 at 300."""
    r = Fraction(1, 3)
    tail = integrate.quad(
        lambda u: np.exp(u) * float(exact.position_density(np.exp(u), r)),
        np.log(x),
        np.log(x) + 8.0,  # eight e-folds of x' in ln x', the rest in x'
        epsrel=1e-11,
        limit=400,
    )[0]
    tail += integrate.quad(
        lambda y: float(exact.position_density(y, r)), x * np.exp(8.0), np.inf, limit=400
    )[0]
    value = exact.mean_speed_squared_given_position(np.array([x]), r)[0]
    assert value * exact.position_density(x, r) == pytest.approx(tail, rel=1e-9, abs=0)


@pytest.mark.parametrize("r", EXACT, ids=str)
@pytest.mark.parametrize("lo, hi", [(1e-4, 1.26e-4), (0.3, 0.4), (25.0, 31.6), (40.0, 50.0)])
def test_bin_average_of_the_outgoing_density(r, lo, hi):
    """int v P(0,v) dv / int v dv over a bin, closed form against quadrature of eq. (P(0,v)),
    also far in the tail (where a difference of regularised gamma functions near 1 would cancel)."""
    direct, _ = integrate.quad(
        lambda v: v * exact.outgoing_speed_density(v, r), lo, hi, epsrel=1e-13
    )
    closed = exact.outgoing_speed_bin_average(np.array([lo]), np.array([hi]), r)[0]
    assert closed == pytest.approx(direct / (0.5 * (hi * hi - lo * lo)), rel=1e-12)


def test_gauss_kronrod_rule_is_exact_to_its_degrees():
    """The 21-point Kronrod rule integrates x^k over [-1, 1] exactly up to k = 31, its embedded
    10-point Gauss rule up to k = 19 and not at k = 20: the constants are QUADPACK's dqk21."""
    nodes = exact.KRONROD_NODES

    def moment(k):
        return 2.0 / (k + 1) if k % 2 == 0 else 0.0

    for k in range(32):
        assert np.sum(exact.KRONROD_WEIGHTS * nodes**k) == pytest.approx(moment(k), abs=1e-15)
    for k in range(20):
        assert np.sum(exact.GAUSS_WEIGHTS * nodes**k) == pytest.approx(moment(k), abs=1e-15)
    assert abs(np.sum(exact.GAUSS_WEIGHTS * nodes**20) - moment(20)) > 1e-8


# (x, v) where the F integral is smooth (v < 0), turns over (v ~ 0) and oscillates (v > 0,
# small x: hundreds of periods at x = 0.001, v = 6)
SAMPLE_POINTS = [(0.001, 6.0), (0.001, 0.5), (0.001, -3.0), (0.01, 4.5), (0.1, -0.05), (2.0, 1.0)]


@pytest.mark.parametrize("r", EXACT, ids=str)
def test_distribution_arrays_agree_with_one_point_quad(r):
    """P(x, v) for arrays (every point at once, adaptive Gauss-Kronrod) against
    distribution_by_force_integral (scipy's quad, one point): within the sum of the two error
    estimates and 1e-10 relative, each estimate below 1e-9 relative."""
    x, v = np.array(SAMPLE_POINTS).T
    values, errors = exact.distribution_with_error(x, v, r)
    theirs, their_errors = np.array(
        [exact.distribution_by_force_integral(xi, vi, r) for xi, vi in SAMPLE_POINTS]
    ).T
    assert np.all(np.abs(values - theirs) <= errors + their_errors)
    assert np.max(np.abs(values / theirs - 1.0)) < 1e-10
    assert np.max(errors / values) < 1e-9


@pytest.mark.parametrize(
    ("r", "mean_x", "delta_x"),
    [
        (Fraction(1, 2), 6.0, 6.0 * np.sqrt(3.0)),
        (Fraction(1, 3), 35.0 / 9.0, np.sqrt(4781.0) / 9.0),
    ],
    ids=["1/2", "1/3"],
)
def test_position_moments_are_the_closed_forms(r, mean_x, delta_x):
    """<x> and Delta x from the moments of P(x), eq. (P(x)2), each to 1e-12 relative: the
    closed forms of eq. (xandDeltax) (6, 6 3^(1/2); 35/9, 4781^(1/2)/9), to the moments'
    tolerance (Delta x^2 = <x^2> - <x>^2 loses a factor <x^2>/Delta x^2 < 1.3 of it)."""
    moments = exact.position_moments(r)
    assert moments["normalization"] == pytest.approx(1.0, rel=1e-12)
    assert moments["mean_x"] == pytest.approx(mean_x, rel=2e-12)
    assert moments["delta_x"] == pytest.approx(delta_x, rel=2e-12)
