"""The asymptotic forms of nu(T): short flights, eq. (short), and long flights, eqs. (long1), (long2).

Short flights: a ball leaving with u << 1 hardly feels gravity, f(T | u) = u^-2 F(T / u^2)
with F McKean's law, and P(0, u) ~ A u^-beta (eq. (asym1)), so ::

    nu(T) ~ A C_beta T^(-beta/2),   T -> 0,   C_beta = (1/2) E_0[T^(beta/2 - 1) | u = 1]
          = (3 Gamma((5 - beta)/2) / (2 pi^(3/2))) int_0^inf dv v^(3/2) z0^(beta - 5)
            2F1((5 - beta)/2, 1/2; 3/2; -3 v / z0^2),   z0^2 = v^2 - v + 1,       (short)

with relative corrections O(T^(1/2)).  The divergence T^(-beta/2) is integrable exactly when
beta < 2, i.e. r > r_c.

Long flights: at fixed u, f(T | u) ~ (sqrt(3) / (8 sqrt(pi))) T^(-1/2) e^(-3T/16)
e^(3u/4) erf((3u)^(1/2) / 2).  With P(0, u) ~ B u^-m e^(-q u) (eqs. (asym3)-(asym6)) the
u-integral converges where q > 3/4, i.e. r < (sqrt 5 - 1) / 2 = 0.618, and then ::

    nu(T) ~ K T^(-1/2) e^(-3T/16),
    K = (sqrt(3) / (8 sqrt(pi))) int du u P(0, u) e^(3u/4) erf((3u)^(1/2) / 2).   (long1)

For r > 0.618 (q < 3/4) long flights come from fast balls: a saddle at u* = c T,
c = 1/2 - 2q/3, gives ::

    nu(T) ~ (B / 4) (2 - 4q/3) c^(1-m) T^(1-m) e^(-(q/2 - q^2/3) T).                (long2)

Both hold with relative corrections O(1/T) (near r = 0.618 they set in only at
T >> (q - 3/4)^-2); B is read off the solver at its highest node (approximate).
"""

import functools

import numpy as np
from scipy import integrate, special

from ..asymptotics import large_speed_decay_rate, large_speed_exponent
from .equilibrium_moments import _outgoing_weights
from .joint_law import SQRT3

__all__ = [
    "GOLDEN_RESTITUTION",
    "shortest_flight_time",
    "underflow_flight_time",
    "short_time_constant",
    "small_speed_amplitude",
    "short_flight_rate_density",
    "large_speed_amplitude",
    "long_flight_rate_density",
    "long_time_decay_rate",
]


#: (sqrt 5 - 1) / 2 = 0.618...: q(r) = 3/4 (eq. (asym4)), where the long-flight law of
#: eq. (long1) gives way to that of eq. (long2).
GOLDEN_RESTITUTION = 0.5 * (np.sqrt(5.0) - 1.0)


#: nu(T) is 0 beyond UNDERFLOW_MARGIN ln(1/tiny) / kappa (``underflow_flight_time``): twice the
#: flight time where e^(-kappa T) reaches the smallest normal double, which leaves the
#: prefactors of eqs. (long1), (long2) (at most ~e^20 over the solver's range of r) e^-700.
UNDERFLOW_MARGIN = 2.0


@functools.lru_cache(maxsize=256)  # a pure function of beta, asked for at each call of nu(T)
def short_time_constant(beta):
    """The constant C_beta of the short-flight law, eq. (short).

    C_beta = int_0^inf du u^(1 - beta) f_0(1 | u) = (1/2) E_0[T^(beta/2 - 1) | u = 1], by
    quadrature of its hypergeometric form.

    Parameters
    ----------
    beta : float
        The small-speed exponent of eq. (asym2), below 5/2.

    Returns
    -------
    float
    """
    a = 0.5 * (5.0 - beta)

    def integrand(v):
        z0_squared = v * v - v + 1.0
        return v**1.5 * z0_squared ** (-a) * special.hyp2f1(a, 0.5, 1.5, -3.0 * v / z0_squared)

    head, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-12, limit=200)
    tail, _ = integrate.quad(integrand, 1.0, np.inf, epsabs=0.0, epsrel=1e-12, limit=200)
    return 3.0 * special.gamma(a) / (2.0 * np.pi**1.5) * (head + tail)


def small_speed_amplitude(solution):
    """The amplitude A of P(0, u) ~ A u^-beta at small u, eq. (asym1).

    Read off the solver's lowest node (where that law is built in).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
    """
    return solution.density[0] * solution.speeds[0] ** solution.small_speed_exponent


def short_flight_rate_density(solution, times):
    """The short-flight law nu(T) ~ A C_beta T^(-beta/2) for T -> 0, eq. (short).

    Relative corrections are O(T^(1/2)).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    numpy.ndarray
    """
    beta = solution.small_speed_exponent
    amplitude = small_speed_amplitude(solution) * short_time_constant(beta)
    return _short_law(amplitude, beta, np.asarray(times, dtype=float))


