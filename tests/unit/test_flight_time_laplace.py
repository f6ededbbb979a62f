"""The flight time's Laplace transform, eq. (laplaceT) of ``flight_time``, and what follows from it.

S0 of eq. (S0) and its derivative are checked against a double quadrature of their g-integrals,
with K_(i g)(x) from its t-integral (nothing of the closed form's derivation is used); eq.
(laplaceT) against the Laplace transform of the flight-time density f(t | u); the expansion of J
at th = 2 pi/3 + eps; and the closed forms (meanT), (meanT2) against E[T | u], E[T^2 | u] written
through S0.  The quadratures' tolerances come from their own error estimates.
"""

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import flight_time as ft

ARGUMENTS = [1e-4, 0.01, 0.3, 1.0, 5.0, 20.0, 100.0, 300.0]  # 100, 300: S0's large-x series
MOMENT_SPEEDS = np.geomspace(1e-3, 50.0, 200)
CLOSED_FORM_TOLERANCE = 1e-12
# the contour Im t = CONTOUR_SHIFT for K_(i g) under J's weight g sinh(g th), which grows like
# e^((pi/3 + eps) g): K_(i g) ~ e^(-pi g / 2) is then a cancellation of terms of size e^(-1.2 g),
# not of size 1, and the rounding error, times the weight, still decays in g
CONTOUR_SHIFT = 1.2
TIME_STEP = 0.01  # trapezoidal steps in t (K_(i g)) and in g (the order integral) of the finer
ORDER_STEP = 0.1  # of the two rules; the coarser one has twice the steps


def _order_integral(x, weight, shift, power, cutoff, order_step, time_step):
    """int_0^cutoff dg weight(g) (-d/dx)^power K_(i g)(x) / cosh(pi g / 3) and the sum of the
    moduli of its terms, by the trapezoidal rule in g and in t for

        K_(i g)(x) = (1/2) int dt e^(-x cosh t + i g t)
                   = e^(-g shift) int_0^inf ds Re[e^(-x cosh(s + i shift) + i g s)],

    the real line moved to Im t = shift (0 <= shift < pi/2: nothing is crossed; (-d/dx)^power
    brings cosh(s + i shift)^power).  Both integrands are even in their variable and analytic in
    a strip, so the rules converge exponentially.  t is cut where x cos(shift) (cosh s - 1) = 60,
    e^-60 of the peak."""
    end = np.arccosh(1.0 + 60.0 / (x * np.cos(shift)))
    s = np.arange(0.0, end + 0.5 * time_step, time_step)
    time_weights = np.full(s.size, time_step)
    time_weights[0] *= 0.5
    z = s + 1j * shift
    envelope = np.cosh(z) ** power * np.exp(-x * (np.cosh(z) - 1.0))
    orders = np.arange(0.0, cutoff + 0.5 * order_step, order_step)
    order_weights = np.full(orders.size, order_step)
    order_weights[[0, -1]] *= 0.5
    phase = np.outer(orders, s)
    bessel = (np.cos(phase) * envelope.real - np.sin(phase) * envelope.imag) @ time_weights
    bessel *= np.exp(-x - orders * shift)
    terms = order_weights * weight(orders) / np.cosh(np.pi * orders / 3.0) * bessel
    return terms.sum(), np.abs(terms).sum()


def _sech_bessel_integral(x, weight, shift=0.0, power=0, cutoff=40.0):
    """int_0^inf dg weight(g) (-d/dx)^power K_(i g)(x) / cosh(pi g / 3) by ``_order_integral``
    with the steps ORDER_STEP, TIME_STEP, and a bound on its error: its difference from the rule
    with twice the steps (which bounds that rule's error, and so this one's) plus 1e-14 of the
    sum of the moduli of the terms (rounding).  The integrand beyond the cutoff is below e^-30
    of the rest for the weights used here (|K_(i g)| < e^(-pi g / 2) K_0)."""
    fine, moduli = _order_integral(x, weight, shift, power, cutoff, ORDER_STEP, TIME_STEP)
    coarse, _ = _order_integral(x, weight, shift, power, cutoff, 2 * ORDER_STEP, 2 * TIME_STEP)
    return fine, abs(fine - coarse) + 1e-14 * moduli


