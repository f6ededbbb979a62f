"""The equilibrium flight-time density nu(T) of eq. (rate), for any r.

Collisions with outgoing speed in du come at the rate u P(0, u) du (eq. (collrate)), so flights
of duration in dT come at the rate ::

    nu(T) = int_0^inf du u P(0, u) f(T | u)                                        (rate)

per unit time, for every r.  int T nu(T) dT = M_2 + M_2 / r = 1 by eqs. (inteq) and
(normalization) (the time between collisions fills the time), and int nu dT = I = M_1.
Above r_c, rho(T) = nu(T) / I is the distribution of the flight time per collision, with mean
1 / I.  Below r_c (beta >= 2), I is infinite: almost all flights are infinitely short and
rho(T) = 0 for every T > 0, but nu(T) is finite for T > 0 and T nu(T) is a probability
density, that of the duration of the flight in progress at a random instant (for r > r_c it
is T rho(T) / <T>), with mean int T^2 nu dT (= <T^2> / <T> above r_c).

nu(T) is the quadrature of eq. (rate) over the solver's nodes, its short-flight law of eq.
(short) (``asymptotic_forms``) below SHORT_FLIGHT_TIME, and 0 beyond
``underflow_flight_time(r)``.
"""

import numpy as np

from ..asymptotics import large_speed_decay_rate, large_speed_exponent
from ..solver import coordinate_of_speed, speed_of_coordinate
from .asymptotic_forms import (
    _short_law,
    short_time_constant,
    shortest_flight_time,
    small_speed_amplitude,
    underflow_flight_time,
)
from .density_given_speed import flight_time_density

__all__ = [
    "flight_rate_density",
    "flight_rate_in_regimes",
    "SHORT_FLIGHT_TIME",
]


RATE_STEP = 0.125  # trapezoidal step in s = ln u + u^(1/2) for nu(T): e^-39 of the rule's error


#: Below this flight time nu(T) is its short-flight law A C_beta T^(-beta/2), eq. (short),
#: whose relative correction (c1 T^(1/2), abs(c1) ~ 0.1 at r = 1/2 and 1/3) is below 1e-15
#: there; above it nu(T) is the quadrature of eq. (rate), which needs P(0, u) down to
#: 1e-4 T^(1/2) (1e-19 here).
SHORT_FLIGHT_TIME = 1e-30


RATE_CHUNK_PAIRS = 2**15  # (T, u) pairs of nu(T) evaluated at once: ~13 MB a temporary


def _outgoing_lattice(solution, first, last, step):
    """Nodes u_k = u(k step), s = ln u + u^(1/2), for k = first..last, and the collision rate
    w_k u_k P(0, u_k) each carries: P from the solver's Nystrom formula up to its highest node
    u_max, continued above by its large-speed form (eq. (asym3))
    P(0, u_max) (u / u_max)^-m e^(-q (u - u_max)).  The lattice is fixed (k step, whatever
    the times asked for), so that each T is integrated on nodes of its own."""
    r, u_max = solution.restitution, solution.speeds[-1]
    u = speed_of_coordinate(step * np.arange(first, last + 1))
    inside = u <= u_max
    density = np.empty(u.size)
    density[inside] = solution.outgoing_speed_density(u[inside])
    q, m = large_speed_decay_rate(r), large_speed_exponent(r)
    beyond = u[~inside] / u_max
    density[~inside] = solution.density[-1] * beyond**-m * np.exp(-q * u_max * (beyond - 1.0))
    return u, step * u / (1.0 + 0.5 * np.sqrt(u)) * u * density


def _rate_windows(solution, times, step):
    """The lattice indices [first, last] of ``_outgoing_lattice`` that each T integrates over:
    from u_lo = min(u_0, 1e-4 T^(1/2)) (u_0 the solver's lowest node) to T/2 + 10 T^(1/2),
    beyond which f(T | u) < e^-75 of its peak."""
    lowest = np.minimum(solution.speeds[0], 1e-4 * np.sqrt(times))
    highest = 0.5 * times + 10.0 * np.sqrt(times)
    first = np.floor(coordinate_of_speed(lowest) / step).astype(np.int64)
    last = np.ceil(coordinate_of_speed(highest) / step).astype(np.int64)
    return first, last


def _direct_flight_rate_density(solution, times, step):
    """nu(T) of eq. (rate) by the trapezoidal rule of ``flight_rate_density``, each T on its own
    window of the lattice (``_rate_windows``), in chunks of at most ``RATE_CHUNK_PAIRS``
    (T, u) pairs (a T whose window is longer is a chunk of its own)."""
    times = np.asarray(times, dtype=float)
    first, last = _rate_windows(solution, times, step)
    u, rate = _outgoing_lattice(solution, int(first.min()), int(last.max()), step)
    start = first - first.min()  # each window's first node in u
    sizes = last - first + 1
    # the rule below u_lo: sum_k>=1 of rate_0 (u_-k / u_lo)^(5/2 - beta) (1 + u_lo^(1/2) / 2)
    decay = 2.5 - solution.small_speed_exponent
    tail = rate[start] * (1.0 + 0.5 * np.sqrt(u[start])) / np.expm1(decay * step)
    result = np.empty(times.size)
    chunk_ends = np.cumsum(sizes) // RATE_CHUNK_PAIRS
    for chunk in np.unique(chunk_ends):
        rows = np.flatnonzero(chunk_ends == chunk)
        offsets = np.concatenate(([0], np.cumsum(sizes[rows])))
        row_of_pair = np.repeat(rows, sizes[rows])
        column = start[row_of_pair] + np.arange(offsets[-1]) - np.repeat(offsets[:-1], sizes[rows])
        f = flight_time_density(times[row_of_pair], u[column])
        result[rows] = (
            np.add.reduceat(f * rate[column], offsets[:-1]) + tail[rows] * f[offsets[:-1]]
        )
    return result


