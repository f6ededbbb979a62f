"""The Airy function of eq. (psi) and where the F integral of eq. (fpsol) can be evaluated.

Ai for real arguments (``airy_ai``) and its exponentially scaled and oscillating forms, from
Bessel functions where scipy evaluates those faster than its ``airy``; and the check of an
(x, v) for the F integral (``check_force_integral_point``).  numpy and scipy.special only: the
exact solutions (``exact``) and the solver's P(x, v) (``distribution``) both use them, and a
job that needs only the exact solution loads neither numba nor the solver.
"""

import numpy as np
from scipy import special

__all__ = [
    "LARGEST_AIRY_PHASE",
    "BESSEL_AIRY_PHASE",
    "force_integral_phase",
    "SERIES_AIRY",
    "ASYMPTOTIC_AIRY",
    "MACLAURIN_TERMS",
    "ASYMPTOTIC_TERMS",
    "scaled_airy_ai",
    "oscillating_airy_ai",
    "airy_ai",
    "check_force_integral_point",
]


#: On the outgoing side v > 0 the Airy factor of the F integral of eq. (fpsol) oscillates; up to
#: F = 60 / x its phase (2/3) F^(1/2) v^(3/2) reaches (2/3) (60 / x)^(1/2) v^(3/2).  quad follows
#: it to ~4e4 (against P(0, v) as x -> 0: 1e-7 at (x, v) = (1e-8, 0.8), (1e-7, 1.7)) and fails
#: beyond (1e-5 wrong at (1e-6, 6), phase 7.6e4; a negative density at (1e-8, 2), phase 1.5e5).
LARGEST_AIRY_PHASE = 4.0e4


def force_integral_phase(x, v):
    """The phase of the Airy factor of eq. (fpsol) at the F integral's end, F = 60 / x.

    Parameters
    ----------
    x, v : array_like
        The height x > 0 and the velocity.

    Returns
    -------
    numpy.ndarray or float
        (2/3) (60 / x)^(1/2) v^(3/2) for v > 0, 0 for v <= 0 (no oscillation).
    """
    return (2.0 / 3.0) * np.sqrt(60.0 / x) * np.maximum(v, 0.0) ** 1.5


#: Ai from ``K_1/3`` (``scaled_airy_ai``) where ``|arg z|`` is below this (the formula holds up
#: to 2 pi / 3).
BESSEL_AIRY_PHASE = 2.0


#: ``scaled_airy_ai`` sums the Maclaurin series of Ai (DLMF 9.4.1) where ``|z| <= SERIES_AIRY``
#: (MACLAURIN_TERMS terms of each of its two series: the next is below 1e-20 of the first), and
#: the asymptotic series (DLMF 9.7.5) where ``|z| >= ASYMPTOTIC_AIRY`` and
#: ``|arg z| <= 2 pi / 3`` (ASYMPTOTIC_TERMS terms: at zeta = (2/3) abs(z)^(3/2) >= 27.7 the next,
#: ~ k! / (2 zeta)^k, is below 1e-16); both within 1e-15 of mpmath's Ai at 30 digits (scipy's
#: airye within 4e-15 there: tests/unit/test_airy.py holds them to 5e-15 of it), several
#: times faster than the Bessel function.
SERIES_AIRY = 1.0


ASYMPTOTIC_AIRY = 12.0


MACLAURIN_TERMS = 9


ASYMPTOTIC_TERMS = 22


_AI0 = 0.355028053887817239260063186004  # Ai(0)
_AIP0 = 0.258819403792806798405183560189  # -Ai'(0)


def _asymptotic_coefficients(count):
    u = [1.0]
    for k in range(1, count):
        u.append(u[-1] * (6 * k - 5) * (6 * k - 3) * (6 * k - 1) / ((2 * k - 1) * 216.0 * k))
    return np.array(u) * (-1.0) ** np.arange(count)


_ASYMPTOTIC_U = _asymptotic_coefficients(ASYMPTOTIC_TERMS)


