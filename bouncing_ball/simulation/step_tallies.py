"""What the shard loop (``loop``) records at each step, compiled: the bin of a value, the
tallies of the path over a step (P(x), <v^2>_x, P(x, v) by the Brownian bridge between the
step's ends), the floor stratum's step end, and the bits of the loop's ``parts``."""

import math

from ..free_flight import (
    bridge_sample,
    bridge_speed_squared_given_position,
    cubic_value,
    level_time,
    level_time_one_step,
    monotone_piece_end,
    piece_inverse,
    quintic_antiderivative_value,
    slope_zeros,
    speed_squared_coefficients,
)
from ..jit import njit
from ..pcg64 import standard_normal

__all__ = [
    "MEAN_PATH_INTEGRALS",
    "POSITION",
    "JOINT",
    "FLIGHTS",
    "CONTROL_VARIATES",
    "EVERY_TALLY",
    "FLOOR_STRATUM_HEIGHT",
    "floor_stratum_end",
]


@njit(cache=True)
def _bin_index(value, log_lo, per_ln, n, edges):
    """Index of ``value`` in LogBins (0 underflow, n + 1 overflow)."""
    if value < edges[0]:
        return 0
    if value >= edges[n]:
        return n + 1
    return _log_bin_index(value, math.log(value), log_lo, per_ln, n, edges)


@njit(cache=True, inline="always")
def _log_bin_index(value, log_value, log_lo, per_ln, n, edges):
    """``_bin_index`` of ``value`` given its logarithm ``log_value``, or any estimate of it:
    the estimate only picks the bin the walk over the edges starts from, and the edges decide
    (so a collision's two speeds, v_out = r v_in, share one logarithm)."""
    if value < edges[0]:
        return 0
    if value >= edges[n]:
        return n + 1
    k = int((log_value - log_lo) * per_ln)
    if k < 0:
        k = 0
    if k > n - 1:
        k = n - 1
    # correct a last-digit disagreement between log and the stored edges
    while k > 0 and value < edges[k]:
        k -= 1
    while k < n - 1 and value >= edges[k + 1]:
        k += 1
    return k + 1


@njit(cache=True)
def _linear_bin_index(value, lo, per_unit, n, edges):
    """Index of ``value`` in LinearBins (0 underflow, n + 1 overflow)."""
    if value < edges[0]:
        return 0
    if value >= edges[n]:
        return n + 1
    k = int((value - lo) * per_unit)
    if k < 0:
        k = 0
    if k > n - 1:
        k = n - 1
    while k > 0 and value < edges[k]:
        k -= 1
    while k < n - 1 and value >= edges[k + 1]:
        k += 1
    return k + 1


@njit(cache=True, inline="always")
def _walked_bin_index(value, k, bin_lower, bin_upper):
    """Index of ``value`` in the x bins, walking from bin ``k`` (no logarithm): the same bin
    as ``_bin_index``, whose answer the edges decide too.  ``bin_lower`` and ``bin_upper``
    are the ends of each bin, -inf and inf those of the under- and overflow bins, so the
    walk stops for a finite value (a NaN stays in bin ``k``; +inf, which a finite step
    cannot draw, would walk off the end)."""
    while value < bin_lower[k]:
        k -= 1
    while value >= bin_upper[k]:
        k += 1
    return k


@njit(cache=True, inline="always")
def _tally_position(
    a,
    sq,
    t_a,
    t_b,
    x_a,
    x_b,
    d_a,
    d_b,
    k,
    s,
    k_s,
    s_second,
    k_second,
    exact_crossings,
    edges,
    time_in,
    v2_in,
):
    """Add the time and int v^2 dt of the monotone piece [t_a, t_b] of the mean path to the
    x bins, each edge crossing placed by ``level_time_one_step`` (no iteration), or by
    ``level_time`` (to ~1e-9 of the piece) where ``exact_crossings`` (a step cut by a
    collision, which the bridge correction leaves alone).

    ``a`` are the mean path's coefficients, ``sq`` those of S(t) (see
    ``speed_squared_coefficients``), x_a, x_b and d_a, d_b the path and its slope at the
    piece's ends and ``k`` the bin of x_a.  The walk crosses one bin edge at a time (no
    logarithms); each crossing's estimate is clipped to [previous crossing, t_b], so the
    piece is cut into consecutive intervals, one per bin.  Returns the bin of x_b and the
    bins of the intervals holding the times ``s`` and ``s_second`` (``k_s``, ``k_second`` if
    before the piece).
    """
    a0, a1, a2, a3 = a
    s1, s2, s3, s4, s5 = sq
    n = edges.shape[0] - 1
    t_prev = t_a
    s_prev = quintic_antiderivative_value(s1, s2, s3, s4, s5, t_a)
    inverse = piece_inverse(t_a, t_b, x_a, x_b, d_a, d_b)
    while True:
        if k <= n and x_b >= edges[k]:  # leaves bin k through its upper edge
            level = edges[k]
            k_next = k + 1
        elif k >= 1 and x_b < edges[k - 1]:  # through its lower edge
            level = edges[k - 1]
            k_next = k - 1
        else:
            break
        if exact_crossings:
            t_e = level_time(a0, a1, a2, a3, level, inverse)
        else:  # clipped to [t_prev, t_b]; max and min keep their first argument against a NaN
            t_e = min(t_b, max(t_prev, level_time_one_step(a0, a1, a2, a3, level, inverse)))
        s_e = quintic_antiderivative_value(s1, s2, s3, s4, s5, t_e)
        time_in[k] += t_e - t_prev
        v2_in[k] += s_e - s_prev
        k_s = k if s >= t_prev else k_s
        k_second = k if s_second >= t_prev else k_second
        t_prev, s_prev = t_e, s_e
        k = k_next
    s_b = quintic_antiderivative_value(s1, s2, s3, s4, s5, t_b)
    time_in[k] += t_b - t_prev
    v2_in[k] += s_b - s_prev
    k_s = k if s >= t_prev else k_s
    k_second = k if s_second >= t_prev else k_second
    return k, k_s, k_second


