"""The weight function w(F) of eq. (weightfunc), by contour integrals of the solver's P(0, v).

With phi of eq. (phi) at s = 1/4 (there (2/3) s^(3/2) = 1/12)::

    phi_F(-v) = psi_F(-v) - e^(-1/(12F)) int_0^inf dG/(2 pi) e^(-1/(12G)) psi_G(v) / (F + G),

psi_F(v) = F^(-1/6) Ai(F^(1/3) v + F^(-2/3)/4), eq. (psi).  The v and G
integrals are swapped in the second term, so::

    w(F) = A(F) - e^(-1/(12F)) B(F),
    A(F) = int_0^inf dv v h(v) psi_F(-v),
    B(F) = int_0^inf dG/(2 pi) e^(-1/(12G)) T(G) / (F + G),   T(G) = int_0^inf dv v h(v) psi_G(v).

T(G) converges absolutely (psi_G(v) decays like exp(-1/(12G) - v/2 - G v^2/2 ...)).
For G > 1e30 it is replaced by its v -> 0 form, h ~ C v^-beta:
T(G) = C G^((2 beta - 5)/6) M(2 - beta), M the Mellin transform of Ai.  Where
beta >= 2 (r <= r_c) int_0 v h(v) dv diverges; since phi_F(0) = 0 exactly (the
two terms of eq. (phi) cancel at v = 0), the same regularisation of
int_0^eps C v^(1-beta) dv (its analytic continuation in beta) in A and in every T
cancels, and the formulas hold unchanged.

A(F) is the hard part: beyond the turning point v = 1/(4F), psi_F(-v)
oscillates with amplitude ~ v^(-1/4) while h(v) ~ v^-m e^((1/2 - q) v), so the
real-axis integral diverges where q(r) < 1/2 (r > sqrt(3) - 1), and where it
converges it cancels exponentially at small F.  A(F) is therefore taken along
a contour: the real axis from 0 to a split point v1, then, writing
Ai(z) = 2 Re[-omega Ai(omega z)] (omega = e^(2 pi i / 3); -omega Ai(omega z) =
(Ai(z) - i Bi(z)) / 2 for real z), 2 Re of the integral of v h(v) (-omega)
F^(-1/6) Ai(omega zeta(v)) along a path into the upper half plane: first at
angle pi/3 (the steepest descent direction at the saddle) until arg v =
THETA_MAX, then radially.  Along that path the Airy factor decays like
exp(-c F^(1/2) abs(v)^(3/2)), faster than any exponential.  h at complex v is the
Nystrom formula of the solver (``outgoing_density``, ``complex_kernel``).  The split point
is v1 = 1/(4F) where q >= 1/2 and the saddle of the continued integrand,
v1 = q (1 - q) / F, where q < 1/2: there the real-axis part is exponentially
smaller than the result and nothing cancels.  At small F,
w(F) ~ exp(-S(q) / F) with S = (3p - p^3)/24, p = min(2q - 1, 1): for q < 1
(r > 1/2) the saddle dominates, for q >= 1 the end point v = 0 does (S = 1/12).
S < 0 for q < 1/2: w then grows without bound as F -> 0, which is why
``log_weight_function`` exists.  Near r = 1 (r > RAY_RESTITUTION) A(F) is taken along the ray
of ``ray_density`` instead.
"""

import numpy as np
from scipy import optimize, special

from ..airy import scaled_airy_ai
from ..asymptotics import large_speed_decay_rate, large_speed_exponent
from ..restitution import restitution_value as restitution_float
from ..solver import _jacobian, coordinate_of_speed, speed_of_coordinate
from .outgoing_density import _GL_W, _GL_X, SMALLEST_SPEED, THETA_MAX, _outgoing_density, _panels
from .ray_density import NEGLIGIBLE_EFOLDS, RAY_ANGLE

__all__ = [
    "small_force_decay",
    "small_force_power",
    "log_weight_function",
    "weight_function",
]


OMEGA = np.exp(2j * np.pi / 3.0)


