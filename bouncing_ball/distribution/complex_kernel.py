"""The kernel of eq. (kernel3) continued to complex v: the terms of the Nystrom sum of P(0, v).

P(0, v) is analytic for abs(arg v) < pi/3 (the kernel of eq. (kernel3) is), and at complex v it
is the Nystrom formula of the solver, P(0, v) = r^-2 int du u G_g(v/r, u) P(0, u), with G_g
continued to complex v (``_complex_kernel_sums``, compiled).  Each term's tau integral (the
stable form of the y integral of ``kernel.py``) is taken by the Gauss-Legendre rule of
TAU_RULE_NODES with the fewest nodes that is accurate enough, or, where its Gaussian falls fast,
by Gauss-Hermite to infinity along arg tau = -arg(z0) / 2 (TAU_HERMITE_NODES).
"""

import cmath
import math

import numpy as np

from ..jit import njit
from ..kernel import TAIL as KERNEL_TAIL
from ..kernel import TAU_NODES

__all__ = []


SKIP_EFOLDS = 46.0  # a term of the Nystrom sum below e^-46 of the largest is skipped


#: The tau integral of a term of the complex Nystrom sum (``_complex_kernel_sums``) by
#: Gauss-Legendre with the fewest of TAU_RULE_NODES nodes that is accurate enough: the integrand
#: is a function of (tau / upper)^2 with the parameter eps = max(|z0 upper^2|, |upper^2|) (its
#: Taylor coefficients fall like eps^k).  The rule with TAU_RULE_NODES[k] nodes is used where
#: eps < TAU_RULE_LIMITS[tier][k], the kernel's TAU_NODES above the last limit.  Tier 0, for the
#: terms within e^-TAU_LOOSE_GAP of the sum's largest, holds each term to ~1e-15 of itself
#: (against 40 nodes); tier 1, for the smaller terms, to ~1e-6 of itself, i.e. below 1e-19 of
#: the largest (tests/unit/test_distribution.py compares the sums with 64 nodes throughout).
TAU_RULE_NODES = (4, 6, 8, 10, 14, TAU_NODES)


TAU_RULE_LIMITS = ((0.0, 0.01, 0.1, 0.3, 3.0), (0.1, 3.0, 10.0, 20.0, 50.0))


TAU_LOOSE_GAP = 30.0


def _tau_rules():
    """The Gauss-Legendre rules of TAU_RULE_NODES on [0, 1], one row each (zero-padded)."""
    size = max(TAU_RULE_NODES)
    x, w = np.zeros((len(TAU_RULE_NODES), size)), np.zeros((len(TAU_RULE_NODES), size))
    for k, count in enumerate(TAU_RULE_NODES):
        nodes, weights = np.polynomial.legendre.leggauss(count)
        x[k, :count], w[k, :count] = 0.5 * (nodes + 1.0), 0.5 * weights
    return x, w


_TAU_X, _TAU_W = _tau_rules()


_TAU_COUNTS = np.array(TAU_RULE_NODES, dtype=np.int64)


_TAU_LIMITS = np.array(TAU_RULE_LIMITS)


#: A term whose Gaussian e^(-z0 tau^2) falls by more than TAIL^2 e-folds before tau1 (where the
#: rules above cut the tau integral) is integrated instead to infinity along arg tau =
#: -arg(z0) / 2: the integrand is analytic and decays in the sector between that ray and
#: tau1's, which holds neither of its singularities (tau^2 = -1, -2), and the part beyond tau1
#: is below e^-TAIL^2.  With tau = x / z0^(1/2) the integral is z0^(-1/2) int_0^inf e^(-x^2)
#: g(x^2 / z0) dx, g smooth with its poles at |x| ~ |z0|^(1/2): Gauss-Hermite (the positive
#: nodes of the 2n-node rule) with the fewest n of TAU_HERMITE_NODES whose limit |z0| reaches,
#: TAU_HERMITE_LIMITS[tier][k] (|arg z0| <= pi/2): ~1e-15 of the integral in tier 0, ~1e-8 in
#: tier 1; below the last limit, the rules above.
TAU_HERMITE_NODES = (4, 5, 6, 7, 8, 10, 12)


TAU_HERMITE_LIMITS = (
    (np.inf, 100.0, 60.0, 40.0, 30.0, 20.0, 16.0),
    (20.0, 16.0, 12.0, 12.0, 8.0, 8.0, 8.0),
)


def _tau_hermite_rules():
    """x^2 and weights of the positive nodes of the Gauss-Hermite rules of TAU_HERMITE_NODES
    (int_0^inf e^(-x^2) f(x^2) dx), one row each (zero-padded)."""
    size = max(TAU_HERMITE_NODES)
    x2, w = np.zeros((len(TAU_HERMITE_NODES), size)), np.zeros((len(TAU_HERMITE_NODES), size))
    for k, count in enumerate(TAU_HERMITE_NODES):
        nodes, weights = np.polynomial.hermite.hermgauss(2 * count)
        x2[k, :count], w[k, :count] = nodes[count:] ** 2, weights[count:]
    return x2, w


_HERMITE_X2, _HERMITE_W = _tau_hermite_rules()


_HERMITE_COUNTS = np.array(TAU_HERMITE_NODES, dtype=np.int64)


_HERMITE_LIMITS = np.array(TAU_HERMITE_LIMITS)


