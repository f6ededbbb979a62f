"""The paper's exact solutions at r = 1/2 and r = 1/3.

eq. (P(0,v)) with the constants of eq. (constants), and P(x) of eq. (P(x)2).
The time averages <x>, Delta x and the collision rate I of eq. (xandDeltax)
are computed here from these distributions (not copied from the paper), so
that a test can compare them with the paper's closed forms.

Every function takes r as a float or an exact fraction string ("1/2", "1/3") and refuses any
other r with a ``ValueError``.
"""

import functools
import math
import warnings
from fractions import Fraction

import numpy as np
import pandas as pd
from scipy import integrate, special

from .airy import check_force_integral_point, oscillating_airy_ai, scaled_airy_ai
from .near_wall import distribution_near_wall, near_wall_points
from .restitution import EXACT_RESTITUTIONS, parse_restitution

__all__ = [
    "normalization_constant",
    "outgoing_speed_density",
    "outgoing_speed_bin_average",
    "position_density",
    "position_bin_average",
    "speed_squared_given_position_bin_average",
    "position_moments",
    "weight_function",
    "distribution_by_force_integral",
    "distribution_on_ray",
    "distribution_with_error",
    "distribution",
    "mean_speed_squared_given_position",
    "distribution_table",
]


@functools.lru_cache(maxsize=64)  # called per point by the scalar integrands below
def _which(restitution) -> Fraction:
    """r (a float, or a fraction string such as "1/3") as 1/2 or 1/3; ValueError otherwise."""
    given = parse_restitution(restitution, "restitution")
    value = given.limit_denominator(1000)
    if value not in EXACT_RESTITUTIONS or abs(float(value) - float(given)) > 1e-12:
        raise ValueError(f"exact solutions exist only for r = 1/2 and 1/3, not r = {restitution}")
    return value


# QUADPACK's 21-point Gauss-Kronrod rule (dqk21) on [-1, 1]: the Kronrod nodes x >= 0 (the
# 10-point Gauss rule's at odd index), their Kronrod weights, and the Gauss weights
_HALF_KRONROD_NODES = (
    0.995657163025808080735527280689003,
    0.973906528517171720077964012084452,
    0.930157491355708226001207180059508,
    0.865063366688984510732096688423493,
    0.780817726586416897063717578345042,
    0.679409568299024406234327365114874,
    0.562757134668604683339000099272694,
    0.433395394129247190799265943165784,
    0.294392862701460198131126603103866,
    0.148874338981631210884826001129720,
    0.0,
)
_HALF_KRONROD_WEIGHTS = (
    0.011694638867371874278064396062192,
    0.032558162307964727478818972459390,
    0.054755896574351996031381300244580,
    0.075039674810919952767043140916190,
    0.093125454583697605535065465083366,
    0.109387158802297641899210590325805,
    0.123491976262065851077208814748999,
    0.134709217311473325928054001771707,
    0.142775938577060080797094273138717,
    0.147739104901338491374841515972068,
    0.149445554002916905664936468389821,
)
_HALF_GAUSS_WEIGHTS = (
    0.066671344308688137593568809893332,
    0.149451349150580593145776339657697,
    0.219086362515982043995534934228163,
    0.269266719309996355091226921569469,
    0.295524224714752870173892994651338,
)
KRONROD_NODES = np.concatenate([np.negative(_HALF_KRONROD_NODES), _HALF_KRONROD_NODES[-2::-1]])
KRONROD_WEIGHTS = np.concatenate([_HALF_KRONROD_WEIGHTS, _HALF_KRONROD_WEIGHTS[-2::-1]])
#: the 10-point Gauss rule's weights on KRONROD_NODES (0 at the Kronrod-only nodes)
GAUSS_WEIGHTS = np.zeros(21)
GAUSS_WEIGHTS[1:10:2] = _HALF_GAUSS_WEIGHTS
GAUSS_WEIGHTS[11:21:2] = _HALF_GAUSS_WEIGHTS[::-1]

#: subintervals one integral may be cut into (``_adaptive_gauss_kronrod``)
MOST_SUBINTERVALS = 10000