LARGEST_KERNEL_FORCE = 1e30  # above, T(G) by its small-v form


def _log_psi(force, v):
    """ln psi_F(v) of eq. (psi) where its argument F^(1/3) v + F^(-2/3)/4 is >= 0 (psi > 0 there)."""
    argument = force ** (1.0 / 3.0) * v + 0.25 * force ** (-2.0 / 3.0)
    return (
        -np.log(force) / 6.0
        + np.log(scaled_airy_ai(argument))
        - (2.0 / 3.0) * np.maximum(argument, 0.0) ** 1.5
    )


def _psi(force, v):
    """psi_F(v), eq. (psi), for real v (any sign)."""
    v = np.asarray(v, dtype=float)
    argument = force ** (1.0 / 3.0) * v + 0.25 * force ** (-2.0 / 3.0)
    positive = argument > 0.0
    out = np.empty(np.broadcast(argument).shape)
    out[positive] = np.exp(_log_psi(force, np.broadcast_to(v, out.shape)[positive]))
    out[~positive] = force ** (-1.0 / 6.0) * special.airy(argument[~positive])[0]
    return out


def _log_psi_omega(force, v):
    """ln of (-omega) F^(-1/6) Ai(omega zeta), zeta = F^(-2/3)/4 - F^(1/3) v (complex v): the half
    of psi_F(-v) that decays in the upper half plane (2 Re of it is psi_F(-v) on the real axis)."""
    z = OMEGA * (0.25 * force ** (-2.0 / 3.0) - force ** (1.0 / 3.0) * v)
    return (
        np.log(-OMEGA)
        - np.log(force) / 6.0
        + np.log(scaled_airy_ai(z).astype(complex))
        - (2.0 / 3.0) * z**1.5
    )


def _airy_mellin(s):
    """int_0^inf t^(s-1) Ai(t) dt = 3^(-(s+2)/3) Gamma(s) / Gamma((s+2)/3), continued to -1 < s < 0."""
    return 3.0 ** (-(s + 2.0) / 3.0) * special.gamma(s) / special.gamma((s + 2.0) / 3.0)


def small_force_decay(restitution) -> float:
    """S(q) in w(F) ~ exp(-S / F) as F -> 0, the small-F decay of w of eq. (weightfunc).

    S = (3p - p^3) / 24 with p = min(2q - 1, 1), q = q(r) of eqs. (asym4), (asym6): for q < 1
    (r > 1/2) the saddle v = q (1 - q) / F of the v integral dominates, for q >= 1 the end point
    v = 0 does (S = 1/12, the e^(-1/(12F)) of eq. (weightfunc2)).  S < 0 where q < 1/2
    (r > 3^(1/2) - 1): w then grows without bound as F -> 0.

    Parameters
    ----------
    restitution : float or str
        r, 0 < r < 1, a float or a fraction string ("1/3").

    Returns
    -------
    float
        S.

    Examples
    --------
    >>> from bouncing_ball.distribution import small_force_decay
    >>> print(small_force_decay(0.25) == small_force_decay("1/2") == 1 / 12)
    True
    >>> print(round(small_force_decay(0.6), 10), round(small_force_decay(0.9), 10))
    0.0642829373 -0.0712409094
    """
    p = min(2.0 * large_speed_decay_rate(restitution_float(restitution)) - 1.0, 1.0)
    return (3.0 * p - p**3) / 24.0


def small_force_power(restitution) -> float:
    """gamma in w(F) ~ F^gamma exp(-S / F) as F -> 0, eqs. (weightfunc), (weightfunc2).

    Parameters
    ----------
    restitution : float or str
        r, 0 < r < 1, a float or a fraction string ("1/3").

    Returns
    -------
    float
        gamma = m - 3/2 where q < 1 (r > 1/2: the saddle v* = q (1 - q) / F of
        eq. (weightfunc), with P(0, v) ~ v^-m e^(-q v) of eq. (asym3)); -1/2 at q = 1 (r = 1/2,
        eq. (weightfunc2)); 0 where q > 1 (r < 1/2: the end point v = 0).

    Examples
    --------
    >>> from bouncing_ball.distribution import small_force_power
    >>> print(small_force_power(0.25), small_force_power(0.5), round(small_force_power(0.6), 10))
    0.0 -0.5 -1.0526867233
    """
    restitution = restitution_float(restitution)
    q = large_speed_decay_rate(restitution)
    if abs(q - 1.0) < 1e-12:
        return -0.5
    return large_speed_exponent(restitution) - 1.5 if q < 1.0 else 0.0


