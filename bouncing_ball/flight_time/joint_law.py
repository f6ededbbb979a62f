"""The joint law of a flight's time and return speed, eq. (joint), and its time moments, eq. (timemoments).

1. McKean's law without gravity.  For integrated Brownian motion with unit diffusion
   (Var B_t = t) started at x = 0 with velocity a > 0, McKean (J. Math. Kyoto Univ. 2, 227
   (1963), eqs. (5), (6); also Lachal) gives the joint density of the hitting time and speed, ::

       (3 w / (pi sqrt(2) t^2)) exp[-2 (w^2 - a w + a^2) / t] int_0^(4 a w / t) e^(-3 th / 2) dth / (pi th)^(1/2).

   The integral is (2/3)^(1/2) erf[(6 a w / t)^(1/2)].  Our noise has Var = 2 t, i.e. speeds are
   sqrt(2) times McKean's (a = u / sqrt 2, w = v / sqrt 2, density x 1/sqrt 2)::

       p_0(t, v | u) = (sqrt(3) v / (2 pi t^2)) exp[-(v^2 - u v + u^2) / t] erf[(3 u v / t)^(1/2)].

   (= v P_0(0, -v; 0, u; t) of Appendix A.)

2. Gravity, eq. (0g): P_g = exp[-(v - v0)/2 - t/4] P_0 at incoming velocity -v, v0 = u, so
   p(t, v | u) = exp[(v + u)/2 - t/4] p_0(t, v | u).  The exponents combine into a sum of squares, ::

       p(t, v | u) = (sqrt(3) v / (2 pi t^2)) exp{-[(t - u - v)^2 + 3 (v - u)^2] / (4 t)}
                     * erf[(3 u v / t)^(1/2)],                                        (joint)

   every term <= 0: nothing overflows, nothing cancels (the erf of a small argument is
   evaluated to full relative precision by scipy).  In v at fixed t the exponent is
   -(v - v*)^2 / t - 3 (t - 2 u)^2 / (16 t) with v* = (t + 2 u) / 4: the ballistic flight time 2 u
   with a Gaussian spread.

3. Time moments of the return at fixed v, in closed form.  With
   erf(s^(1/2)) = 2 (s / pi)^(1/2) int_0^1 dy e^(-s y^2) and
   int_0^inf dt t^(n - 1) e^(-t/4 - z^2/t) = 2 (2 z)^n K_n(z), ::

       int_0^inf dt t^k p(t, v | u) = (3 v (u v)^(1/2) / pi) e^((v+u)/2) int_0^1 dy e^(-z) h_k(z),
       z^2 = v^2 - v u + u^2 + 3 v u y^2,
       h_0 = (z^-2 + z^-3) / 2,  h_1 = 1 / z,  h_2 = 2,  h_3 = 4 (1 + z)           (timemoments)

   (K_{k-3/2} is elementary).  k = 0 is v G_g(v, u) of eq. (kernel3), so (joint) integrates over
   t to the paper's kernel: this is the check that the time-domain law and its units are right
   (eq. (GgP)).  Each y-integral is made stable exactly as in ``kernel.py`` (y -> z -> tau); the
   result is ::

       int dt t^k p = (2 sqrt(3) v / pi) exp[-(3/4)(v - u)^2 / ((v + u)/2 + z0)]
                      * int_0^tau1 dtau e^(-z0 tau^2) z h_k(z) / (2 + tau^2)^(1/2),
       z = z0 (1 + tau^2).
"""

import numpy as np
from scipy import special

from ..kernel import TAIL, TIME_MOMENT_TAU_NODES

__all__ = [
    "free_first_passage_density",
    "log_joint_density",
    "joint_density",
    "return_time_moment",
]


SQRT3 = np.sqrt(3.0)


# Gauss-Legendre on [0, 1] for the tau integral of (timemoments)
_TAU_NODES, _TAU_WEIGHTS = np.polynomial.legendre.leggauss(TIME_MOMENT_TAU_NODES)


_TAU_NODES, _TAU_WEIGHTS = 0.5 * (_TAU_NODES + 1.0), 0.5 * _TAU_WEIGHTS


MOMENT_POWERS = range(4)  # k of (timemoments)


def free_first_passage_density(t, v, u):
    """McKean's first-passage law without gravity, p_0(t, v | u), in the paper's units.

    Item 1 of the module's account (McKean's eqs. (5), (6), with the noise of eq. (eqmo)).

    Parameters
    ----------
    t : array_like
        Flight times.
    v : array_like
        Return speeds (the incoming velocity is -v).
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        p_0(t, v | u), broadcast; 0 where t, v or u is not positive.
    """
    t, v, u = (np.asarray(a, dtype=float) for a in (t, v, u))
    with np.errstate(divide="ignore", invalid="ignore"):
        value = (
            SQRT3
            * v
            / (2.0 * np.pi * t * t)
            * np.exp(-(v * v - u * v + u * u) / t)
            * special.erf(np.sqrt(3.0 * u * v / t))
        )
    return np.where((t > 0.0) & (v > 0.0) & (u > 0.0), value, 0.0)