def _gauss_kronrod(integrand, lower, upper, owner):
    """The 21-point Gauss-Kronrod rule on every interval [lower, upper] at once: the integrals,
    their error estimates and the rounding floor of those estimates, as QUADPACK's dqk21 makes
    them; ``integrand(nodes, owner)`` takes the nodes (intervals x 21) of the integrals
    ``owner`` (one per interval)."""
    centre, half = 0.5 * (lower + upper), 0.5 * (upper - lower)
    f = integrand(centre[:, None] + half[:, None] * KRONROD_NODES, owner)
    kronrod = f @ KRONROD_WEIGHTS
    absolute = (np.abs(f) @ KRONROD_WEIGHTS) * half
    spread = (np.abs(f - 0.5 * kronrod[:, None]) @ KRONROD_WEIGHTS) * half
    difference = np.abs(kronrod - f @ GAUSS_WEIGHTS) * half
    both = (spread > 0.0) & (difference > 0.0)
    ratio = 200.0 * difference / np.where(both, spread, 1.0)
    error = np.where(both, spread * np.minimum(1.0, ratio**1.5), difference)
    rounding = 50.0 * np.finfo(float).eps * absolute
    return kronrod * half, np.maximum(error, rounding), rounding


def _adaptive_gauss_kronrod(integrand, lower, upper, relative_tolerance):
    """Integrals over [lower_i, upper_i] by 21-point Gauss-Kronrod, each bisected adaptively on
    its own until its error estimate is below ``relative_tolerance`` times its value.

    Every round evaluates all the intervals being refined, of every integral, in one call of
    ``integrand(nodes, owner)`` (``_gauss_kronrod``).  An integral is refined where an interval's
    error exceeds its share of the tolerance (in proportion to its length), unless the error
    is QUADPACK's rounding floor (50 eps int |f|, which bisection does not lower), or the
    integral has MOST_SUBINTERVALS intervals.  Returns the integrals and their error estimates,
    the sums over each integral's intervals.
    """
    count = len(lower)
    owner = np.arange(count)
    lo, hi = np.array(lower, dtype=float), np.array(upper, dtype=float)
    length = hi - lo
    value, error, rounding = _gauss_kronrod(integrand, lo, hi, owner)
    while True:
        total = np.bincount(owner, value, count)
        total_error = np.bincount(owner, error, count)
        refine = (total_error > relative_tolerance * np.abs(total)) & (
            np.bincount(owner, minlength=count) < MOST_SUBINTERVALS
        )
        share = relative_tolerance * np.abs(total[owner]) * (hi - lo) / length[owner]
        split = refine[owner] & (error > share) & (error > rounding)
        if not split.any():
            if np.any(np.bincount(owner, minlength=count) >= MOST_SUBINTERVALS):
                warnings.warn(
                    f"an integral needs more than {MOST_SUBINTERVALS} subintervals",
                    integrate.IntegrationWarning,
                    stacklevel=3,
                )
            return total, total_error
        middle = 0.5 * (lo[split] + hi[split])
        halves = (
            np.concatenate([lo[split], middle]),
            np.concatenate([middle, hi[split]]),
            np.tile(owner[split], 2),
        )
        new = _gauss_kronrod(integrand, *halves)
        keep = ~split
        lo, hi, owner = (
            np.concatenate([old[keep], fresh]) for old, fresh in zip((lo, hi, owner), halves)
        )
        value, error, rounding = (
            np.concatenate([old[keep], fresh]) for old, fresh in zip((value, error, rounding), new)
        )


def normalization_constant(restitution) -> float:
    """The normalization constant A of P(0, v), eq. (constants).

    Parameters
    ----------
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    float
        A_{1/2} = 1/3 and A_{1/3} = (27 / (32 pi))^(1/2).

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import normalization_constant
    >>> print(round(normalization_constant("1/2"), 12), round(normalization_constant(1 / 3), 12))
    0.333333333333 0.518241224207
    """
    if _which(restitution) == Fraction(1, 2):
        return 1.0 / 3.0
    return np.sqrt(27.0 / (32.0 * np.pi))