def _log_sum(log_terms, signs=None):
    """ln |sum_k signs_k exp(log_terms_k)| and its sign, without overflow."""
    log_terms = np.asarray(log_terms, dtype=float)
    top = np.max(log_terms)
    if not np.isfinite(top):
        return -np.inf, 0.0
    total = np.sum((1.0 if signs is None else signs) * np.exp(log_terms - top))
    return top + np.log(abs(total)), float(np.sign(total))


def _real_segment_terms(density, force, v1):
    """ln |terms| and signs of int_{SMALLEST_SPEED}^{v1} dv v h(v) psi_F(-v) (Gauss-Legendre in s),
    and ln of the closed-form part below SMALLEST_SPEED (C psi_F(0) eps^(2-beta) / (2-beta))."""
    v, log_vh = density.real_axis_nodes(v1)
    turning = 0.25 / force  # beyond, psi_F(-v) oscillates with amplitude O(F^(-1/6))
    inside = v <= turning
    log_psi, signs = np.empty(v.shape), np.ones(v.shape)
    log_psi[inside] = _log_psi(force, -v[inside])
    psi_beyond = _psi(force, -v[~inside])
    with np.errstate(divide="ignore"):
        log_psi[~inside] = np.log(np.abs(psi_beyond))
    signs[~inside] = np.sign(psi_beyond)
    log_terms = log_vh + log_psi
    beta = density.beta
    small = (
        density.log_amplitude
        + _log_psi(force, 0.0)
        + (2.0 - beta) * np.log(SMALLEST_SPEED)
        - np.log(abs(2.0 - beta))
        + np.log1p(-_small_speed_slope(force, beta))
    )
    return log_terms, signs, small, np.sign(2.0 - beta)


def _small_speed_slope(force, beta):
    """The linear term of psi_F(v) = psi_F(0) (1 + v psi'/psi + ...) in the closed-form part
    int_0^eps C v^(1-beta) psi_F(v) dv below eps = SMALLEST_SPEED, relative to its constant term:
    ((2 - beta)/(3 - beta)) eps F^(1/3) Ai'(c)/Ai(c), c = F^(-2/3)/4.  Without it the part is
    off by (eps F^(1/3))^(3 - beta) of the whole, which matters where beta nears 5/2 (r -> 0)
    and F^(1/3) eps is not small (F up to 1e30 in T(G))."""
    scaled = special.airye(0.25 * force ** (-2.0 / 3.0))
    ratio = scaled[1] / scaled[0]
    return (2.0 - beta) / (3.0 - beta) * SMALLEST_SPEED * force ** (1.0 / 3.0) * ratio