@pytest.mark.parametrize("x", ARGUMENTS)
def test_sech_bessel_moment_is_its_integral(x):
    """Eq. (S0): the erfcx closed form (the asymptotic series above x = 80) is
    int_0^inf dg g^2 K_(i g)(x) / cosh(pi g / 3) to within the quadrature's error, which is far
    below S0 itself (so a wrong coefficient is caught)."""
    value, error = _sech_bessel_integral(x, lambda g: g * g)
    assert error < 1e-9 * abs(value)
    closed = float(ft.sech_bessel_moment(x))
    # 1e-12: the closed form's own rounding (x^2 times erfcx's below x = 80)
    assert abs(closed - value) <= error + 1e-12 * abs(value)


@pytest.mark.parametrize("x", ARGUMENTS)
def test_sech_bessel_moment_derivative_is_its_integral(x):
    """S0'(x) = -int dg g^2 / cosh(pi g / 3) int dt cosh(t) e^(-x cosh t) cos(g t), by quadrature."""
    value, error = _sech_bessel_integral(x, lambda g: -g * g, power=1)
    assert error < 1e-9 * abs(value)
    closed = float(ft.sech_bessel_moment_derivative(x))
    assert abs(closed - value) <= error + 1e-12 * abs(value)


@pytest.mark.parametrize("x", [1e-3, 0.2, 3.0, 30.0, 79.9, 80.0, 150.0])
def test_sech_bessel_moment_derivative_is_its_derivative(x):
    """S0' against a central difference of S0 (steps h and h/2, Richardson), on both sides of the
    series switch at x = 80."""
    h = 1e-2 * min(x, 1.0)  # S0 varies on the scale min(x, 1)

    def central(step):
        return (ft.sech_bessel_moment(x + step) - ft.sech_bessel_moment(x - step)) / (2.0 * step)

    coarse, fine = central(h), central(0.5 * h)
    richardson = (4.0 * fine - coarse) / 3.0
    # the extrapolated difference's truncation is about (h / min(x, 1))^2 = 1e-4 times
    # |fine - coarse| (allowed: 1e-2 times); rounding: S0's (relative 1e-12 at most) over h/2
    tolerance = 1e-2 * abs(fine - coarse) + 4e-12 * abs(float(ft.sech_bessel_moment(x))) / h
    assert abs(float(ft.sech_bessel_moment_derivative(x)) - richardson) <= tolerance
    assert tolerance < 1e-6 * abs(richardson)


def test_sech_bessel_moment_limits_and_bad_input():
    """S0(0) = 0 and S0'(0) = pi (S0 = pi x + O(x^(3/2))); x < 0 or NaN raises."""
    assert float(ft.sech_bessel_moment(0.0)) == 0.0
    assert float(ft.sech_bessel_moment_derivative(0.0)) == pytest.approx(np.pi, rel=1e-15)
    with pytest.raises(ValueError, match="sech_bessel_moment"):
        ft.sech_bessel_moment(-1.0)
    with pytest.raises(ValueError, match="sech_bessel_moment_derivative"):
        ft.sech_bessel_moment_derivative([1.0, np.nan])


def _laplace_kernel_integral(theta, x):
    """J(th, x) of eq. (laplaceT) by nested quadrature (K_(i g) on the shifted contour), with its
    error bound; th <= 2 pi/3 + 0.05, so the integrand decays at least like e^(-0.47 g)."""
    return _sech_bessel_integral(
        x, lambda g: g * np.sinh(g * theta), shift=CONTOUR_SHIFT, cutoff=90.0
    )