def outgoing_speed_density(v, restitution):
    """P(0, v) for v > 0 (outgoing side), eq. (P(0,v)); the incoming side is eq. (bc).

    Parameters
    ----------
    v : array_like
        Outgoing speeds, v >= 0 (P(0, 0) is infinite).
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        P(0, v) = A e^(-v) / v at r = 1/2, A v^(-3/2) e^(-3 v / 2) at r = 1/3, with A of
        eq. (constants); the shape of ``v``.

    Raises
    ------
    ValueError
        If a v is negative or NaN (the incoming side is r^2 P(0, -r v), eq. (bc)), or r is not
        1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import outgoing_speed_density
    >>> print(outgoing_speed_density([0.5, 1.0, 2.0], "1/2").round(8))
    [0.40435377 0.12262648 0.02255588]
    """
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
    """int_lo^hi v P(0,v) dv / int_lo^hi v dv, the quantity a simulation bin measures.

    P(0, v) of eq. (P(0,v)), averaged over a bin with the weight v of the flux through the
    floor (the tally counts collisions).

    Parameters
    ----------
    lo, hi : array_like
        The bins' lower and upper edges, 0 <= lo < hi; they broadcast.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        The average of P(0, v) over each bin, weighted by v.

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import outgoing_speed_bin_average
    >>> print(round(float(outgoing_speed_bin_average(1.0, 2.0, "1/2")), 10))
    0.0516764795
    """
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
    """P(x), the density of the height x, eq. (P(x)2).

    Parameters
    ----------
    x : array_like
        Heights, x >= 0 (P(0) is infinite).
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        P(x) = K_0((2 x / 3)^(1/2)) / 3 at r = 1/2; at r = 1/3 the integral over F of
        eq. (P(x)2), by quadrature.  The shape of ``x``.

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import position_density
    >>> print(position_density([1.5, 6.0], "1/2").round(8))
    [0.14034148 0.03796462]
    """
    x = np.asarray(x, dtype=float)
    if _which(restitution) == Fraction(1, 2):
        return special.k0(np.sqrt(2.0 * x / 3.0)) / 3.0
    return _position_density_third(x)


def _force_integrals_third(lo, power, width=None, scaled=False):
    """The integrals over F of eq. (P(x)2) at r = 1/3, all at once (``_adaptive_gauss_kronrod``):

        (1/4 pi) int dF F^-1 K_{1/6}(z) e^{-z} e^{-F lo_i} F^-power (1 - e^{-F width_i}),

    z = 1/(12 F), in ln F, the last factor 1 without ``width``.  P(x) is power 0 at lo = x;
    int_x^inf P(x') dx' power 1; int over a bin [lo, lo + width) of P power 1 and of the tail
    power 2.  e^{-2z} cuts off small F, e^{-F lo} large F; at lo = 0 the integrand decays only
    as F^(1/6 - power) in ln F, so it runs to F = 1e16 / width.  With ``scaled``, the integrals
    times e^{2 (lo / 6)^(1/2)}, the saddle value of e^{-2z - F lo} (at F = (6 lo)^(-1/2)): finite
    where the integrals underflow (lo beyond ~1e5)."""
    lo = np.asarray(lo, dtype=float)
    scale = np.ones_like(lo) if width is None else np.asarray(width, dtype=float)
    shift = 2.0 * np.sqrt(lo / 6.0) if scaled else np.zeros_like(lo)

    def integrand(log_f, owner):
        f = np.exp(log_f)
        z = 1.0 / (12.0 * f)
        exponent = -2.0 * z - f * lo[owner, None] + shift[owner, None]
        value = special.kve(1.0 / 6.0, z) * np.exp(exponent) * f**-power
        return value if width is None else value * -np.expm1(-f * scale[owner, None])

    with np.errstate(divide="ignore"):
        # at lo > 0, where e^{-2z - F lo} has fallen by e^-60 from its saddle value at
        # F = (6 lo)^(-1/2) (to F = 60 / lo at small lo), widened by e either side
        root = np.sqrt(lo / 6.0)
        saddle = -0.5 * np.log(6.0 * np.where(lo > 0.0, lo, 1.0))
        reach = np.arccosh(1.0 + 30.0 / np.where(lo > 0.0, root, 1.0)) + 1.0
        lower = np.where(lo > 0.0, saddle - reach, -8.0)
        upper = np.where(lo > 0.0, saddle + reach, np.maximum(np.log(1.0e16 / scale), 8.0))
    values, _ = _adaptive_gauss_kronrod(integrand, lower, upper, 1e-11)
    return values / (4.0 * np.pi)


def _position_density_third(x):
    """P(x) at r = 1/3 for an array x, eq. (P(x)2) (``_force_integrals_third``); infinite at
    x = 0, where the integrand grows as F^(1/6)."""
    x = np.asarray(x, dtype=float)
    out = np.full(x.shape, np.inf)
    inside = x > 0.0
    out[inside] = _force_integrals_third(x[inside], 0)
    return out


def position_bin_average(lo, hi, restitution):
    """int_lo^hi P(x) dx / (hi - lo): P(x) of eq. (P(x)2) averaged over a bin.

    Parameters
    ----------
    lo, hi : array_like
        The bins' lower and upper edges, 0 <= lo < hi, of the same shape.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        The mean of P(x) over each bin (in closed form at r = 1/2, by quadrature at r = 1/3).

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import position_bin_average
    >>> print(round(float(position_bin_average(0.0, 1.5, "1/2")), 10))
    0.2653951799
    """
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    if _which(restitution) == Fraction(1, 2):
        # int (1/3) K0(sqrt(2x/3)) dx = -u K1(u), u = sqrt(2x/3)
        def primitive(x):
            u = np.sqrt(2.0 * x / 3.0)
            return np.where(u > 0, -u * special.k1(np.where(u > 0, u, 1.0)), -1.0)

        return (primitive(hi) - primitive(lo)) / (hi - lo)
    return _bin_integrals_third(lo, hi, 1) / (hi - lo)