def _contour(force, v1, q):
    """Nodes and weights (dv) of the path from v1: at angle pi/3 until arg v = THETA_MAX, then
    radially, far enough that the Airy factor has decayed by e^-NEGLIGIBLE_EFOLDS more than
    h can grow."""
    direction = np.exp(1j * np.pi / 3.0)
    tangent = np.tan(THETA_MAX)
    t1 = v1 * tangent / (np.sin(np.pi / 3.0) - tangent * np.cos(np.pi / 3.0))
    scale = force ** (-1.0 / 3.0)  # the Airy scale (the saddle is wider: (|1 - 2q| / F)^(1/2))
    t, wt = _panels(0.0, t1, max(scale, t1 / 60.0))
    leg1 = v1 + t * direction
    p1 = v1 + t1 * direction
    rho1 = abs(p1)
    # radial leg: |Airy| ~ exp(-(2/3) F^(1/2) cos(3 (pi/3 - THETA_MAX)/2) rho^(3/2))
    c = (2.0 / 3.0) * np.sqrt(force) * np.cos(1.5 * (np.pi / 3.0 - THETA_MAX))
    growth = max((0.5 - q) * np.cos(THETA_MAX), 0.0) + 0.05  # |h(v)| ~ e^((1/2 - q) Re v)

    def decayed(rho):  # e-folds gained beyond rho1
        return c * (rho**1.5 - rho1**1.5) - growth * (rho - rho1) - NEGLIGIBLE_EFOLDS

    top = rho1 + 1.0
    while decayed(top) < 0.0:
        top = 2.0 * top
    rho2 = optimize.brentq(decayed, rho1, top)
    # panels at most 40 % wide in rho (h varies on the scale |v|) and 6 / F^(1/2) in rho^(3/2)
    # (the Airy phase)
    edges = [rho1]
    while edges[-1] < rho2:
        edges.append(min(1.4 * edges[-1], (edges[-1] ** 1.5 + 6.0 / np.sqrt(force)) ** (2.0 / 3.0)))
    edges = np.asarray(edges)
    half = 0.5 * np.diff(edges)[:, None]
    rho = (0.5 * (edges[:-1, None] + edges[1:, None]) + half * _GL_X[None, :]).ravel()
    leg2 = p1 / rho1 * rho
    w2 = p1 / rho1 * (half * _GL_W[None, :]).ravel()
    return np.concatenate([leg1, leg2]), np.concatenate([wt * direction, w2])


def _log_kernel_transform(density, forces):
    """B(F) (see ``_kernel_transform_table``)."""
    g, weights, transforms, tail = _kernel_transform_table(density)
    forces = np.atleast_1d(forces)
    return np.sum(weights * transforms / (forces[:, None] + g), axis=1) + tail


_KERNEL_TRANSFORMS = {}


def _kernel_transform_table(density):
    """T(G) at Gauss-Legendre nodes in ln G, the weights of int dG/(2 pi) e^(-1/(12G)) ...,
    and the closed-form remainder of B above LARGEST_KERNEL_FORCE (cached per density)."""
    key = id(density)
    if key in _KERNEL_TRANSFORMS and _KERNEL_TRANSFORMS[key][0] is density:
        return _KERNEL_TRANSFORMS[key][1]
    table = _compute_kernel_transform_table(density)
    _KERNEL_TRANSFORMS.clear()
    _KERNEL_TRANSFORMS[key] = (density, table)
    return table


def _kernel_transforms(density, g):
    """T(G) = int_0^inf dv v h(v) psi_G(v) at the forces ``g`` (Gauss-Legendre panels in s, and
    the closed form C psi_G(0) eps^(2-beta) / (2-beta) below eps = SMALLEST_SPEED)."""
    beta = density.beta
    # v grid: Gauss-Legendre panels in s up to where P(0, v) has fallen by e^-60 from its peak
    top = min(density.largest, 20.0 + NEGLIGIBLE_EFOLDS / density.q)
    s, ws = _panels(coordinate_of_speed(SMALLEST_SPEED), coordinate_of_speed(top), 0.5)
    v = speed_of_coordinate(s)
    log_vh = np.log(ws * _jacobian(v) * v) + 0.5 * v + density.log_density(v)
    # psi_G(v) <= G^(-1/6) exp(-(2/3) (G^(1/3) v)^(3/2)): the terms beyond e^-120 of the
    # largest such bound (per G) are dropped before the Airy function is evaluated
    bound = (
        log_vh[None, :]
        - np.log(g)[:, None] / 6.0
        - (2.0 / 3.0) * (np.cbrt(g)[:, None] * v[None, :]) ** 1.5
    )
    which, index = np.nonzero(
        bound > np.max(bound, axis=1, keepdims=True) - 2.0 * NEGLIGIBLE_EFOLDS
    )
    log_psi = _log_psi(g[which], v[index])
    body = np.bincount(which, np.exp(log_vh[index] + log_psi), minlength=g.size)
    small = (
        np.exp(density.log_amplitude + _log_psi(g, 0.0))
        * SMALLEST_SPEED ** (2.0 - beta)
        / (2.0 - beta)
        * (1.0 + _small_speed_slope(g, beta))
    )
    return body + small


