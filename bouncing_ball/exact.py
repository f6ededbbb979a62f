"""The paper's exact solutions at r = 1/2 and r = 1/3.

eq. (P(0,v)) with the constants of eq. (constants), and P(x) of eq. (P(x)2).
The time averages <x>, Delta x and the collision rate I of eq. (xandDeltax)
are computed here from these distributions (not copied from the paper), so
that a test can compare them with the paper's closed forms.
"""

import functools
import math
from fractions import Fraction

import numpy as np
import pandas as pd
from scipy import integrate, special

from .distribution import check_force_integral_point
from .restitution import EXACT_RESTITUTIONS, parse_restitution


@functools.lru_cache(maxsize=64)  # called per point by the scalar integrands below
def _which(restitution) -> Fraction:
    """r (a float, or a fraction string such as "1/3") as 1/2 or 1/3; ValueError otherwise."""
    given = parse_restitution(restitution, "restitution")
    value = given.limit_denominator(1000)
    if value not in EXACT_RESTITUTIONS or abs(float(value) - float(given)) > 1e-12:
        raise ValueError(f"exact solutions exist only for r = 1/2 and 1/3, not r = {restitution}")
    return value


def normalization_constant(restitution) -> float:
    """A_{1/2} = 1/3 and A_{1/3} = (27 / (32 pi))^(1/2), eq. (constants)."""
    if _which(restitution) == Fraction(1, 2):
        return 1.0 / 3.0
    return np.sqrt(27.0 / (32.0 * np.pi))


def outgoing_speed_density(v, restitution):
    """P(0, v) for v > 0 (outgoing side), eq. (P(0,v)); the incoming side is eq. (bc)."""
    v = np.asarray(v, dtype=float)
    if np.any(~(v >= 0.0)):
        raise ValueError(
            "v: P(0, v) is the density of outgoing speeds, v >= 0; "
            "the incoming side is r^2 P(0, r |v|), eq. (bc)"
        )
    a = normalization_constant(restitution)
    if _which(restitution) == Fraction(1, 2):
        return a * np.exp(-v) / v
    return a * v**-1.5 * np.exp(-1.5 * v)


def outgoing_speed_bin_average(lo, hi, restitution):
    """int_lo^hi v P(0,v) dv / int_lo^hi v dv, the quantity a simulation bin measures."""
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    a = normalization_constant(restitution)
    if _which(restitution) == Fraction(1, 2):
        rate = (
            a * np.exp(-lo) * -np.expm1(lo - hi)
        )  # int v^0 e^{-v}, no cancellation in narrow bins
    else:
        # int v^{-1/2} e^{-3v/2} dv = Gamma(1/2) (3/2)^{-1/2} [P(1/2, 3v/2)]
        # (the upper functions Q in the tail, where P -> 1 would cancel)
        scale = special.gamma(0.5) / np.sqrt(1.5)
        tail = 1.5 * lo > 0.5
        lower = special.gammainc(0.5, 1.5 * hi) - special.gammainc(0.5, 1.5 * lo)
        upper = special.gammaincc(0.5, 1.5 * lo) - special.gammaincc(0.5, 1.5 * hi)
        rate = a * scale * np.where(tail, upper, lower)
    return rate / (0.5 * (hi**2 - lo**2))


def position_density(x, restitution):
    """P(x), eq. (P(x)2)."""
    x = np.asarray(x, dtype=float)
    if _which(restitution) == Fraction(1, 2):
        return special.k0(np.sqrt(2.0 * x / 3.0)) / 3.0
    return np.vectorize(_position_density_third)(x)


def _position_density_third(x):
    # (1/4 pi) int dF F^-1 K_{1/6}(z) e^{-z - F x}, z = 1/(12 F); in ln F
    def integrand(log_f):
        f = np.exp(log_f)
        z = 1.0 / (12.0 * f)
        return special.kve(1.0 / 6.0, z) * np.exp(-2.0 * z - f * x)

    # e^{-2z} cuts off small F; e^{-F x} (or, at x = 0, nothing) large F
    upper = np.log(60.0 / x) if x > 0.0 else np.inf
    value, _ = integrate.quad(integrand, -8.0, max(upper, 8.0), limit=400, epsabs=0.0, epsrel=1e-11)
    return value / (4.0 * np.pi)


def position_bin_average(lo, hi, restitution):
    """int_lo^hi P(x) dx / (hi - lo)."""
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    if _which(restitution) == Fraction(1, 2):
        # int (1/3) K0(sqrt(2x/3)) dx = -u K1(u), u = sqrt(2x/3)
        def primitive(x):
            u = np.sqrt(2.0 * x / 3.0)
            return np.where(u > 0, -u * special.k1(np.where(u > 0, u, 1.0)), -1.0)

        return (primitive(hi) - primitive(lo)) / (hi - lo)
    averages = [
        integrate.quad(_position_density_third, a, b, epsrel=1e-10)[0] / (b - a)
        for a, b in zip(np.atleast_1d(lo), np.atleast_1d(hi))
    ]
    return np.asarray(averages).reshape(np.shape(lo))