def speed_squared_given_position_bin_average(lo, hi, restitution):
    """<v^2>_x of eq. (moment2) averaged over [lo, hi) with weight P(x).

    That is int_bin dx int_x^inf P(x') dx' / int_bin P(x) dx, the quantity a
    simulation bin measures.  For r = 1/2, int_x^inf P = u K1(u) with
    u = sqrt(2x/3), and int u K1(u) dx = -3 u^2 K2(u).  For r = 1/3 both
    integrals over x are done under the integral over F of eq. (P(x)2):
    int_lo^hi dx int_x^inf e^{-F x'} dx' = (e^{-F lo} - e^{-F hi}) / F^2.

    Parameters
    ----------
    lo, hi : array_like
        The bins' lower and upper edges, 0 <= lo < hi, of the same shape.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        The P(x)-weighted mean of <v^2>_x over each bin.

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import speed_squared_given_position_bin_average
    >>> print(round(float(speed_squared_given_position_bin_average(0.0, 1.5, "1/2")), 10))
    2.8271885085
    """
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    if _which(restitution) == Fraction(1, 2):
        # int_x^inf P = u K1(u), int u K1(u) dx = -3 u^2 K2(u), u = sqrt(2x/3); both bin
        # integrals times e^(u_lo) (the scaled Bessel functions): finite where they underflow
        u_lo, u_hi = np.sqrt(2.0 * lo / 3.0), np.sqrt(2.0 * hi / 3.0)
        safe = np.where(u_lo > 0.0, u_lo, 1.0)
        decay = np.exp(u_lo - u_hi)
        tail_lo = np.where(u_lo > 0.0, 3.0 * safe**2 * special.kve(2, safe), 6.0)
        mass_lo = np.where(u_lo > 0.0, safe * special.k1e(safe), 1.0)
        numerator = tail_lo - 3.0 * u_hi**2 * special.kve(2, u_hi) * decay
        denominator = mass_lo - u_hi * special.k1e(u_hi) * decay
        return numerator / denominator
    width = (hi - lo).ravel()
    numerator = _force_integrals_third(lo.ravel(), 2, width, scaled=True)
    denominator = _force_integrals_third(lo.ravel(), 1, width, scaled=True)
    return (numerator / denominator).reshape(lo.shape)


def _bin_integrals_third(lo, hi, power):
    """At r = 1/3, for every bin [lo, hi): with power 1, int_lo^hi P(x) dx; with power 2,
    int_lo^hi dx int_x^inf P(x') dx' (``_force_integrals_third``)."""
    lo, hi = np.broadcast_arrays(np.asarray(lo, dtype=float), np.asarray(hi, dtype=float))
    return _force_integrals_third(lo.ravel(), power, (hi - lo).ravel()).reshape(lo.shape)