# T(G) G^-alpha e^(1/(12G)) (smooth in ln G, alpha = (2 beta - 5)/6) is computed at
# KERNEL_TRANSFORM_NODES Chebyshev nodes on panels KERNEL_TRANSFORM_WIDTH wide in ln G and
# interpolated to the quadrature nodes of B(F)
KERNEL_TRANSFORM_WIDTH = 3.0


KERNEL_TRANSFORM_NODES = 16


def _compute_kernel_transform_table(density):
    """T(G) at Gauss-Legendre nodes in ln G, with the weights of int dG/(2 pi) e^(-1/(12G)) ...,
    and the closed-form remainder above LARGEST_KERNEL_FORCE (returned as a coefficient of
    int_{G_c}^inf G^alpha / (F + G) dG)."""
    beta = density.beta
    alpha = (2.0 * beta - 5.0) / 6.0
    lo, hi = np.log(2e-3), np.log(LARGEST_KERNEL_FORCE)
    log_g, wg = _panels(lo, hi, 1.0)
    g = np.exp(log_g)
    count = int(np.ceil((hi - lo) / KERNEL_TRANSFORM_WIDTH))
    edges = np.linspace(lo, hi, count + 1)
    x = np.cos(np.pi * (np.arange(KERNEL_TRANSFORM_NODES) + 0.5) / KERNEL_TRANSFORM_NODES)
    nodes = 0.5 * (edges[:-1, None] + edges[1:, None]) + 0.5 * np.diff(edges)[:, None] * x
    at_nodes = np.exp(nodes)
    smooth = _kernel_transforms(density, at_nodes.ravel()).reshape(nodes.shape)
    smooth *= np.exp(1.0 / (12.0 * at_nodes) - alpha * nodes)
    index = np.clip(np.searchsorted(edges, log_g) - 1, 0, count - 1)
    t = (2.0 * log_g - edges[index] - edges[index + 1]) / (edges[index + 1] - edges[index])
    coefficients = np.array([np.polynomial.chebyshev.chebfit(x, row, x.size - 1) for row in smooth])
    interpolated = np.polynomial.chebyshev.chebval(t, coefficients[index].T, tensor=False)
    transforms = interpolated * np.exp(alpha * log_g - 1.0 / (12.0 * g))
    weights = wg * g * np.exp(-1.0 / (12.0 * g)) / (2.0 * np.pi)
    tail_coefficient = np.exp(density.log_amplitude) * _airy_mellin(2.0 - beta) / (2.0 * np.pi)
    tail = tail_coefficient * LARGEST_KERNEL_FORCE**alpha / -alpha  # F << G_c
    return g, weights, transforms, tail


EPSILON = np.finfo(float).eps


#: A contour node of A(F) whose term (by the real-axis P(0, |v|)) is below the largest by more
#: than CONTOUR_SLACK_MARGIN e-folds may take P(0, v) from a Nystrom sum that many e-folds less
#: accurate (at most LARGEST_SLACK: still ~1e-4 of itself, below 1e-19 of the largest term).
CONTOUR_SLACK_MARGIN = 10.0


LARGEST_SLACK = 26.0


# rounding error of a sum of N terms of mixed signs, in units of EPSILON times the sum of their
# magnitudes (~ N^(1/2) for N ~ 1000 terms)
ROUNDING = 50.0


def _split_point(q, force):
    """v1: the turning point 1/(4F) where q >= 1/2, the saddle q (1 - q) / F where q < 1/2; at
    large F at least half the Airy scale F^(-1/3) (psi is O(1) there: a shorter complex path)."""
    v1 = 0.25 / force if q >= 0.5 else q * (1.0 - q) / force
    return max(v1, 0.5 * force ** (-1.0 / 3.0))