@njit(cache=True)
def _principal_sqrt(z):
    """The principal square root of a finite complex z (cmath.sqrt's value, without its
    handling of infinities and NaN, which the inner loops of the Nystrom sums feel)."""
    a, b = z.real, z.imag
    size = math.hypot(a, b)
    if a >= 0.0:
        root = math.sqrt(0.5 * (size + a))
        return complex(root, 0.5 * b / root) if root > 0.0 else complex(0.0, b)
    root = math.sqrt(0.5 * (size - a))
    return complex(0.5 * abs(b) / root, math.copysign(root, b))


@njit(cache=True)
def _complex_kernel_sums(
    v,
    r,
    q,
    u,
    log_weights,
    tau_x,
    tau_w,
    tau_counts,
    tau_limits,
    hermite_x2,
    hermite_w,
    hermite_counts,
    hermite_limits,
    slack,
    out,
    magnitude,
):
    """out_i = e^(q v_i) r^-2 sum_j exp(log_weights_j) G_g(v_i / r, u_j) for complex v_i: the
    stable form of eq. (kernel3) in kernel.py, continued to complex v (the tau integral runs
    along the straight segment from 0 to tau1, by the rule of ``_tau_rules`` that eps selects,
    TAU_RULE_LIMITS, or to infinity by the rule of ``_tau_hermite_rules`` where the Gaussian
    has fallen by TAIL^2 e-folds before tau1, TAU_HERMITE_LIMITS).  Terms below e^-SKIP_EFOLDS of the largest are skipped (at large |v| the
    kernel confines u to a window of width ~ |v|^(1/2)).  A sum whose result is needed only to
    e^slack_i times the accuracy of the others skips below e^-(SKIP_EFOLDS - slack_i) and
    takes tau rule tier 1 below e^-(TAU_LOOSE_GAP - slack_i)."""
    root3_pi = math.sqrt(3.0) / math.pi
    # per u: z0, the exponent and its real part with the u^(1/2) bound (first pass, reused)
    z0s = np.empty(u.size, dtype=np.complex128)
    exponents = np.empty(u.size, dtype=np.complex128)
    levels = np.empty(u.size)
    half_log_u = 0.5 * np.log(u)
    for i in range(v.size):
        big_v = v[i] / r
        size_v = abs(big_v)
        half_log_size_v = 0.5 * math.log(size_v)
        best = -1e300
        last = u.size
        for j in range(u.size):
            d = big_v - u[j]
            z0 = _principal_sqrt(d * d + big_v * u[j])
            exponent = -0.75 * d * d / (0.5 * (big_v + u[j]) + z0) + log_weights[j]
            z0s[j] = z0
            exponents[j] = exponent
            # G ~ u^(1/2) for u << |v|
            levels[j] = exponent.real + min(half_log_u[j] - half_log_size_v, 0.0)
            if levels[j] > best:
                best = levels[j]
            # beyond u = 2 |V| + 10 the terms only fall (like e^(-(1/2 + q) u)): stop once they
            # are 10 e-folds below the skipped ones
            if u[j] > 2.0 * size_v + 10.0 and levels[j] < best - SKIP_EFOLDS - 10.0:
                last = j
                break
        # kernel.kernel_small_u_limit (relative error O(u / |v|)) without its u^(1/2) e^(...)
        small_u = 1.5 / math.pi * big_v**-2.5 * (1.0 + big_v) * cmath.exp(-0.5 * big_v + q * v[i])
        total = 0.0 + 0.0j
        size = 0.0
        for j in range(last):
            if levels[j] < best - (SKIP_EFOLDS - slack[i]):
                continue
            if u[j] < 1e-13 * size_v:
                term = small_u * math.sqrt(u[j]) * math.exp(log_weights[j])
                total += term
                size += abs(term)
                continue
            z0 = z0s[j]
            tau1 = _principal_sqrt(3.0 * big_v * u[j] / ((big_v + u[j] + z0) * z0))
            decay = (z0 * tau1 * tau1).real
            tier = 0 if levels[j] > best - (TAU_LOOSE_GAP - slack[i]) else 1
            upper = tau1
            hermite = -1
            if decay > 0.0 and KERNEL_TAIL / math.sqrt(decay) < 1.0:
                upper = tau1 * (KERNEL_TAIL / math.sqrt(decay))
                size_z0 = abs(z0)
                for k in range(hermite_limits.shape[1]):
                    if size_z0 >= hermite_limits[tier, k]:
                        hermite = k
                        break
            if hermite >= 0:
                acc = 0.0 + 0.0j
                inverse_z0 = 1.0 / z0
                for k in range(hermite_counts[hermite]):
                    t2 = hermite_x2[hermite, k] * inverse_z0
                    one_t2 = 1.0 + t2
                    acc += hermite_w[hermite, k] * (
                        (1.0 + z0 + hermite_x2[hermite, k])
                        / (one_t2 * one_t2 * _principal_sqrt(2.0 + t2))
                    )
                integral = acc / _principal_sqrt(z0)
            else:
                upper2 = upper * upper
                eps = max(abs(z0 * upper2), abs(upper2))
                rule = 0
                while rule < tau_limits.shape[1] and eps >= tau_limits[tier, rule]:
                    rule += 1
                acc = 0.0 + 0.0j
                for k in range(tau_counts[rule]):
                    tau = upper * tau_x[rule, k]
                    t2 = tau * tau
                    one_t2 = 1.0 + t2
                    acc += tau_w[rule, k] * (
                        cmath.exp(-z0 * t2)
                        * (1.0 + z0 * one_t2)
                        / (one_t2 * one_t2 * _principal_sqrt(2.0 + t2))
                    )
                integral = upper * acc
            term = cmath.exp(exponents[j] + q * v[i]) * root3_pi * integral / (z0 * z0)
            total += term
            size += abs(term)
        out[i] = total / (r * r)
        magnitude[i] = size / (r * r)