def position_moments(restitution) -> dict:
    """<x>, Delta x (eq. (xandDeltax)) from P(x), and I from eq. (collrate).

    The moments of P(x) of eq. (P(x)2) by quadrature, and I = int_0^inf v P(0, v) dv with
    P(0, v) of eq. (P(0,v)), so that they can be checked against the paper's closed forms.

    Parameters
    ----------
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    dict
        ``normalization`` (int P(x) dx, 1 up to quadrature error), ``mean_x`` (<x>),
        ``delta_x`` (Delta x) and ``collision_rate`` (I).

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    At r = 1/2, <x> = 6, Delta x = 6 3^(1/2) and I = 1/3:

    >>> from bouncing_ball.exact import position_moments
    >>> moments = position_moments("1/2")
    >>> print({name: round(float(value), 8) for name, value in moments.items()})
    {'normalization': 1.0, 'mean_x': 6.0, 'delta_x': 10.39230485, 'collision_rate': 0.33333333}
    """

    # int x^k P(x) dx for k = 0, 1, 2 (the integrals' ``owner``), in x = 3 u^2 / 2, which makes
    # the decay exp(-u) for both r: beyond u = 80, x^2 P(x) 3u < 1e-25
    def integrand(u, k):
        x = 1.5 * u * u
        return x ** k[:, None] * position_density(x, restitution) * 3.0 * u

    moments, _ = _adaptive_gauss_kronrod(integrand, np.zeros(3), np.full(3, 80.0), 1e-12)
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
    """The weight function w(F) of eq. (weightfunc2) with the constants of eq. (constants).

    Parameters
    ----------
    force : array_like
        Values of F > 0.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        w(F), the shape of ``force``.

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import weight_function
    >>> print(weight_function([0.1, 1.0], "1/2").round(8))
    [0.22905337 0.15334074]
    """
    force = np.asarray(force, dtype=float)
    a = normalization_constant(restitution)
    with np.errstate(over="ignore"):  # z = inf at subnormal F, where w underflows to 0
        z = (1.0 / 12.0) / force
    if _which(restitution) == Fraction(1, 2):
        return 0.5 * a * force**-0.5 * np.exp(-z)
    # in logs: F^-1/2 overflows where K e^-z underflows (F below ~1e-300); beyond z = 1e8 (where
    # scipy's kve stops) w < e^-z underflows to 0 whatever K_nu(z) e^z (~ (pi / 2z)^(1/2));
    # below z = 1e-100 (where kve overflows at subnormal z) K_nu(z) = Gamma(nu)/2
    # (2/z)^nu (1 + O(z^(2 nu))), relative 1e-33 there
    small = z < 1e-100
    log_bessel = np.where(
        small,
        np.log(0.5 * special.gamma(1.0 / 6.0))
        + (np.log(2.0) - np.log(np.where(small, z, 1.0))) / 6.0,
        np.log(special.kve(1.0 / 6.0, np.clip(z, 1e-100, 1e8))),
    )
    log_c = np.log(np.sqrt(2.0 / (27.0 * np.pi)) * a)
    return np.exp(log_c - 0.5 * np.log(force) + log_bessel - z)


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
    """P(x, v) of eqs. (fpsol), (psi), (weightfunc2) by integration over F, and its error.

    One point by scipy's ``quad`` (relative tolerance 1e-10): the cross-check of the arrays
    ``distribution_with_error`` integrates all at once, over the same range of ln F.
    Converges absolutely for x > 0, and for x = 0 on the incoming side v < 0
    (there the Airy function decays); at x = 0, v > 0 only conditionally.

    Parameters
    ----------
    x : float
        The height, x >= 0.
    v : float
        The velocity; v < 0 if x = 0.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    value : float
        P(x, v).
    error : float
        quad's estimate of the absolute error of ``value``.

    Raises
    ------
    ValueError
        If x < 0, or x = 0 with v >= 0 (``airy.check_force_integral_point``), or r is
        not 1/2 or 1/3.

    Examples
    --------
    At x = 0 on the incoming side the integral gives eq. (bc), r^2 P(0, -r v) = e^(-1/2) / 6
    at r = 1/2, v = -1:

    >>> import math
    >>> from bouncing_ball.exact import distribution_by_force_integral
    >>> value, error = distribution_by_force_integral(0.0, -1.0, "1/2")
    >>> print(round(value, 8), round(math.exp(-0.5) / 6.0, 8), error < 1e-9)
    0.10108844 0.10108844 True
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


#: The angle of the ray of F of ``distribution_on_ray``, its step in ln |F| and its lower end.
RAY_FORCE_ANGLE = 1.3


RAY_FORCE_STEP = 0.05


RAY_FORCE_LOWEST = -80.0


def _log_weight_rest(force, restitution):
    """ln w(F) + 1/(12 F) of eq. (weightfunc2) at complex F, Re F > 0."""
    a = normalization_constant(restitution)
    if _which(restitution) == Fraction(1, 2):
        return np.log(0.5 * a) - 0.5 * np.log(force)
    z = (1.0 / 12.0) / force
    far = np.abs(z) > 1e4  # scipy's kve fails far out; its asymptotic series (DLMF 10.40.2)
    near = np.where(far, 1.0, z)
    mu, y = 4.0 / 36.0, 1.0 / (8.0 * np.where(far, z, 1.0))
    series = 1.0 + (mu - 1.0) * y * (1.0 + (mu - 9.0) * y / 2.0 * (1.0 + (mu - 25.0) * y / 3.0))
    bessel = np.where(
        far,
        0.5 * np.log(np.pi / (2.0 * np.where(far, z, 1.0))) + np.log(series),
        np.log(special.kve(1.0 / 6.0, near)),
    )
    return np.log(np.sqrt(2.0 / (27.0 * np.pi)) * a) - 0.5 * np.log(force) + bessel


def distribution_on_ray(x, v, restitution):
    """P(x, v) of eqs. (fpsol), (psi), (weightfunc2), v > 0, by the F integral on a complex ray.

    Any x >= 0, however fast the Airy factor oscillates on the real axis.
    On the real axis Ai(z) = 2 Re[-omega Ai(omega z)], omega = e^(2 pi i / 3); for
    z = -F^(1/3) v + F^(-2/3) / 4 the half -omega Ai(omega z) ~ e^(i (2/3) F^(1/2) v^(3/2)) decays
    in the upper half F plane, and w(F) of eq. (weightfunc2) is analytic for Re F > 0, so its
    integral is taken along F = t e^(i RAY_FORCE_ANGLE), t > 0 (with e^(-F x) the arc at
    infinity vanishes for the angle below pi / 2; at F -> 0 the half grows like e^(1/(12 F)),
    w falls like e^(-1/(12 F)), and their product, summed in one exponent, is bounded).  On
    the ray the integrand does not oscillate and is no larger than the result, so nothing
    cancels: the trapezoidal rule in ln t, step RAY_FORCE_STEP from ln t = RAY_FORCE_LOWEST to
    where e^(-F x) or the half's decay reaches e^-80, is exact to the rounding of its terms: ~3e-13 relative at r = 1/2, and at r = 1/3 up to
    4e-12 at v = 20 (against P(0, v) of eq. (P(0,v)) at x = 0, v = 1e-3 to 300 and 20, and
    the real-axis integral where that works).

    Parameters
    ----------
    x : array_like
        Heights, x >= 0.
    v : array_like
        Outgoing velocities, 1e-3 <= v <= 300 at r = 1/2, <= 20 at r = 1/3; they broadcast
        against ``x``.  (At r = 1/3 the ray's integrand near F = 0, ~e^(-v), cancels down to
        P ~ e^(-3 v / 2): the rounding grows like e^(v / 2), 4e-7 at v = 40.)
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        P(x, v), the broadcast shape; P(0, v) of eq. (P(0,v)) at x = 0.

    Raises
    ------
    ValueError
        If an x is negative or not finite, a v outside its range, or r not 1/2 or 1/3.

    Examples
    --------
    At x = 0 it is eq. (P(0,v)), e^(-v) / (3 v) at r = 1/2; at x = 1e-5, v = 20 the real-axis
    integral (``distribution_by_force_integral``) is out of reach:

    >>> from bouncing_ball.exact import distribution_on_ray, outgoing_speed_density
    >>> values = distribution_on_ray([0.0, 1e-5], 20.0, "1/2")
    >>> print(values, outgoing_speed_density(20.0, "1/2"))
    [3.43525604e-11 3.43525613e-11] 3.435256037397596e-11
    """
    _which(restitution)
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v, dtype=float))
    if np.any(~(x >= 0.0) | ~np.isfinite(x)):
        raise ValueError("x: P(x, v) on the F ray needs finite heights x >= 0")
    top_speed = 300.0 if _which(restitution) == Fraction(1, 2) else 20.0
    if np.any(~(v >= 1e-3) | ~(v <= top_speed)):
        raise ValueError(
            f"v: P(x, v) on the F ray needs outgoing velocities 1e-3 <= v <= {top_speed:g} "
            f"at r = {restitution}"
        )
    theta = RAY_FORCE_ANGLE
    turn = np.exp(1j * theta)
    omega = np.exp(2j * np.pi / 3.0)
    out = np.empty(x.shape)
    for index in np.ndindex(x.shape):
        xi, vi = float(x[index]), float(v[index])
        top = 2.0 * math.log(80.0 / ((2.0 / 3.0) * vi**1.5 * math.sin(0.5 * theta)))
        if xi > 0.0:
            top = min(top, math.log(80.0 / (xi * math.cos(theta))))
        t = np.arange(RAY_FORCE_LOWEST, max(top, 0.0) + RAY_FORCE_STEP, RAY_FORCE_STEP)
        force = np.exp(t) * turn
        u = 4.0 * force * vi
        power = (1.0 - u) * np.sqrt(1.0 - u)
        # -(2/3) (omega z)^(3/2) - 1/(12 F) = ((1 - u)^(3/2) - 1) / (12 F), without the
        # cancellation at small u (numpy's complex log1p loses it)
        small = np.abs(u) < 0.5
        exponent = np.where(small, (-3.0 * u + 3.0 * u * u - u**3) / (power + 1.0), power - 1.0)
        exponent = exponent / (12.0 * force)
        zeta = omega * 0.25 * force ** (-2.0 / 3.0) * (1.0 - u)
        log_rest = _log_weight_rest(force, restitution) + exponent - force * xi - 0.5 * vi
        terms = -omega * scaled_airy_ai(zeta) * np.exp(log_rest + (5.0 / 6.0) * np.log(force))
        out[index] = 2.0 * RAY_FORCE_STEP * float(np.sum(terms.real))
    return out


def _force_integrals(x, v, restitution):
    """P(x, v) at the points x > 0 (1-d arrays x, v), eqs. (fpsol), (psi), (weightfunc2): the
    integrand of ``distribution_by_force_integral`` on the same range of ln F, all points at
    once by ``_adaptive_gauss_kronrod`` (relative tolerance 1e-10).  Returns the values and
    their absolute error estimates."""

    def integrand(log_force, owner):
        # e^{-v/2} w(F) e^{-F x} psi_{1/4,F}(-v) F, eqs. (fpsol), (psi); dF = F d(ln F); the
        # decay of Ai (z > 0) joins e^{-v/2 - F x} in one exponential: finite at any v
        f = np.exp(log_force)
        xi, vi = x[owner, None], v[owner, None]
        argument = -np.cbrt(f) * vi + 0.25 * f ** (-2.0 / 3.0)
        # the points at one x bisect the same interval, so share its nodes: w(F) once per interval
        key = log_force[:, 0] + 1j * log_force[:, -1]
        _, first, shared = np.unique(key, return_index=True, return_inverse=True)
        weight = weight_function(f[first], restitution)[shared.ravel()]
        decaying = argument > 0.0
        airy = np.empty(argument.shape)
        airy[decaying] = scaled_airy_ai(argument[decaying])
        airy[~decaying] = oscillating_airy_ai(-argument[~decaying])
        decay = (2.0 / 3.0) * np.where(decaying, argument, 0.0) ** 1.5
        return np.exp(-0.5 * vi - f * xi - decay) * weight * f ** (5.0 / 6.0) * airy

    if x.size == 0:
        return np.empty(0), np.empty(0)
    # as distribution_by_force_integral: w(F) ~ e^{-1/(6F)} below e^-6, e^{-F x} < e^-60 above;
    # widened to where e^{-1/(6F) - F E} has fallen by e^-60 from its saddle value at
    # F = (6 E)^(-1/2), E = x + v^2/2 on the incoming side (v < 0: e^{-v/2} Ai = e^{-1/(12F) -
    # F v^2/2 ...}), where the saddle lies outside (x beyond ~1e3, or v below ~-30)
    energy = x + 0.5 * np.minimum(v, 0.0) ** 2
    root = np.sqrt(energy / 6.0)
    saddle = -0.5 * np.log(6.0 * energy)
    reach = np.arccosh(1.0 + 30.0 / root) + 1.0
    lower = np.minimum(-6.0, saddle - reach)
    upper = np.maximum(np.log(60.0 / x), saddle + reach)
    return _adaptive_gauss_kronrod(integrand, lower, upper, 1e-10)


def distribution_with_error(x, v, restitution):
    """P(x, v) and an estimate of its absolute error, for broadcast arrays x >= 0 and v.

    At x = 0 the outgoing side is eq. (P(0,v)) and the incoming side the
    boundary condition eq. (bc), P(0, -v) = r^2 P(0, r v) (the F integral
    converges only conditionally there); P(0, 0) diverges and is NaN.  Elsewhere P(x, v) is the
    F integral of eqs. (fpsol), (psi), (weightfunc2) over the same range of ln F as
    ``distribution_by_force_integral``, to 1e-10 relative, every point at once by an adaptive
    21-point Gauss-Kronrod rule, each point's intervals bisected on its own
    (``_force_integrals``); next to the floor at large v > 0, where that integral oscillates
    too fast (x < 1.7e-8 v^3, ``near_wall.near_wall_points``), the Taylor series in x of
    eq. (fp) from eq. (P(0,v)) (``near_wall.distribution_near_wall``, to ~1e-13 of
    ``distribution_on_ray``).

    Parameters
    ----------
    x : array_like
        Heights, x >= 0.
    v : array_like
        Velocities; broadcast against ``x``.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    values : numpy.ndarray
        P(x, v), the broadcast shape.
    errors : numpy.ndarray
        The adaptive Gauss-Kronrod estimate of the absolute error of each value
        (``_force_integrals``; 0 at x = 0, where the values are in closed form).

    Raises
    ------
    ValueError
        If an x is negative, or r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import distribution_with_error
    >>> values, errors = distribution_with_error([0.0, 0.0, 1.0], [1.0, -2.0, 0.5], "1/2")
    >>> print(values.round(8), bool(errors.max() < 1e-9))
    [0.12262648 0.03065662 0.0471541 ] True
    """
    x, v = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(v, dtype=float))
    near = near_wall_points(x, v)
    for index in np.ndindex(x.shape):
        if x[index] != 0.0 and not near[index]:
            check_force_integral_point(float(x[index]), float(v[index]))
    values, errors = np.empty(x.shape), np.zeros(x.shape)
    r = float(_which(restitution))
    if near.any():
        values[near], errors[near] = distribution_near_wall(
            x[near], v[near], lambda speeds: outgoing_speed_density(speeds, restitution), r
        )
    wall = x == 0.0
    outgoing, incoming = wall & (v > 0.0), wall & (v < 0.0)
    values[outgoing] = outgoing_speed_density(v[outgoing], restitution)
    values[incoming] = r * r * outgoing_speed_density(-r * v[incoming], restitution)
    values[wall & (v == 0.0)] = np.nan
    inside = ~wall & ~near
    values[inside], errors[inside] = _force_integrals(x[inside], v[inside], restitution)
    return values, errors


def distribution(x, v, restitution):
    """P(x, v), eqs. (fpsol), (psi), (weightfunc2); see ``distribution_with_error``.

    Parameters
    ----------
    x : array_like
        Heights, x >= 0.
    v : array_like
        Velocities; broadcast against ``x``.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        P(x, v), the broadcast shape (NaN at x = v = 0, where it diverges).

    Raises
    ------
    ValueError
        If an x is negative, or r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import distribution
    >>> print(distribution(1.0, [0.5, -0.5], "1/2").round(8))
    [0.0471541  0.03578642]
    """
    return distribution_with_error(x, v, restitution)[0]


def mean_speed_squared_given_position(x, restitution):
    """<v^2>_x = P(x)^-1 int_x^inf P(x') dx', eq. (moment2).

    Parameters
    ----------
    x : array_like
        Heights, x > 0.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    numpy.ndarray
        <v^2>_x with P(x) of eq. (P(x)2), the shape of ``x``: the ratio of the exponentially
        scaled integrals, so finite where P(x) underflows (x beyond ~1e5).

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import mean_speed_squared_given_position
    >>> print(mean_speed_squared_given_position([1.5, 6.0], "1/2").round(8))
    [4.28887619 7.36822158]
    """
    x = np.asarray(x, dtype=float)
    if _which(restitution) == Fraction(1, 2):
        u = np.sqrt(2.0 * x / 3.0)
        return 3.0 * u * special.k1e(u) / special.k0e(u)  # e^u K: finite where K underflows
    flat = x.ravel()
    tail = _force_integrals_third(flat, 1, scaled=True)
    return (tail / _force_integrals_third(flat, 0, scaled=True)).reshape(x.shape)


def distribution_table(positions, speeds, restitution):
    """P(x, v) on a grid, eqs. (fpsol), (psi), (weightfunc2), and its largest relative error.

    Parameters
    ----------
    positions : array_like
        The heights x >= 0.
    speeds : array_like
        The velocities v.
    restitution : float or str
        r = 1/2 or 1/3, a float or a fraction string ("1/2", "1/3").

    Returns
    -------
    table : pandas.DataFrame
        P(x, v) for every x in ``positions`` and v in ``speeds``, in long format: columns
        ``x``, ``v``, ``pxv``, x varying slowest.
    worst : float
        The largest estimated relative error of a positive finite P(x, v): a point's error
        estimate (``distribution_with_error``) over its value.

    Raises
    ------
    ValueError
        If r is not 1/2 or 1/3.

    Examples
    --------
    >>> from bouncing_ball.exact import distribution_table
    >>> table, worst = distribution_table([0.0, 1.0], [-1.0, 1.0], "1/2")
    >>> print(table.round(6).to_string(index=False), worst < 1e-9)
      x    v      pxv
    0.0 -1.0 0.101088
    0.0  1.0 0.122626
    1.0 -1.0 0.027950
    1.0  1.0 0.045491 True
    """
    x, v = np.meshgrid(np.asarray(positions, dtype=float), speeds, indexing="ij")
    pxv, error = distribution_with_error(x, v, restitution)
    finite = np.isfinite(pxv) & (pxv > 0.0)
    worst = float(np.max(error[finite] / pxv[finite])) if finite.any() else 0.0
    return pd.DataFrame({"x": x.ravel(), "v": v.ravel(), "pxv": pxv.ravel()}), worst
