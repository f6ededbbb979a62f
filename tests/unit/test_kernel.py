"""G_g(v, u) of eq. (kernel3) in its stable form: symmetry, eq. (normG), the printed forms."""

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball.kernel import kernel_small_u_limit, return_speed_density, return_speed_kernel

SPEEDS = np.geomspace(1e-12, 1e3, 46)


def test_symmetric_and_finite_over_the_whole_range():
    v, u = np.meshgrid(SPEEDS, SPEEDS, indexing="ij")
    g = return_speed_kernel(v, u)
    assert np.all(np.isfinite(g)) and np.all(g >= 0.0)
    positive = g > 0.0
    # below ~1e-300 the kernel underflows (v, u ~ 1e3 apart); everywhere else it is symmetric
    assert positive.mean() > 0.9
    np.testing.assert_allclose(g[positive], g.T[positive], rtol=1e-10, atol=0.0)


def _printed_kernel3(v, u):
    """Eq. (kernel3) exactly as printed, by adaptive quadrature (safe for moderate v, u)."""

    def integrand(y):
        z = np.sqrt(v * v - v * u + u * u + 3.0 * v * u * y * y)
        return np.exp(-z) * (z**-3 + z**-2)

    width = np.sqrt((v + u) / (6.0 * v * u))
    points = [p for p in (0.5 * width, width, 2.0 * width, 4.0 * width) if p < 1.0]
    value, _ = integrate.quad(
        integrand, 0.0, 1.0, points=points or None, epsabs=0.0, epsrel=1e-13, limit=200
    )
    return 1.5 / np.pi * np.sqrt(v * u) * np.exp(0.5 * (v + u)) * value


@pytest.mark.parametrize("v", [1e-4, 0.03, 0.5, 2.0, 7.0, 30.0])
@pytest.mark.parametrize("u", [2e-3, 0.2, 1.0, 5.0, 40.0])
def test_equals_printed_form_where_that_is_safe(v, u):
    assert return_speed_kernel(v, u) == pytest.approx(_printed_kernel3(v, u), rel=1e-10)


def _bessel_k_imaginary_order(gamma, x):
    """K_{i gamma}(x) = int_0^inf e^{-x cosh t} cos(gamma t) dt."""
    upper = np.arccosh(1.0 + 60.0 / x)
    value, _ = integrate.quad(
        lambda t: np.exp(-x * np.cosh(t)), 0.0, upper, weight="cos", wvar=gamma, limit=400
    )
    return value


def _kernel2(v, u):
    """Eq. (kernel2), the Kontorovich-Lebedev form."""

    def integrand(gamma):
        ratio = np.sinh(np.pi * gamma) / np.cosh(np.pi * gamma / 3.0)
        return (
            gamma
            * ratio
            * _bessel_k_imaginary_order(gamma, v)
            * _bessel_k_imaginary_order(gamma, u)
        )

    value, _ = integrate.quad(integrand, 0.0, 18.0, limit=400, epsrel=1e-12)
    return np.exp(0.5 * (v + u)) / (np.pi**2 * v * u) * value


@pytest.mark.parametrize(("v", "u"), [(1.0, 1.0), (0.7, 2.0), (2.5, 1.5)])
def test_equals_kontorovich_lebedev_form(v, u):
    # the integrand falls like exp(-pi gamma / 3): cut at gamma = 18 it misses ~1e-8;
    # beyond, K_{i gamma} ~ exp(-pi gamma / 2) is lost to cancellation in its cos integral
    assert return_speed_kernel(v, u) == pytest.approx(_kernel2(v, u), rel=1e-7)


@pytest.mark.parametrize("u", np.geomspace(1e-6, 100.0, 9))
def test_return_probability_is_one(u):
    """Eq. (normG): int_0^inf dv v G_g(v, u) = 1, to 1e-10."""

    def integrand(log_v):
        v = np.exp(log_v)
        return float(v * v * return_speed_kernel(v, u))

    # the return speed is ~ u +- (4u/3)^(1/2) for large u; for small u, scale-free around u
    centre = np.log(u)
    spread = np.log1p(8.0 / np.sqrt(u)) if u > 1.0 else 3.0
    points = sorted({centre - spread, centre, centre + spread})
    lo, hi = centre - 60.0, max(centre + 60.0, np.log(u + 80.0 * np.sqrt(u) + 80.0))
    total = sum(
        integrate.quad(integrand, a, b, epsabs=0.0, epsrel=1e-13, limit=400)[0]
        for a, b in zip([lo, *points], [*points, hi])
    )
    assert total == pytest.approx(1.0, abs=1e-10)