@njit(cache=True, inline="always")
def _tally_step(
    a,
    dt,
    tau,
    x_tau,
    slope_tau,
    k,
    s,
    s_second,
    exact_crossings,
    edges,
    bin_lower,
    bin_upper,
    time_in,
    v2_in,
):
    """Add the time and int v^2 dt over [0, tau] of the step's piecewise assignment (the
    mean path, its edge crossings estimated) to the x bins.

    ``k`` is the bin of m(0); returns the bin of m(tau) = x_tau, where the slope is
    slope_tau, and the bins the assignment gives the times ``s`` and ``s_second``. The
    common case is a step that stays in its bin: the cubic on [0, tau] lies inside the hull
    of its Bernstein control points m(0), m(0) + m'(0) tau/3, m(tau) - m'(tau) tau/3,
    m(tau), so when those all lie in bin k the whole step is tallied there at once.
    Otherwise the path is split at the zeros of m' into monotone pieces (none when the
    control points of m' share a sign), which are walked edge by edge.
    """
    a0, a1, a2, a3 = a
    sq = speed_squared_coefficients(a1, a2, a3, dt)
    c1 = a0 + a1 * tau * (1.0 / 3.0)
    c2 = x_tau - slope_tau * tau * (1.0 / 3.0)
    lowest = min(min(a0, x_tau), min(c1, c2))
    highest = max(max(a0, x_tau), max(c1, c2))
    if bin_lower[k] <= lowest and highest < bin_upper[k]:
        time_in[k] += tau
        v2_in[k] += quintic_antiderivative_value(sq[0], sq[1], sq[2], sq[3], sq[4], tau)
        return k, k, k
    # m' is a quadratic with Bernstein control points m'(0), m'(0) + a2 tau,
    # m'(tau): when they share a sign, m is monotone and needs no split
    slope_mid = a1 + a2 * tau
    if (a1 > 0.0 and slope_mid > 0.0 and slope_tau > 0.0) or (
        a1 < 0.0 and slope_mid < 0.0 and slope_tau < 0.0
    ):
        n_zero, t1, t2 = 0, tau, tau
    else:
        n_zero, t1, t2 = slope_zeros(a1, a2, a3, tau)
    t_a = 0.0
    x_a = a0
    d_a = a1
    k_s = k_second = k
    for piece in range(n_zero + 1):
        t_b = monotone_piece_end(piece, n_zero, t1, t2, tau)
        if t_b == tau:
            x_b, d_b = x_tau, slope_tau
        else:  # a zero of m'
            x_b, d_b = cubic_value(a0, a1, a2, a3, t_b), 0.0
        k, k_s, k_second = _tally_position(
            a,
            sq,
            t_a,
            t_b,
            x_a,
            x_b,
            d_a,
            d_b,
            k,
            s,
            k_s,
            s_second,
            k_second,
            exact_crossings,
            edges,
            time_in,
            v2_in,
        )
        t_a, x_a, d_a = t_b, x_b, d_b
    return k, k_s, k_second


@njit(cache=True)
def _bridge_correction(a1, a2, a3, dt, weight, s, normal_1, k_s, k_x, time_in, v2_in):
    """The bridge correction of a step's P(x) and <v^2>_x (module docstring): the assignment
    gave the time s to bin k_s, the bridge point x(s) (drawn with ``normal_1``) is in bin
    k_x; the point's ``weight`` (the length of the interval s is uniform in: tau, or a
    stratum of ``floor_stratum_end``) moves from k_s to k_x, and weight E[v(s)^2 | x(s),
    ends] with it in int v^2 dt.  Called where k_x != k_s, in steps not cut by a
    collision."""
    v2_s = weight * bridge_speed_squared_given_position(a1, a2, a3, dt, s, normal_1)
    time_in[k_x] += weight
    time_in[k_s] -= weight
    v2_in[k_x] += v2_s
    v2_in[k_s] -= v2_s


#: A step that starts at the floor (the outgoing step of a collision) draws a second bridge point
#: while its mean path is still below this height, where the x bins are narrow
#: (``floor_stratum_end``).
FLOOR_STRATUM_HEIGHT = 0.1