def _maclaurin_airy(z):
    """Ai(z) exp((2/3) z^(3/2)) for |z| <= SERIES_AIRY: Ai = Ai(0) f - (-Ai'(0)) g with
    f = sum 3^k (1/3)_k z^(3k) / (3k)!, g = sum 3^k (2/3)_k z^(3k+1) / (3k+1)!."""
    cube = z * z * z
    f_term, g_term = np.ones_like(z), z.copy()
    f, g = f_term.copy(), g_term.copy()
    for k in range(MACLAURIN_TERMS - 1):
        f_term = f_term * cube / ((3 * k + 2) * (3 * k + 3))
        g_term = g_term * cube / ((3 * k + 3) * (3 * k + 4))
        f, g = f + f_term, g + g_term
    return (_AI0 * f - _AIP0 * g) * np.exp((2.0 / 3.0) * z**1.5)


def _asymptotic_airy(z):
    """Ai(z) exp((2/3) z^(3/2)) for |z| >= ASYMPTOTIC_AIRY, |arg z| <= 2 pi / 3:
    z^(-1/4) / (2 pi^(1/2)) sum_k (-1)^k u_k zeta^-k, zeta = (2/3) z^(3/2)."""
    inverse = 1.0 / ((2.0 / 3.0) * z**1.5)
    total = np.full_like(z, _ASYMPTOTIC_U[-1])
    for u in _ASYMPTOTIC_U[-2::-1]:
        total = total * inverse + u
    return z**-0.25 / (2.0 * np.sqrt(np.pi)) * total


def scaled_airy_ai(z):
    """Ai(z) exp((2/3) z^(3/2)), the Airy function without its decay, for complex z.

    Its Maclaurin series where ``|z| <= SERIES_AIRY``; its asymptotic series where
    ``|z| >= ASYMPTOTIC_AIRY`` and ``|arg z| <= 2 pi / 3``; elsewhere, for ``|arg z| <
    BESSEL_AIRY_PHASE`` from the scaled Bessel function, ``(z / 3)^(1/2) kve(1/3, (2/3)
    z^(3/2)) / pi`` (DLMF 9.6.1: the same to ~5e-15, and as close to mpmath's, three to nine
    times faster than scipy's airye), and scipy's airye beyond.

    Parameters
    ----------
    z : array_like
        Arguments, real or complex.

    Returns
    -------
    numpy.ndarray
        Ai(z) exp((2/3) z^(3/2)), the shape of ``z``.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy import special
    >>> from bouncing_ball.airy import scaled_airy_ai
    >>> z = np.array([1e-3 + 0.5j, 3.0 - 1.0j, 40.0 * np.exp(2j)])
    >>> bool(np.allclose(scaled_airy_ai(z), special.airye(z)[0], rtol=1e-14, atol=0.0))
    True
    """
    z = np.asarray(z)
    size = np.abs(z)
    angle = np.abs(np.angle(z))
    small = size <= SERIES_AIRY
    large = (size >= ASYMPTOTIC_AIRY) & (angle <= 2.0 * np.pi / 3.0 + 1e-12)
    bessel = ~small & ~large & (angle < BESSEL_AIRY_PHASE)
    out = np.empty(z.shape, dtype=np.result_type(z.dtype, float))
    out[small] = _maclaurin_airy(z[small])
    out[large] = _asymptotic_airy(z[large])
    out[bessel] = (
        np.sqrt(z[bessel] / 3.0) * special.kve(1.0 / 3.0, (2.0 / 3.0) * z[bessel] ** 1.5) / np.pi
    )
    rest = ~small & ~large & ~bessel
    out[rest] = special.airye(z[rest])[0]
    return out


def oscillating_airy_ai(z):
    """Ai(-z) for real z >= 0, where the Airy function oscillates.

    From the Hankel function: ``(z^(1/2) / 2) (J_1/3 - Y_1/3 / 3^(1/2))`` at
    ``zeta = (2/3) z^(3/2)`` (DLMF 9.6.6 with ``J_-1/3 = (J_1/3 - 3^(1/2) Y_1/3) / 2``: as
    close to mpmath's as scipy's airy up to z = 120, and several times faster); scipy's airy
    where z < 1e-3.

    Parameters
    ----------
    z : array_like
        Real arguments, z >= 0.

    Returns
    -------
    numpy.ndarray
        Ai(-z), the shape of ``z``.
    """
    z = np.asarray(z, dtype=float)
    out = np.empty(z.shape)
    small = z < 1e-3
    out[small] = special.airy(-z[small])[0]
    hankel = special.hankel1(1.0 / 3.0, (2.0 / 3.0) * z[~small] ** 1.5)
    out[~small] = 0.5 * np.sqrt(z[~small]) * (hankel.real - hankel.imag / np.sqrt(3.0))
    return out