def _short_law(amplitude, beta, times):
    """amplitude T^(-beta/2) of eq. (short), as (amplitude^(1/2) T^(-beta/4))^2: finite
    wherever the product is (T^(-beta/2) alone overflows first where amplitude < 1), to a few
    ulp."""
    return (np.sqrt(amplitude) * times ** (-0.25 * beta)) ** 2


def large_speed_amplitude(solution):
    """The amplitude B of P(0, u) ~ B u^-m e^(-q u) at large u, eq. (asym3).

    Read off the solver's highest node (approximate).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).

    Returns
    -------
    float
    """
    r, u = solution.restitution, solution.speeds[-1]
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    return solution.density[-1] * u**m * np.exp(q * u)


def long_flight_rate_density(solution, times):
    """The long-flight law of nu(T) for T -> infinity, eqs. (long1) and (long2).

    Eq. (long1), K T^(-1/2) e^(-3T/16), where q(r) > 3/4 (r < 0.618); eq. (long2) above.
    Relative corrections are O(1/T).

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times T > 0.

    Returns
    -------
    numpy.ndarray
    """
    times = np.asarray(times, dtype=float)
    r = solution.restitution
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    if q > 0.75:
        u, rate = _outgoing_weights(solution)
        weight = np.exp(0.75 * u) * special.erf(0.5 * np.sqrt(3.0 * u))
        # above u_max: P = B u^-m e^(-q u), erf = 1 (to e^-(3 u_max / 4)), an incomplete Gamma
        a, x = 2.0 - m, (q - 0.75) * u[-1]
        beyond = large_speed_amplitude(solution) * special.gammaincc(a, x) * special.gamma(a)
        beyond /= (q - 0.75) ** a
        constant = SQRT3 / (8.0 * np.sqrt(np.pi)) * (float(rate @ weight) + beyond)
        return constant * times**-0.5 * np.exp(-3.0 * times / 16.0)
    c = 0.5 - 2.0 * q / 3.0
    amplitude = 0.25 * large_speed_amplitude(solution) * (2.0 - 4.0 * q / 3.0) * c ** (1.0 - m)
    return amplitude * times ** (1.0 - m) * np.exp(-(0.5 * q - q * q / 3.0) * times)


def long_time_decay_rate(restitution):
    """The decay rate kappa of nu(T) ~ e^(-kappa T) at long flight times.

    Parameters
    ----------
    restitution : float
        r, in (0, 1).

    Returns
    -------
    float
        3/16 (eq. (long1)) where q(r) > 3/4, q/2 - q^2/3 (eq. (long2)) where q(r) < 3/4
        (r > ``GOLDEN_RESTITUTION`` = 0.618).

    Examples
    --------
    >>> from bouncing_ball.flight_time import long_time_decay_rate
    >>> print(long_time_decay_rate(0.5), round(long_time_decay_rate(0.8), 10))
    0.1875 0.1360544218
    """
    q = large_speed_decay_rate(restitution)
    return 3.0 / 16.0 if q > 0.75 else 0.5 * q - q * q / 3.0


def underflow_flight_time(restitution):
    """The flight time beyond which nu(T) is below the smallest normal double, and is 0.

    ``UNDERFLOW_MARGIN`` ln(1/tiny) / kappa, with kappa of ``long_time_decay_rate``: nu(T)
    ~ K T^a e^(-kappa T), eqs. (long1), (long2).

    Parameters
    ----------
    restitution : float
        r, in (0, 1).

    Returns
    -------
    float

    Examples
    --------
    >>> from bouncing_ball.flight_time import underflow_flight_time
    >>> print(round(underflow_flight_time(0.5)))
    7556
    """
    return UNDERFLOW_MARGIN * -np.log(np.finfo(float).tiny) / long_time_decay_rate(restitution)


def shortest_flight_time(amplitude, beta):
    """The flight time below which amplitude T^(-beta/2) exceeds the largest double.

    nu(T) ~ A C_beta T^(-beta/2) at short T (eq. (short)): below this T it is not a float.

    Parameters
    ----------
    amplitude : float
        A C_beta (or A C_beta / I for rho(T)), > 0.
    beta : float
        The small-speed exponent of eq. (asym2), >= 0.

    Returns
    -------
    float
        0 where even the smallest double gives a finite value.

    Examples
    --------
    >>> from bouncing_ball.flight_time import shortest_flight_time
    >>> print(shortest_flight_time(1.0, 1.0), f"{shortest_flight_time(1.0, 2.4):.3g}")
    0.0 1.32e-257
    """
    if beta <= 0.0:
        return 0.0
    exponent = 2.0 / beta * (np.log(amplitude) - np.log(np.finfo(float).max))
    return float(np.exp(exponent)) if exponent > np.log(np.finfo(float).smallest_subnormal) else 0.0
