"""The flight-time density given the outgoing speed u, f(t | u) = int_0^inf dv p(t, v | u).

By Gauss-Legendre in w = v^(1/2) over the window ``|v - v*| < 6.5 t^(1/2)`` (e^-42 of the
Gaussian of eq. (joint) beyond); the integrand 2 w^3 erf(a w) exp[-(w^2 - v*)^2 / t] is entire
in w.
"""

import numpy as np
from scipy import special

from .conditional_moments import trapezoid_nodes
from .joint_law import SQRT3

__all__ = [
    "log_flight_time_density",
    "flight_time_density",
    "free_flight_time_density",
]


# Gauss-Legendre on [0, 1] for the v-integral of f(t | u), in w = v^(1/2): 40 nodes give 1e-13
_SPEED_NODES, _SPEED_WEIGHTS = np.polynomial.legendre.leggauss(48)


_SPEED_NODES, _SPEED_WEIGHTS = 0.5 * (_SPEED_NODES + 1.0), 0.5 * _SPEED_WEIGHTS


WINDOW = 6.5  # |v - v*| < WINDOW t^(1/2): the Gaussian of f(t | u) beyond is below e^-42


TIME_STEP = 0.1  # trapezoidal step in s = ln t + t^(1/2) for integrals over f(t | u)


EXPONENT_CUT = 45.0  # time window: the Gaussian factor of f(t | u) above e^-45


def _log_speed_integral(t, u, centre):
    """ln int_0^inf dv v exp[-(v - centre)^2 / t] erf((3 u v / t)^(1/2)), vectorised: Gauss-Legendre
    in w = v^(1/2) (the integrand 2 w^3 erf(a w) exp[-(w^2 - centre)^2 / t] is entire in w) over
    |v - centre| < WINDOW t^(1/2)."""
    half_width = WINDOW * np.sqrt(t)
    w_lo = np.sqrt(np.maximum(centre - half_width, 0.0))[..., None]
    w_hi = np.sqrt(centre + half_width)[..., None]
    w = w_lo + (w_hi - w_lo) * _SPEED_NODES
    v = w * w
    integrand = (
        2.0
        * w
        * v
        * special.erf(np.sqrt(3.0 * u / t)[..., None] * w)
        * np.exp(-((v - centre[..., None]) ** 2) / t[..., None])
    )
    with np.errstate(divide="ignore"):
        return np.log((w_hi - w_lo)[..., 0] * (integrand @ _SPEED_WEIGHTS))


def log_flight_time_density(t, u):
    """ln f(t | u), the log of the flight-time density given the outgoing speed.

    f(t | u) = int_0^inf dv p(t, v | u) of eq. (joint), by Gauss-Legendre in w = v^(1/2) (item 5
    of the module's account).

    Parameters
    ----------
    t : array_like
        Flight times.
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        Broadcast; -inf where t or u is not positive.
    """
    t, u = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(u, dtype=float))
    valid = (t > 0.0) & (u > 0.0)
    t, u = np.where(valid, t, 1.0), np.where(valid, u, 1.0)
    gauss = -3.0 * (t - 2.0 * u) ** 2 / (16.0 * t)
    value = np.log(SQRT3 / (2.0 * np.pi)) - 2.0 * np.log(t) + gauss
    value = value + _log_speed_integral(t, u, 0.25 * (t + 2.0 * u))
    return np.where(valid, value, -np.inf)


def flight_time_density(t, u):
    """f(t | u): the density of the flight time of a ball leaving the floor with speed u.

    The integral over the return speed of eq. (joint) (see ``log_flight_time_density``).

    Parameters
    ----------
    t : array_like
        Flight times.
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        Broadcast; 0 where t or u is not positive.

    Examples
    --------
    It is normalised, with the mean of eq. (meanT):

    >>> from bouncing_ball.flight_time import flight_time_density, flight_time_nodes
    >>> t, weights = flight_time_nodes(1.0)
    >>> f = weights * flight_time_density(t, 1.0)
    >>> print(round(f.sum(), 10), round(f @ t, 8))
    1.0 3.15247858
    """
    return np.exp(log_flight_time_density(t, u))


def free_flight_time_density(t, u):
    """f_0(t | u) = int dv p_0(t, v | u): McKean's flight-time law without gravity.

    The short-flight limit of ``flight_time_density`` (eq. (short)).

    Parameters
    ----------
    t : array_like
        Flight times, > 0.
    u : array_like
        Outgoing speeds, > 0.

    Returns
    -------
    numpy.ndarray
    """
    t, u = np.broadcast_arrays(np.asarray(t, dtype=float), np.asarray(u, dtype=float))
    value = (
        np.log(SQRT3 / (2.0 * np.pi))
        - 2.0 * np.log(t)
        - 0.75 * u * u / t
        + _log_speed_integral(t, u, 0.5 * u)
    )
    return np.exp(value)


def _flight_time_window(u, cut=EXPONENT_CUT):
    """[t_lo, t_hi] outside which 3 (t - 2u)^2 / (16 t) > cut: f(t | u) is negligible there."""
    b = 4.0 * u + 16.0 * cut / 3.0
    t_hi = 0.5 * (b + np.sqrt(b * b - 16.0 * u * u))
    return 4.0 * u * u / t_hi, t_hi


def flight_time_nodes(u, step=TIME_STEP):
    """Flight times and weights that integrate functions of t against f(t | u).

    A trapezoidal rule in s = ln t + t^(1/2) over the times where the Gaussian factor of
    f(t | u) is above e^-45.

    Parameters
    ----------
    u : float
        The outgoing speed.
    step : float
        The rule's step in s.

    Returns
    -------
    t, weights : numpy.ndarray
    """
    return trapezoid_nodes(*_flight_time_window(u), step)