def airy_ai(z):
    """Ai(z) for real z, from Bessel functions where ``|z| > 10``.

    scipy evaluates those several times faster there than its airy.  scipy's airy where
    ``|z| <= 10``; ``(z / 3)^(1/2) K_1/3(zeta) / pi`` above (DLMF 9.6.1);
    ``(t^(1/2) / 2) (J_1/3(zeta) - Y_1/3(zeta) / 3^(1/2))`` at ``z = -t`` below (DLMF 9.6.6
    with 10.4.7), where ``zeta = (2/3) |z|^(3/2)`` and J and Y come from one Hankel function.
    Where the Airy function oscillates, neither this nor scipy's airy can beat a few rounding
    errors of the phase zeta.

    Parameters
    ----------
    z : array_like
        Real arguments.

    Returns
    -------
    numpy.ndarray
        Ai(z), the shape of ``z``.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy import special
    >>> from bouncing_ball.airy import airy_ai
    >>> z = np.array([-50.0, -1.0, 0.0, 2.0, 30.0])
    >>> bool(np.allclose(airy_ai(z), special.airy(z)[0], rtol=1e-12, atol=0.0))
    True
    """
    z = np.asarray(z, dtype=float)
    out = np.empty(z.shape)
    middle, below, above = np.abs(z) <= 10.0, z < -10.0, z > 10.0
    out[middle] = special.airy(z[middle])[0]
    out[below] = oscillating_airy_ai(-z[below])
    out[above] = scaled_airy_ai(z[above]) * np.exp(-(2.0 / 3.0) * z[above] ** 1.5)
    return out


def check_force_integral_point(x: float, v: float) -> None:
    """Refuse an (x, v) at which the F integral of eq. (fpsol) diverges or quad cannot follow it.

    The integral converges and quad evaluates it at x > 0 where the phase of psi_F(-v) stays
    below ``LARGEST_AIRY_PHASE`` (any x > 0 where v <= 0; x >= 1e-4 up to v = 18), and at x = 0
    only with v < 0.  Below that x at v > 0, P(x, v) is the near-wall series of eq. (fp)
    (``near_wall.distribution_near_wall``).

    Parameters
    ----------
    x : float
        The height.
    v : float
        The velocity.

    Returns
    -------
    None

    Raises
    ------
    ValueError
        Naming x (and the smallest x it can be at this v), elsewhere.

    Examples
    --------
    >>> from bouncing_ball.airy import check_force_integral_point
    >>> check_force_integral_point(0.0, -1.0)
    >>> check_force_integral_point(0.0, 1.0)
    Traceback (most recent call last):
    ...
    ValueError: x = 0.0: the F integral of eq. (fpsol) needs x > 0, or x = 0 with v < 0 (v = 1.0)
    >>> check_force_integral_point(1e-8, 2.0)
    Traceback (most recent call last):
    ...
    ValueError: x = 1e-08: at v = 2.0 the F integral of eq. (fpsol) ... below x = 1.3e-07; ...
    """
    if not x >= 0.0 or (x == 0.0 and not v < 0.0):
        raise ValueError(
            f"x = {x}: the F integral of eq. (fpsol) needs x > 0, or x = 0 with v < 0 (v = {v})"
        )
    if x > 0.0 and force_integral_phase(x, v) > LARGEST_AIRY_PHASE:
        smallest = 60.0 * ((2.0 / 3.0) * v**1.5 / LARGEST_AIRY_PHASE) ** 2
        raise ValueError(
            f"x = {x}: at v = {v} the F integral of eq. (fpsol) oscillates too fast to evaluate "
            f"below x = {smallest:.2g}; use x = 0 (P(0, v)) or a larger x"
        )