def speed_squared_given_position_bin_average(lo, hi, restitution):
    """<v^2>_x of eq. (moment2) averaged over [lo, hi) with weight P(x).

    That is int_bin dx int_x^inf P(x') dx' / int_bin P(x) dx, the quantity a
    simulation bin measures.  For r = 1/2, int_x^inf P = u K1(u) with
    u = sqrt(2x/3), and int u K1(u) dx = -3 u^2 K2(u).  For r = 1/3 both
    integrals over x are done under the integral over F of eq. (P(x)2):
    int_lo^hi dx int_x^inf e^{-F x'} dx' = (e^{-F lo} - e^{-F hi}) / F^2.
    """
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    if _which(restitution) == Fraction(1, 2):

        def primitive(x):
            u = np.sqrt(2.0 * x / 3.0)
            safe = np.where(u > 0, u, 1.0)
            return np.where(u > 0, -3.0 * safe**2 * special.kn(2, safe), -6.0)

        numerator = primitive(hi) - primitive(lo)
    else:
        numerator = np.asarray(
            [_tail_integral_third(a, b) for a, b in zip(np.atleast_1d(lo), np.atleast_1d(hi))]
        ).reshape(np.shape(lo))
    return numerator / (position_bin_average(lo, hi, restitution) * (hi - lo))


def _tail_integral_third(lo, hi):
    # int_lo^hi dx int_x^inf P(x') dx' at r = 1/3: (1/4 pi) int dF F^-1 K_{1/6}(z) e^{-z}
    # (e^{-F lo} - e^{-F hi}) / F^2, z = 1/(12 F), in ln F as in _position_density_third
    def integrand(log_f):
        f = np.exp(log_f)
        z = 1.0 / (12.0 * f)
        difference = np.exp(-f * lo) * -np.expm1(-f * (hi - lo))
        return special.kve(1.0 / 6.0, z) * np.exp(-2.0 * z) * difference / (f * f)

    # e^{-F lo} cuts off large F; at lo = 0 the integrand decays only as F^{-5/6} in ln F
    upper = np.log(60.0 / lo) if lo > 0.0 else np.log(1.0e16 / hi)
    value, _ = integrate.quad(integrand, -8.0, max(upper, 8.0), limit=400, epsabs=0.0, epsrel=1e-11)
    return value / (4.0 * np.pi)


def position_moments(restitution) -> dict:
    """<x>, Delta x (eq. (xandDeltax)) from P(x), and I from eq. (collrate)."""
    moments = []
    for k in (0, 1, 2):
        # x = 3 u^2 / 2 makes the decay exp(-u) for both r
        def integrand(u, k=k):
            x = 1.5 * u * u
            return x**k * float(position_density(x, restitution)) * 3.0 * u

        value, _ = integrate.quad(integrand, 0.0, np.inf, limit=400, epsrel=1e-12)
        moments.append(value)
    norm, first, second = moments
    mean_x = first / norm
    a = normalization_constant(restitution)
    # r = 1/2: int_0^inf v * v^-1 e^-v dv
    rate = a if _which(restitution) == Fraction(1, 2) else a * special.gamma(0.5) / np.sqrt(1.5)
    return {
        "normalization": norm,
        "mean_x": mean_x,
        "delta_x": np.sqrt(second / norm - mean_x**2),
        "collision_rate": rate,
    }


def weight_function(force, restitution):
    """w(F) of eq. (weightfunc2) with the constants of eq. (constants)."""
    force = np.asarray(force, dtype=float)
    a = normalization_constant(restitution)
    z = 1.0 / (12.0 * force)
    if _which(restitution) == Fraction(1, 2):
        return 0.5 * a * force**-0.5 * np.exp(-z)
    return np.sqrt(2.0 / (27.0 * np.pi)) * a * force**-0.5 * special.kve(1.0 / 6.0, z) * np.exp(-z)


def _scalar_weight_function(restitution):
    """``weight_function`` for one float F at a time, its constants computed once (quad calls
    the integrand below hundreds of times per point of P(x, v))."""
    a = normalization_constant(restitution)
    if _which(restitution) == Fraction(1, 2):
        c = 0.5 * a

        def weight(force):
            return c * force**-0.5 * math.exp(-1.0 / (12.0 * force))

        return weight
    c = math.sqrt(2.0 / (27.0 * math.pi)) * a
    kve = special.kve

    def weight(force):
        z = 1.0 / (12.0 * force)
        return c * force**-0.5 * float(kve(1.0 / 6.0, z)) * math.exp(-z)

    return weight