def _log_contour_part(density, force, with_noise=True):
    """ln |A(F)|, its sign, and ln of an estimate of its rounding error (NaN without
    ``with_noise``): the real segment plus 2 Re of the complex path.  Raises ValueError where
    P(0, v) would be needed beyond the range in which the solution's is accurate."""
    if density.ray is not None:
        return _log_ray_contour_part(density.ray, force, with_noise)
    q = density.q
    v1 = _split_point(q, force)
    cut = min(v1, density.largest)
    log_terms, signs, small, small_sign = _real_segment_terms(density, force, cut)
    all_terms = np.append(log_terms, small)
    all_signs = np.append(signs, small_sign)
    endpoint_negligible = log_terms[-1] < np.max(all_terms) - 36.0  # 2e-16
    if cut < v1 and not endpoint_negligible:
        raise ValueError(
            f"w({force}) needs P(0, v) beyond v = {density.largest:.4g}: solve with a higher "
            "highest node (distribution.outgoing_speed_solution)"
        )
    if endpoint_negligible:
        log_value, sign = _log_sum(all_terms, all_signs)
        return log_value, sign, _log_sum(all_terms)[0] + np.log(ROUNDING * EPSILON)
    v, wv = _contour(force, v1, q)
    # drop the nodes where the Airy factor times e^((1/2 - q) Re v) (|h| up to powers of v)
    # is below e^-50 of the largest term
    log_airy = _log_psi_omega(force, v)
    estimate = np.log(np.abs(wv * v)) + (0.5 - q) * v.real + log_airy.real
    keep = estimate > max(np.max(estimate), np.max(all_terms)) - 50.0
    v, wv, log_airy = v[keep], wv[keep], log_airy[keep]
    if np.max(np.abs(v)) > density.largest:
        raise ValueError(
            f"w({force}) needs P(0, v) at |v| = {np.max(np.abs(v)):.4g} > {density.largest:.4g}"
        )
    # a node far below the largest term needs P(0, v) less accurately: its slack (the e-folds,
    # less CONTOUR_SLACK_MARGIN for |P(0, v) e^(q v)| off the real axis, up to LARGEST_SLACK)
    # from the real-axis |P(0, |v|)| e^(q |v|)
    proxy = estimate[keep] + density.log_density(np.abs(v)) + q * np.abs(v)
    slack = np.clip(
        max(np.max(proxy), np.max(all_terms)) - proxy - CONTOUR_SLACK_MARGIN, 0.0, LARGEST_SLACK
    )
    scaled, magnitude = density.scaled_complex(v, slack, with_noise)
    log_rest = np.log(wv * v) + (0.5 - q) * v + log_airy
    log_terms_c = np.log(scaled) + log_rest  # complex logs
    top = max(np.max(log_terms_c.real), np.max(all_terms))
    contour = 2.0 * np.sum(np.exp(log_terms_c - top)).real
    real = np.sum(all_signs * np.exp(all_terms - top))
    total = contour + real
    if not with_noise:
        return top + np.log(abs(total)), float(np.sign(total)), np.nan
    noise = 2.0 * np.sum(np.exp(np.log(magnitude) + log_rest.real - top)) * EPSILON
    noise += np.sum(np.exp(all_terms - top)) * ROUNDING * EPSILON
    return top + np.log(abs(total)), float(np.sign(total)), top + np.log(noise)


#: Panels of the ray contour of A(F): Gauss-Legendre in ln rho, RAY_PANEL_NODES nodes each, no
#: wider than 1 in ln rho and across each of which the integrand turns through at most
#: RAY_PANEL_TURN radians of phase plus e-folds of modulus.
RAY_PANEL_NODES = 20


RAY_PANEL_TURN = 10.0


_RAY_PANEL_X, _RAY_PANEL_W = np.polynomial.legendre.leggauss(RAY_PANEL_NODES)


