"""The collision rate of eq. (collrate) and the moments of the equilibrium flight-time density nu(T).

Collisions with outgoing speed in du come at the rate u P(0, u) du (eq. (collrate)); the
moments of nu(T) of eq. (rate) (``equilibrium_density``) are sums over the solver's nodes of
that rate times the conditional moments given u (``conditional_moments``), the solver's rule
continued below its lowest node by the power law of P(0, u).  int nu dT = I = M_1 (the collision
rate, infinite below r_c) and int T nu(T) dT = M_2 + M_2 / r = 1 by eqs. (inteq) and
(normalization) (the time between collisions fills the time).
"""

import numpy as np

from .conditional_moments import (
    conditional_moment,
    flight_time_second_moment_given_speed,
    mean_flight_time_given_speed,
)

__all__ = [
    "collision_rate",
    "flight_rate_moment",
    "mean_flight_time",
    "flight_time_second_moment",
    "time_weighted_mean_flight_time",
]


def _outgoing_weights(solution):
    """u_j P(0, u_j) w_j: the collision rate carried by each node of the solver."""
    u = solution.speeds
    return u, solution.quadrature_weights * u * solution.density


def _lower_tail_factor(solution, exponent):
    """Sum over the solver's rule continued below its lowest node u_0 of
    w u P(0, u) (u / u_0)^exponent, divided by P(0, u_0); P is the power law u^-beta there (as in
    the solver), du/ds = u."""
    decay = 2.0 - solution.small_speed_exponent + exponent
    if decay <= 0.0:
        return np.inf
    return solution.step * solution.speeds[0] ** 2 / np.expm1(decay * solution.step)


def collision_rate(solution):
    """The collision rate I = M_1 of eq. (collrate).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
        I; inf below r_c (eq. (rc)).
    """
    return solution.moment(1)


def flight_rate_moment(solution, k):
    """int_0^inf T^k nu(T) dT = int du u P(0, u) E[T^k | u], k = 0..3, for any r.

    k = 0 is I (inf below r_c); k = 1 is 1 for every r (a check); k = 2 is the mean duration of
    the flight in progress at a random instant.  E[T^k | u] from eqs. (meanT), (meanT2) for
    k = 1, 2, by quadrature (``conditional_moment``) for k = 3.  Below u_0,
    E[T^k | u] ~ u^(1/2) (k >= 1).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    k : int
        The power of T, 0 to 3.

    Returns
    -------
    float
    """
    if k == 0:
        return collision_rate(solution)
    u, rate = _outgoing_weights(solution)
    if k == 1:
        moments = mean_flight_time_given_speed(u)
    elif k == 2:
        moments = flight_time_second_moment_given_speed(u)
    else:
        moments = np.array([conditional_moment(x, k, 0) for x in u])
    tail = _lower_tail_factor(solution, 0.5) * solution.density[0] * moments[0]
    return float(rate @ moments + tail)


def mean_flight_time(solution):
    """The mean flight time per collision, <T> = int T nu dT / I, eq. (rate).

    By the momentum balance it is 1 / I, eqs. (inteq), (normalization).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
        <T>; 0 below r_c (I = inf).

    Examples
    --------
    At r = 1/2, I = 1/3 (eq. (xandDeltax)):

    >>> from bouncing_ball import Equilibrium
    >>> from bouncing_ball.flight_time import mean_flight_time
    >>> print(round(mean_flight_time(Equilibrium(0.5).solution), 8))
    3.0
    """
    rate = collision_rate(solution)
    return flight_rate_moment(solution, 1) / rate if np.isfinite(rate) else 0.0


def flight_time_second_moment(solution):
    """The second moment of the flight time per collision, <T^2> = int T^2 nu dT / I.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
        <T^2>; 0 below r_c (I = inf).
    """
    rate = collision_rate(solution)
    return flight_rate_moment(solution, 2) / rate if np.isfinite(rate) else 0.0


def time_weighted_mean_flight_time(solution):
    """The mean duration of the flight in progress at a random instant, int T^2 nu dT.

    Defined for any r; <T^2> / <T> above r_c.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
    """
    return flight_rate_moment(solution, 2)