@pytest.mark.parametrize("sigma, u", [(0.3, 1.0), (1.5, 0.2), (0.05, 4.0)])
def test_laplace_transform_of_flight_time(sigma, u):
    """Eq. (laplaceT): e^(u/2) J(th, kappa u) / (pi u kappa sin th) is int dt e^(-sigma t) f(t | u)
    (f from eq. (joint), item 5 of ``flight_time``)."""
    kappa = np.sqrt(1.0 + 4.0 * sigma)
    theta = np.arccos(-0.5 / kappa)
    j, j_error = _laplace_kernel_integral(theta, kappa * u)
    factor = np.exp(0.5 * u) / (np.pi * u * kappa * np.sin(theta))

    def integrand(log_t):
        t = np.exp(log_t)
        return t * np.exp(-sigma * t) * ft.flight_time_density(t, u)

    points = sorted([np.log(u * u), np.log(2.0 * u + 1.0)])
    direct, direct_error = integrate.quad(
        integrand, -40.0, 7.0, points=points, epsabs=0.0, epsrel=1e-12, limit=400
    )
    # f(t | u) is a Gauss-Legendre sum good to about 1e-13 relative
    tolerance = factor * j_error + direct_error + 1e-11 * direct
    assert abs(factor * j - direct) <= tolerance
    assert tolerance < 1e-8 * direct


def test_laplace_kernel_expansion_is_cubic():
    """J(2 pi/3 + eps, x) = pi x sin(pi/3 + eps) e^(-x cos(pi/3 + eps)) - eps S0(x) + O(eps^3):
    the remainder is -eps^3 S4(x) / 6 - eps^5 S6(x) / 120 - ..., S_n = int dg g^n K_(i g)(x) /
    cosh(pi g / 3), so it differs from -eps^3 S4 / 6 by less than 2 eps^5 S6 / 120 (here about
    3e-4 of it: a relative error of S0 above about 1e-6 is caught)."""
    x = 1.5
    s4, s4_error = _sech_bessel_integral(x, lambda g: g**4)
    s6, s6_error = _sech_bessel_integral(x, lambda g: g**6)
    for eps in (0.04, -0.04, 0.02):
        j, j_error = _laplace_kernel_integral(2.0 * np.pi / 3.0 + eps, x)
        alpha = np.pi / 3.0 + eps
        leading = np.pi * x * np.sin(alpha) * np.exp(-x * np.cos(alpha))
        remainder = j - leading + eps * float(ft.sech_bessel_moment(x))
        cubic = -(eps**3) * s4 / 6.0
        tolerance = (
            j_error + abs(eps) ** 3 * s4_error / 6.0 + 2.0 * abs(eps) ** 5 * (s6 + s6_error) / 120.0
        )
        assert abs(remainder - cubic) <= tolerance
        assert tolerance < 1e-3 * abs(cubic)


def _moments_from_sech_bessel_moment(u):
    """E[T | u] and E[T^2 | u] written through S0 and S0' (the second-order expansion of
    eq. (laplaceT) in sigma)."""
    s0, s0_prime = ft.sech_bessel_moment(u), ft.sech_bessel_moment_derivative(u)
    growth = np.exp(0.5 * u)
    first = 2.0 * u + 4.0 / 3.0 - 4.0 * growth * s0 / (3.0 * np.pi * u)
    second = (
        4.0 * u * u
        + 32.0 * u / 3.0
        + 32.0 / 3.0
        - 16.0 * growth * s0 / (np.pi * u)
        + 16.0 * growth * s0_prime / (3.0 * np.pi)
    )
    return first, second


def test_mean_flight_time_closed_form_is_laplace_expansion():
    """Eq. (meanT) equals 2u + 4/3 - 4 e^(u/2) S0(u) / (3 pi u) to rounding, 1e-3 <= u <= 50."""
    first, _ = _moments_from_sech_bessel_moment(MOMENT_SPEEDS)
    closed = ft.mean_flight_time_given_speed(MOMENT_SPEEDS)
    assert np.max(np.abs(first / closed - 1.0)) < CLOSED_FORM_TOLERANCE


def test_second_moment_closed_form_is_laplace_expansion():
    """Eq. (meanT2) equals 4u^2 + 32u/3 + 32/3 - 16 e^(u/2) S0(u) / (pi u)
    + 16 e^(u/2) S0'(u) / (3 pi) to rounding, 1e-3 <= u <= 50."""
    _, second = _moments_from_sech_bessel_moment(MOMENT_SPEEDS)
    closed = ft.flight_time_second_moment_given_speed(MOMENT_SPEEDS)
    assert np.max(np.abs(second / closed - 1.0)) < CLOSED_FORM_TOLERANCE
