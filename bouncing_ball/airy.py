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


def scaled_airy_ai(z):
    """Ai(z) exp((2/3) z^(3/2)), the Airy function without its decay, for complex z.

    scipy's airye, with its leading asymptotic form where ``|z| > 1e6`` (scipy returns NaN
    there); for ``0 < |z| <= 1e6`` with ``|arg z| < BESSEL_AIRY_PHASE`` from the scaled Bessel
    function, ``(z / 3)^(1/2) kve(1/3, (2/3) z^(3/2)) / pi`` (DLMF 9.6.1: the same to ~5e-15,
    and as close to mpmath's, three to nine times faster).

    Parameters
    ----------
    z : array_like
        Arguments, real or complex.

    Returns
    -------
    numpy.ndarray
        Ai(z) exp((2/3) z^(3/2)), the shape of ``z``.
    """
    z = np.asarray(z)
    big = np.abs(z) > 1e6
    far = np.where(big, z, 1e6)
    asymptotic = far**-0.25 / (2.0 * np.sqrt(np.pi)) * (1.0 - 5.0 / (48.0 * far**1.5))
    bessel = (z != 0.0) & (np.abs(np.angle(z)) < BESSEL_AIRY_PHASE) & ~big
    out = np.where(big, asymptotic, 0.0 * z)
    out[bessel] = (
        np.sqrt(z[bessel] / 3.0) * special.kve(1.0 / 3.0, (2.0 / 3.0) * z[bessel] ** 1.5) / np.pi
    )
    rest = ~bessel & ~big
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