def _distribution_integrand(log_force, x, v, weight):
    # e^{-v/2} w(F) e^{-F x} psi_{1/4,F}(-v) F, eqs. (fpsol), (psi); dF = F d(ln F);
    # ``weight``: _scalar_weight_function
    f = math.exp(log_force)
    argument = -(f ** (1.0 / 3.0)) * v + 0.25 * f ** (-2.0 / 3.0)
    airy = float(special.airy(argument)[0])
    return math.exp(-0.5 * v - f * x) * weight(f) * f ** (-1.0 / 6.0) * airy * f


def distribution_by_force_integral(x, v, restitution):
    """P(x, v) of eqs. (fpsol), (psi), (weightfunc2) by integration over F, and quad's error estimate.

    Converges absolutely for x > 0, and for x = 0 on the incoming side v < 0
    (there the Airy function decays); at x = 0, v > 0 only conditionally.
    Returns (value, estimated absolute error).
    """
    xi, vi = float(x), float(v)
    check_force_integral_point(xi, vi)
    # w(F) vanishes like e^{-1/(6F)} at small F; e^{-F x} cuts large F (at x = 0, v < 0 the
    # Airy factor ~ exp(-(2/3) F^(1/2) |v|^(3/2)) does)
    upper = np.log(60.0 / xi) if xi > 0.0 else np.log((90.0 / abs(vi) ** 1.5) ** 2 + 1.0)
    value, error, *_ = integrate.quad(
        _distribution_integrand,
        -6.0,
        upper,
        args=(xi, vi, _scalar_weight_function(restitution)),
        limit=2000,
        epsabs=0.0,
        epsrel=1e-10,
        full_output=1,
    )
    return value, error


def distribution_with_error(x, v, restitution):
    """P(x, v) and an estimate of its absolute error, for broadcast arrays x >= 0 and v.

    At x = 0 the outgoing side is eq. (P(0,v)) and the incoming side the
    boundary condition eq. (bc), P(0, -v) = r^2 P(0, r v) (the F integral
    converges only conditionally there); P(0, 0) diverges and is NaN.
    """
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v, dtype=float))
    for index in np.ndindex(x.shape):
        if x[index] != 0.0:
            check_force_integral_point(float(x[index]), float(v[index]))
    values, errors = np.empty(x.shape), np.zeros(x.shape)
    r = float(_which(restitution))
    for index in np.ndindex(x.shape):
        xi, vi = float(x[index]), float(v[index])
        if xi == 0.0:
            if vi > 0.0:
                values[index] = outgoing_speed_density(vi, restitution)
            elif vi < 0.0:
                values[index] = r * r * outgoing_speed_density(-r * vi, restitution)
            else:
                values[index] = np.nan
            continue
        values[index], errors[index] = distribution_by_force_integral(xi, vi, restitution)
    return values, errors


def distribution(x, v, restitution):
    """P(x, v), eqs. (fpsol), (psi), (weightfunc2); see ``distribution_with_error``."""
    return distribution_with_error(x, v, restitution)[0]


def mean_speed_squared_given_position(x, restitution):
    """<v^2>_x = P(x)^-1 int_x^inf P(x') dx', eq. (moment2)."""
    x = np.asarray(x, dtype=float)
    if _which(restitution) == Fraction(1, 2):
        u = np.sqrt(2.0 * x / 3.0)
        return u * special.k1(u) / (special.k0(u) / 3.0)

    return np.vectorize(_position_tail_third)(x) / position_density(x, restitution)


def _position_tail_third(x):
    # int_x^inf P(x') dx' at r = 1/3, under the F integral of eq. (P(x)2):
    # int_x^inf e^{-F x'} dx' = e^{-F x} / F, in ln F as in _position_density_third
    def integrand(log_f):
        f = np.exp(log_f)
        z = 1.0 / (12.0 * f)
        return special.kve(1.0 / 6.0, z) * np.exp(-2.0 * z - f * x) / f

    # at x = 0 the integrand decays only as F^(-5/6) in ln F
    upper = np.log(60.0 / x) if x > 0.0 else np.log(1.0e16)
    value, _ = integrate.quad(integrand, -8.0, max(upper, 8.0), limit=400, epsabs=0.0, epsrel=1e-11)
    return value / (4.0 * np.pi)


def distribution_table(positions, speeds, restitution):
    """P(x, v) for every x in ``positions`` and v in ``speeds`` (long format: x, v, pxv), and
    the largest relative error quad estimates for it."""
    x, v = np.meshgrid(np.asarray(positions, dtype=float), speeds, indexing="ij")
    pxv, error = distribution_with_error(x, v, restitution)
    finite = np.isfinite(pxv) & (pxv > 0.0)
    worst = float(np.max(error[finite] / pxv[finite])) if finite.any() else 0.0
    return pd.DataFrame({"x": x.ravel(), "v": v.ravel(), "pxv": pxv.ravel()}), worst