def flight_rate_in_regimes(times, direct, short_amplitude, beta, restitution):
    """nu(T) of eq. (rate) from its three regimes, each T on its own.

    Eq. (short) below ``SHORT_FLIGHT_TIME``, ``direct`` up to ``underflow_flight_time``, 0
    beyond it (and wherever nu is below the smallest normal double).  The one home of the
    domain of nu(T), for ``flight_rate_density`` and ``equilibrium.ExactEquilibrium``.

    Parameters
    ----------
    times : array_like
        Flight times, ``shortest_flight_time(short_amplitude, beta) <= T``.
    direct : callable
        nu of a 1-d array of T in [SHORT_FLIGHT_TIME, underflow_flight_time], by quadrature
        of eq. (rate).
    short_amplitude : float
        A C_beta of eq. (short).
    beta : float
        The small-speed exponent of eq. (asym2).
    restitution : float
        r (for ``underflow_flight_time``).

    Returns
    -------
    numpy.ndarray
        nu(T), shaped like ``times``; finite.

    Raises
    ------
    ValueError
        If a T is not positive or lies below ``shortest_flight_time``, where nu(T) exceeds the
        largest double.
    """
    times = np.asarray(times, dtype=float)
    shortest = shortest_flight_time(short_amplitude, beta)
    bad = ~(times >= max(shortest, np.finfo(float).smallest_subnormal))
    if bad.any():
        raise ValueError(
            f"times: nu(T) is finite for T >= {shortest:.3g} (T > 0; below, A C_beta "
            f"T^(-beta/2) of eq. (short) exceeds the largest double), got {times[bad].flat[0]!r}"
        )
    result = np.zeros(times.shape)
    short = times < SHORT_FLIGHT_TIME
    result[short] = _short_law(short_amplitude, beta, times[short])
    middle = ~short & (times <= underflow_flight_time(restitution))
    if middle.any():
        result[middle] = direct(times[middle])
    return np.where(result >= np.finfo(float).tiny, result, 0.0)


def flight_rate_density(solution, times, step=RATE_STEP):
    """nu(T) of eq. (rate): flights of duration in dT per unit time, for any r.

    nu(T) = int_0^inf du u P(0, u) f(T | u), finite for T > 0 (also below r_c), in three
    regimes (``flight_rate_in_regimes``), each T on its own (a value never depends on the
    others asked for with it):

    - ``SHORT_FLIGHT_TIME`` <= T <= ``underflow_flight_time(r)``: the u-integral is a
      trapezoidal rule in s = ln u + u^(1/2) of step ``step`` on the fixed lattice s = k step,
      finer than the solver's (f(T | u) falls like exp(-3 u^2 / 4T) for u >> T^(1/2), which the
      solver's step 0.25 resolves only to ~1e-8), with P(0, u) from the solver's Nystrom
      formula, from u_lo = min(u_0, 1e-4 T^(1/2)) to T/2 + 10 T^(1/2).  Below u_lo the rule is
      summed in closed form with f(T | u) = f(T | u_lo) (u / u_lo)^(1/2) (relative error
      O(u_lo / T^(1/2))) and P(0, u) its power law.  Above the solver's highest node u_max,
      P(0, u) is continued by its large-speed form (long flights come from fast balls where
      q(r) < 3/4, i.e. r > 0.618); where that matters (T >~ u_max / (1/2 - 2q/3)) nu(T) is
      only as good as that form (and below e^-690 of its peak).  Accurate to ~1e-9 relative
      with the solver's P(0, u).
    - T < ``SHORT_FLIGHT_TIME``: eq. (short), A C_beta T^(-beta/2), its relative correction
      O(T^(1/2)) below 1e-14 (A read off the solver's lowest node, ``small_speed_amplitude``).
    - T > ``underflow_flight_time(r)``: 0 (nu decays like e^(-kappa T), eqs. (long1),
      (long2), and is below the smallest normal double there); so is any nu below that double.

    Parameters
    ----------
    solution : solver.OutgoingSpeedSolution
        The solver's P(0, u), eq. (inteq).
    times : array_like
        Flight times, T >= ``shortest_flight_time`` (> 0; below it nu(T) exceeds the largest
        double: 0 unless beta > 1.9, i.e. r < 0.2; 2.4e-258 at r = 0.02).
    step : float
        The rule's step in s.

    Returns
    -------
    numpy.ndarray
        nu(T), shaped like ``times``; finite.

    Raises
    ------
    ValueError
        If a T is not positive or lies below ``shortest_flight_time``.
    """
    beta = solution.small_speed_exponent
    return flight_rate_in_regimes(
        times,
        lambda t: _direct_flight_rate_density(solution, t, step),
        small_speed_amplitude(solution) * short_time_constant(beta),
        beta,
        solution.restitution,
    )