@njit(cache=True)
def floor_stratum_end(tau, x, v):
    """Where the bridge points of a step of length tau from (x, v) are stratified: t_low.

    t_low = FLOOR_STRATUM_HEIGHT / v in a step that starts at the floor (x = 0, v = v_out) with
    v tau > FLOOR_STRATUM_HEIGHT, about where its mean path (v t - t^2 / 2 + ...) reaches
    that height; else tau (one point, no strata).  With t_low < tau the step draws two
    points, s uniform in [t_low, tau] with weight tau - t_low and s uniform in [0, t_low]
    with weight t_low: P(x, v) and the bridge correction stay exact in expectation and the
    weights still add up to tau.  Why: such a step is long (D ~ (v / c)^2 from the floor, up
    to a few time units, eq. (criterion)) and crosses the narrow bins near the floor in a small
    part of it; its one uniform point landed there rarely and then moved a whole step's tau
    (and tau V in <v^2>_x) into one of them, a heavy tail of the shards' <v^2>_x at x < 0.003
    (excess kurtosis 9-12 over the 64 shards of the default run at r = 1/2 and 3/4).

    Parameters
    ----------
    tau : float
        The step's length in time (up to a collision, if it has one).
    x, v : float
        The step's start.

    Returns
    -------
    float
        t_low: FLOOR_STRATUM_HEIGHT / v for a step from the floor that rises past that height
        on its mean path, else tau.

    Examples
    --------
    The Python function (``py_func``: no compile):

    >>> from bouncing_ball.simulation import floor_stratum_end
    >>> print(floor_stratum_end.py_func(2.0, 0.0, 1.0), floor_stratum_end.py_func(2.0, 0.5, 1.0))
    0.1 2.0
    >>> print(floor_stratum_end.py_func(0.05, 0.0, 1.0))
    0.05
    """
    if x == 0.0 and v * tau > FLOOR_STRATUM_HEIGHT:
        return FLOOR_STRATUM_HEIGHT / v
    return tau


# What the compiled loop records, by bit of its ``parts`` argument: the benchmark leaves
# them out one at a time to time each (``python -m benchmarks``); a shard records them all.
# The collisions, their outgoing speeds, the time and the steps are always recorded.
MEAN_PATH_INTEGRALS = 1  #: Bit of ``parts``: int x dt and int x^2 dt.
POSITION = 2  #: Bit of ``parts``: P(x) and <v^2>_x (the mean path and its bridge correction).
JOINT = 4  #: Bit of ``parts``: P(x, v) from the bridge sample.
FLIGHTS = 8  #: Bit of ``parts``: flight times and (outgoing, return) speed pairs.
CONTROL_VARIATES = 16  #: Bit of ``parts``: the noise sums of the martingale control variates.
#: Every bit of ``parts``: what a shard records.
EVERY_TALLY = MEAN_PATH_INTEGRALS | POSITION | JOINT | FLIGHTS | CONTROL_VARIATES


@njit(cache=True)
def _tally_second_bridge_point(
    tally_high,
    tally_low,
    tally_inc_high,
    tally_inc_low,
    a,
    dt,
    s,
    weight,
    k_s,
    collided,
    parts,
    x_log_lo,
    x_per_ln,
    x_edges,
    x_bin_lower,
    x_bin_upper,
    u_lo,
    u_per_unit,
    u_edges,
    position_time,
    position_v2_time,
    position_velocity_time,
):
    """The second bridge point of a step from the floor (``floor_stratum_end``), at time s
    in [0, t_low] with ``weight`` t_low, its normals drawn here from the tally stream (whose
    new state it returns): the bridge correction (with POSITION; k_s is the bin the
    assignment gives s) and P(x, v) (with JOINT), as the loop does for the first point."""
    a0, a1, a2, a3 = a
    tally_high, tally_low, normal_1 = standard_normal(
        tally_high, tally_low, tally_inc_high, tally_inc_low
    )
    tally_high, tally_low, normal_2 = standard_normal(
        tally_high, tally_low, tally_inc_high, tally_inc_low
    )
    x_s, v_s = bridge_sample(a0, a1, a2, a3, dt, s, normal_1, normal_2)
    if parts & POSITION:
        x_cell = _walked_bin_index(x_s, k_s, x_bin_lower, x_bin_upper)
        if x_cell != k_s and not collided:
            _bridge_correction(
                a1, a2, a3, dt, weight, s, normal_1, k_s, x_cell, position_time, position_v2_time
            )
    else:
        x_cell = _bin_index(x_s, x_log_lo, x_per_ln, x_edges.shape[0] - 1, x_edges)
    if parts & JOINT:
        cell_v = _linear_bin_index(v_s, u_lo, u_per_unit, u_edges.shape[0] - 1, u_edges)
        position_velocity_time[x_cell, cell_v] += weight
    return tally_high, tally_low


#: Steps between the shard loop's looks at its stop flag (``ShardStop``), at the check of its
#: step budget: a small fraction of a second of any shard.
