"""Flight times between collisions: McKean's first-passage law with gravity, for any r.

Units of the paper (g = Lambda = 1): dx = v dt, dv = -dt + xi dt, <xi(t) xi(t')> = 2 delta(t - t').
A ball leaves the floor with speed u > 0; p(t, v | u) dt dv is the probability that it first
comes back after a flight time in [t, t + dt] with speed (incoming velocity -v) in [v, v + dv].
The modules, in the order they build on each other:

- ``joint_law``: p(t, v | u) from McKean's law and eq. (0g), eq. (joint), and its time moments
  at fixed v in closed form, eq. (timemoments);
- ``conditional_moments``: E[T^k v^m | u], and E[T | u], E[T^2 | u] in closed form from the
  Laplace transform of T, eqs. (meanT), (meanT2);
- ``density_given_speed``: the flight-time density given u, f(t | u) = int dv p(t, v | u);
- ``equilibrium_moments``: the collision rate of eq. (collrate) and the moments of nu(T);
- ``asymptotic_forms``: nu(T) at short flights, eq. (short), and long ones, eqs. (long1),
  (long2);
- ``equilibrium_density``: the equilibrium flight-time density nu(T) = int du u P(0, u) f(T | u),
  eq. (rate);
- ``tables``: the pipeline's tables and bin averages (nu(T), the return-speed law in bins).

Every name is importable from ``bouncing_ball.flight_time`` itself.

Examples
--------
E[T | u] of eq. (meanT) obeys Ito's identity E[T | u] = u + E[v | u] (``conditional_moments``):

>>> from bouncing_ball.flight_time import conditional_moment, mean_flight_time_given_speed
>>> u = 1.5
>>> print(round(mean_flight_time_given_speed(u) - u - conditional_moment(u, 0, 1), 10))
0.0
"""

from .asymptotic_forms import (
    GOLDEN_RESTITUTION,
    UNDERFLOW_MARGIN,
    _short_law,
    large_speed_amplitude,
    long_flight_rate_density,
    long_time_decay_rate,
    short_flight_rate_density,
    short_time_constant,
    shortest_flight_time,
    small_speed_amplitude,
    underflow_flight_time,
)
from .conditional_moments import (
    _SECH_SERIES,
    _SECH_SERIES_DERIVATIVE,
    SECH_SERIES_FROM,
    SECH_SERIES_TERMS,
    SMALLEST_RATIO,
    SPEED_STEP,
    _erfcx_minus_one,
    _flight_time_ingredients,
    _return_speed_nodes,
    _sech_bessel_argument,
    _sech_bessel_series,
    _sech_series_bracket,
    conditional_moment,
    flight_time_second_moment_given_speed,
    mean_flight_time_given_speed,
    sech_bessel_moment,
    sech_bessel_moment_derivative,
    trapezoid_nodes,
)
from .density_given_speed import (
    _SPEED_NODES,
    _SPEED_WEIGHTS,
    EXPONENT_CUT,
    TIME_STEP,
    WINDOW,
    _flight_time_window,
    _log_speed_integral,
    flight_time_density,
    flight_time_nodes,
    free_flight_time_density,
    log_flight_time_density,
)
from .equilibrium_density import (
    RATE_CHUNK_PAIRS,
    RATE_STEP,
    SHORT_FLIGHT_TIME,
    _direct_flight_rate_density,
    _outgoing_lattice,
    _rate_windows,
    flight_rate_density,
    flight_rate_in_regimes,
)
from .equilibrium_moments import (
    _lower_tail_factor,
    _outgoing_weights,
    collision_rate,
    flight_rate_moment,
    flight_time_second_moment,
    mean_flight_time,
    time_weighted_mean_flight_time,
)
from .joint_law import (
    _TAU_NODES,
    _TAU_WEIGHTS,
    MOMENT_POWERS,
    SQRT3,
    free_first_passage_density,
    joint_density,
    log_joint_density,
    return_time_moment,
)
from .tables import (
    _BIN_NODES,
    _BIN_WEIGHTS,
    _LAW_PANEL_EDGES,
    _LAW_PANEL_VANDERMONDE,
    _LAW_PANEL_X,
    FLIGHT_TIME_TABLE_RANGE,
    LAW_PANEL_NODES,
    _direct_return_speed_bin_law,
    _law_panel_edges,
    _log_gauss,
    _speed_sub_bins,
    flight_rate_bin_integrals,
    flight_time_bin_average,
    flight_time_summary,
    flight_time_table,
    return_speed_bin_law,
    return_speed_bin_probabilities,
    return_speed_table,
)

__all__ = [
    "GOLDEN_RESTITUTION",
    "free_first_passage_density",
    "log_joint_density",
    "joint_density",
    "return_time_moment",
    "conditional_moment",
    "sech_bessel_moment",
    "sech_bessel_moment_derivative",
    "mean_flight_time_given_speed",
    "flight_time_second_moment_given_speed",
    "log_flight_time_density",
    "flight_time_density",
    "free_flight_time_density",
    "flight_rate_density",
    "flight_rate_in_regimes",
    "SHORT_FLIGHT_TIME",
    "FLIGHT_TIME_TABLE_RANGE",
    "shortest_flight_time",
    "underflow_flight_time",
    "collision_rate",
    "flight_rate_moment",
    "mean_flight_time",
    "flight_time_second_moment",
    "time_weighted_mean_flight_time",
    "short_time_constant",
    "small_speed_amplitude",
    "short_flight_rate_density",
    "large_speed_amplitude",
    "long_flight_rate_density",
    "long_time_decay_rate",
    "flight_time_summary",
    "flight_time_table",
    "return_speed_table",
    "flight_rate_bin_integrals",
    "flight_time_bin_average",
    "return_speed_bin_law",
    "return_speed_bin_probabilities",
]