def log_joint_density(t, v, u):
    """ln p(t, v | u) of eq. (joint): McKean's law with gravity through eqs. (0g), (GgP).

    Parameters
    ----------
    t : array_like
        Flight times.
    v : array_like
        Return speeds (the incoming velocity is -v).
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        ln p(t, v | u), broadcast; -inf where t, v or u is not positive.
    """
    t, v, u = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (t, v, u)))
    valid = (t > 0.0) & (v > 0.0) & (u > 0.0)
    t, v, u = (np.where(valid, a, 1.0) for a in (t, v, u))
    exponent = -((t - u - v) ** 2 + 3.0 * (v - u) ** 2) / (4.0 * t)
    with np.errstate(divide="ignore"):
        value = (
            np.log(SQRT3 * v / (2.0 * np.pi))
            - 2.0 * np.log(t)
            + exponent
            + np.log(special.erf(np.sqrt(3.0 * u * v / t)))
        )
    return np.where(valid, value, -np.inf)


def joint_density(t, v, u):
    """The joint density p(t, v | u) of eq. (joint): flight time and return speed.

    p(t, v | u) dt dv is the probability that a ball leaving the floor with speed u first
    comes back after a time in [t, t + dt] with speed in [v, v + dv].

    Parameters
    ----------
    t : array_like
        Flight times.
    v : array_like
        Return speeds (the incoming velocity is -v).
    u : array_like
        Outgoing speeds.

    Returns
    -------
    numpy.ndarray
        p(t, v | u), broadcast; 0 where t, v or u is not positive.

    Examples
    --------
    Gravity multiplies the free law by exp[(v + u)/2 - t/4], eq. (0g):

    >>> import numpy as np
    >>> from bouncing_ball.flight_time import free_first_passage_density, joint_density
    >>> ratio = joint_density(2.0, 1.0, 1.0) / free_first_passage_density(2.0, 1.0, 1.0)
    >>> bool(np.isclose(ratio, np.exp(1.0 - 0.5)))
    True
    """
    return np.exp(log_joint_density(t, v, u))


def return_time_moment(v, u, k):
    """The time moments int_0^inf dt t^k p(t, v | u) of eq. (timemoments), k = 0..3.

    k = 0 is v G_g(v, u) of eq. (kernel3): the return-speed law (eq. (GgP)).

    Parameters
    ----------
    v : array_like
        Return speeds.
    u : array_like
        Outgoing speeds.
    k : int
        The power of t, 0 to 3.

    Returns
    -------
    numpy.ndarray
        Broadcast over v and u; 0 where v or u is not positive.

    Raises
    ------
    ValueError
        If k is not 0, 1, 2 or 3.

    Examples
    --------
    k = 0 integrates over v to 1 (eq. (normG)), k = 1 to E[T | u] (eq. (meanT)):

    >>> from bouncing_ball.flight_time import (
    ...     mean_flight_time_given_speed, return_time_moment, trapezoid_nodes)
    >>> v, weights = trapezoid_nodes(1e-9, 160.0, 0.15)
    >>> print(round(weights @ return_time_moment(v, 1.0, 0), 10))
    1.0
    >>> mean = weights @ return_time_moment(v, 1.0, 1)
    >>> print(round(mean, 8), round(float(mean_flight_time_given_speed(1.0)), 8))
    3.15247858 3.15247858
    """
    if k not in MOMENT_POWERS:
        raise ValueError(f"time power k must be one of {list(MOMENT_POWERS)}, got {k}")
    v, u = np.broadcast_arrays(np.asarray(v, dtype=float), np.asarray(u, dtype=float))
    valid = (v > 0.0) & (u > 0.0)
    v, u = np.where(valid, v, 1.0)[..., None], np.where(valid, u, 1.0)[..., None]
    difference = v - u
    z0 = np.sqrt(difference * difference + v * u)
    tau1 = np.sqrt(3.0 * v * u / ((v + u + z0) * z0))
    upper = np.minimum(tau1, TAIL / np.sqrt(z0))
    tau2 = (upper * _TAU_NODES) ** 2
    z = z0 * (1.0 + tau2)
    shape = {0: (1.0 + z) / (2.0 * z * z), 1: 1.0, 2: 2.0 * z, 3: 4.0 * z * (1.0 + z)}[k]
    integrand = np.exp(-z0 * tau2) * shape / np.sqrt(2.0 + tau2)
    gauss = np.exp(-0.75 * difference * difference / (0.5 * (v + u) + z0))
    value = (2.0 * SQRT3 / np.pi) * (v * gauss * upper)[..., 0] * (integrand @ _TAU_WEIGHTS)
    return np.where(valid, value, 0.0)