def test_small_u_limit():
    # the limit's relative correction is O(u max(1, 1 / v)) (its docstring): u / 2 at v = 20
    v = np.array([1e-3, 0.5, 3.0, 20.0])
    u = 1e-9 * v
    relative = return_speed_kernel(v, u) / kernel_small_u_limit(v, u) - 1.0
    assert np.all(np.abs(relative) <= u * np.maximum(1.0, 1.0 / v))


@pytest.mark.parametrize(
    ("v", "u"),
    [(1e155, 1.0), (1e200, 1.0), (1.0, 1e300), (1e300, 1e300), (1e-200, 1e-200), (100.0, 5e-324)],
)
def test_return_speed_density_is_finite_at_extreme_speeds(v, u):
    """v G_g(v, u) in logs: 0 where it underflows, never NaN; where it is positive, the
    scale-free limits hold: v G_g(v, v) (v)^(1/2) -> 0.3454941494712 for large v (the Gaussian
    peak of width ~v^(1/2)), v G_g ~ (3^(1/2) / pi) / (2 v) ... at v = u -> 0 and the small-u
    limit at u << v."""
    value = float(return_speed_density(v, u))
    assert np.isfinite(value) and value >= 0.0
    if v == u and v > 1.0:
        assert value * np.sqrt(v) == pytest.approx(0.3454941494712, rel=1e-10)
    elif v == u:
        # scale-free: v G_g(v, v) = 1 / v times its value at v = u = 1e-100, to rounding
        assert value * v == pytest.approx(float(return_speed_density(1e-100, 1e-100)) * 1e-100)
    elif u < 1e-300:
        assert value == pytest.approx(v * kernel_small_u_limit(v, u), rel=1e-12)
    else:
        assert value == 0.0  # e^(-(3/4) v) underflows


def test_tau_rule_is_converged():
    """The fixed Gauss-Legendre rule of the tau integral against a 64-node rule, over
    v in [1e-5, 200] and u in [1e-12, 200]: far below the solver's 1e-11."""
    from bouncing_ball.kernel import _kernel_matrix, return_speed_kernel_matrix

    v, u = np.geomspace(1e-5, 200.0, 150), np.geomspace(1e-12, 200.0, 160)
    nodes, weights = np.polynomial.legendre.leggauss(64)
    reference = _kernel_matrix(v, u, 0.5 * (nodes + 1.0), 0.5 * weights)
    rule = return_speed_kernel_matrix(v, u)
    resolved = reference > 1e-300
    assert np.max(np.abs(rule[resolved] / reference[resolved] - 1.0)) < 1e-12


@pytest.mark.parametrize("u", [50.0, 400.0])
def test_return_speed_spread_is_four_thirds_of_the_outgoing_speed(u):
    """A ball leaving with speed u returns with mean u + 4/3 and variance 4u/3 + 8/9, up to
    terms exponentially small in u (Ito: E[v | u] = E[T | u] - u, E[v^2 | u] = u^2 + 2 E[T | u],
    E[T | u] = 2u + 4/3 + O(e^(-u/2))), so its standard deviation is
    (4u/3)^(1/2) (1 + 2/(3u))^(1/2), between (4u/3)^(1/2) and (4u/3)^(1/2) (1 + 1/(3u)):
    ~1.15 u^(1/2), the spread the solver's u^(1/2) spacing follows (docs/methods.md)."""
    spread = np.sqrt(u)

    def moment(power):
        def integrand(v):
            return float(v**power * return_speed_density(v, u))

        edges = [0.0, u - 6.0 * spread, u, u + 6.0 * spread, u + 40.0 * spread]  # u >= 50
        return sum(
            integrate.quad(integrand, a, b, epsabs=0.0, epsrel=1e-13, limit=200)[0]
            for a, b in zip(edges[:-1], edges[1:])
        )

    total, first, second = (moment(power) for power in range(3))
    mean = first / total
    variance = second / total - mean**2
    assert mean == pytest.approx(u + 4.0 / 3.0, rel=1e-11)
    assert variance == pytest.approx(4.0 * u / 3.0 + 8.0 / 9.0, rel=1e-9)
    excess = np.sqrt(variance / (4.0 * u / 3.0)) - 1.0
    assert 0.0 < excess <= 1.0 / (3.0 * u)