def _ray_log_integrand(ray_density, force, rho):
    """ln of v h(v) (-omega) F^(-1/6) Ai(omega zeta(v)) at v = rho ray (complex)."""
    v = rho * ray_density.ray
    return np.log(v) + 0.5 * v + ray_density.log_density(rho) + _log_psi_omega(force, v)


def _ray_contour_nodes(ray_density, force):
    """ln rho and weights (d ln rho) of the panels of the ray contour of A(F), up to where its
    integrand has fallen by NEGLIGIBLE_EFOLDS + 10 below its largest modulus.

    The panels follow the integrand's log-derivative in v, (2 - beta) / v + 1/2 - q +
    omega F^(1/3) (z + 1/2)^(1/2) with z = omega zeta (Ai'(z) / Ai(z) ~ -(z + 1/2)^(1/2): the
    leading term at large |z|, -0.707 against -0.729 at z = 0), integrated on a grid in ln rho:
    its imaginary and real parts along the ray measure the phase turned and the e-folds."""
    ray = ray_density.ray
    t = np.arange(np.log(SMALLEST_SPEED), np.log(ray_density.largest), 0.02)
    rho = np.exp(t)
    v = rho * ray
    z = OMEGA * (0.25 * force ** (-2.0 / 3.0) - force ** (1.0 / 3.0) * v)
    slope = (
        ray
        * rho
        * (
            (2.0 - ray_density.beta) / v
            + 0.5
            - ray_density.q
            + OMEGA * np.cbrt(force) * np.sqrt(z + 0.5)
        )
    )
    step = 0.5 * (slope[1:] + slope[:-1]) * np.diff(t)
    level = np.concatenate([[0.0], np.cumsum(step.real)])
    above = np.nonzero(level > np.max(level) - NEGLIGIBLE_EFOLDS - 10.0)[0]
    if above[-1] == t.size - 1:
        raise ValueError(
            f"w({force}) needs P(0, v) on the ray beyond |v| = {ray_density.largest:.4g}"
        )
    end = above[-1] + 1
    cost = np.concatenate([[0.0], np.cumsum(np.abs(step.real) + np.abs(step.imag))])[: end + 1]
    t = t[: end + 1]
    by_cost = np.interp(np.arange(0.0, cost[-1], RAY_PANEL_TURN), cost, t)
    edges = np.unique(np.concatenate([by_cost, np.arange(t[0], t[-1], 1.0), [t[-1]]]))
    half = 0.5 * np.diff(edges)[:, None]
    x = (0.5 * (edges[:-1, None] + edges[1:, None]) + half * _RAY_PANEL_X[None, :]).ravel()
    return x, (half * _RAY_PANEL_W[None, :]).ravel()


def _log_ray_contour_part(ray_density, force, with_noise=True):
    """ln |A(F)|, its sign and ln of an estimate of its error (NaN without ``with_noise``):
    A = 2 Re int_0^inf along the ray v = rho e^(i RAY_ANGLE) of v h(v) (-omega) F^(-1/6)
    Ai(omega zeta), with P(0, v) on the ray from ``_RayDensity`` (the two halves of psi_F(-v)
    = 2 Re[-omega F^(-1/6) Ai(omega zeta)] turned onto the ray and its mirror image, where
    the Airy factor decays; the integrand is analytic in between).  The part below
    SMALLEST_SPEED is C psi(0) (eps ray)^(2 - beta) / (2 - beta)."""
    t, wt = _ray_contour_nodes(ray_density, force)
    rho = np.exp(t)
    beta = ray_density.beta
    log_terms = np.log(wt * rho * ray_density.ray) + _ray_log_integrand(ray_density, force, rho)
    small = (
        ray_density.log_amplitude
        + (2.0 - beta) * (np.log(SMALLEST_SPEED) + 1j * RAY_ANGLE)
        - np.log(2.0 - beta)
        + _log_psi_omega(force, np.array([0.0 + 0.0j]))[0]
    )
    log_terms = np.append(log_terms, small)
    top = np.max(log_terms.real)
    total = 2.0 * np.sum(np.exp(log_terms - top)).real
    if not with_noise:
        return top + np.log(abs(total)), float(np.sign(total)), np.nan
    size = 2.0 * np.sum(np.exp(log_terms.real - top))
    noise = size * (ROUNDING * EPSILON + ray_density.error)
    return top + np.log(abs(total)), float(np.sign(total)), top + np.log(noise)


def _log_weight_with_noise(forces, density, with_noise=True):
    """ln w(F) and an estimate of its relative rounding error (inf, and ln w NaN, where the
    solution's P(0, v) does not reach far enough; NaN without ``with_noise``)."""
    forces = np.atleast_1d(np.asarray(forces, dtype=float))
    b = _log_kernel_transform(density, forces)
    log_w = np.full(forces.size, np.nan)
    noise = np.full(forces.size, np.inf)
    for k, f in enumerate(forces):
        try:
            log_a, sign_a, log_noise = _log_contour_part(density, f, with_noise)
        except ValueError:
            continue
        z = 1.0 / (12.0 * f)
        log_b = np.log(abs(b[k])) - z  # B < 0 is possible where beta > 2 (regularised)
        top = max(log_a, log_b)
        total = sign_a * np.exp(log_a - top) - np.sign(b[k]) * np.exp(log_b - top)
        if total > 0.0:
            log_w[k] = top + np.log(total)
            noise[k] = np.exp(log_noise - log_w[k]) + ROUNDING * EPSILON * np.exp(log_b - log_w[k])
    return log_w, noise


def log_weight_function(force, solution, density=None):
    """ln w(F) of eq. (weightfunc), evaluated directly (not interpolated).

    w(F) = A(F) - e^(-1/(12F)) B(F), A along a contour into the complex v plane (the module's
    account of the method).

    Parameters
    ----------
    force : array_like
        Values of F > 0.
    solution : solver.OutgoingSpeedSolution
        P(0, v) of eq. (inteq); ``outgoing_speed_solution`` reaches as far as small F needs.
    density : optional
        The solution's P(0, v) prepared for the contour integrals, to reuse across calls (a
        private type of this module); built from ``solution`` if None.

    Returns
    -------
    numpy.ndarray
        ln w(F), the shape of ``force``; NaN where the solution's P(0, v) does not reach far
        enough.

    Examples
    --------
    Solving compiles the kernel on its first call (so not run as a doctest); at r = 1/2 w(F)
    is eq. (weightfunc2):

    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> from bouncing_ball.distribution import log_weight_function, outgoing_speed_solution
    >>> solution = outgoing_speed_solution("1/2")  # doctest: +SKIP
    >>> print(np.exp(log_weight_function([0.1, 1.0], solution)).round(8))  # doctest: +SKIP
    [0.22905337 0.15334074]
    >>> print(exact.weight_function([0.1, 1.0], "1/2").round(8))
    [0.22905337 0.15334074]
    """
    density = _outgoing_density(solution) if density is None else density
    return _log_weight_with_noise(force, density, with_noise=False)[0].reshape(np.shape(force))


def weight_function(force, solution, density=None):
    """w(F) of eq. (weightfunc), evaluated directly (``log_weight_function``, exponentiated).

    Parameters
    ----------
    force : array_like
        Values of F > 0.
    solution : solver.OutgoingSpeedSolution
        P(0, v) of eq. (inteq), from ``outgoing_speed_solution``.
    density : optional
        As in ``log_weight_function``.

    Returns
    -------
    numpy.ndarray
        w(F), the shape of ``force``; it over- or underflows where ``log_weight_function``
        does not.

    Examples
    --------
    Solving compiles the kernel on its first call (so not run as a doctest):

    >>> from bouncing_ball.distribution import outgoing_speed_solution, weight_function
    >>> solution = outgoing_speed_solution("1/2")  # doctest: +SKIP
    >>> print(weight_function([0.1, 1.0], solution).round(8))  # doctest: +SKIP
    [0.22905337 0.15334074]
    """
    return np.exp(log_weight_function(force, solution, density))
