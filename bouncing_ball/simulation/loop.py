"""Monte Carlo simulation of the inelastically bouncing ball (the paper's Sec. IV).

The particle moves by the exact free-flight update, eqs. (xstep), (vstep),
with step Delta = D(x, v) + delta: D is the largest step allowed by
eq. (criterion) and delta a minimum step, reset after every collision so
that sqrt(2 delta) = v_out / min_step_divisor (the paper uses 500).

Where a collision happens.  When a step ends below x = 0, the collision is
placed where the bridge mean path (the cubic Hermite interpolant of the two
ends of the step, see ``free_flight``) first reaches x = 0, and the impact
speed is that path's slope there.  The rest of the step is discarded, the
particle restarts from x = 0 with v_out = r v_in, eq. (restitution), and
the clock advances only to the collision.  Taking the end-of-step velocity
instead adds the whole step's noise sqrt(2 Delta) >= sqrt(2 delta) to the
impact speed, which biases P(0, v) upward at speeds comparable to it; the
interpolated crossing does not.

What a shard records after its equilibration time (integrals over each step
given both its ends, not left-point sums, which are biased because Delta
depends on the state):

  * outgoing speeds at collisions, on log bins;
  * the time, collisions and steps (all after equilibration);
  * int x dt and int x^2 dt, exact in expectation given the ends (mean path
    plus bridge variance);
  * one point of each recorded step's bridge: a time s uniform in [0, tau] and
    (x(s), v(s)) from the bridge's exact conditional Gaussian given both ends
    (``free_flight.bridge_sample``), drawn from their own generator
    (``tally_seed_sequence``), so the trajectory and the tallies that do not use
    the point are those of a shard without it.  A step from the floor draws two,
    one in each stratum [0, t_low], [t_low, tau] of ``floor_stratum_end``, each
    weighing its stratum's length (the weights add up to tau).
  * the time spent in each cell of (x, v), x on the position bins and v on
    evenly spaced bins, for P(x, v): the point's weight (tau, or its stratum's
    length) added to the cell of (x(s), v(s)).  Given the ends, the expectation
    of what is added to a cell is the expected time in the cell,
    int Prob[(x(s), v(s)) in cell | ends] ds over the step: unbiased, with no
    discretisation error.
  * the time spent in each log bin of x, and int v^2 dt in each bin, which give
    P(x) and <v^2>_x of eq. (moment2), exact in expectation (but in the steps
    cut by a collision, below), with nearly the errors of the mean path's
    integrals alone.  A step's time is first assigned along its
    mean path, each bin edge crossed at a time estimated by one Halley step
    (``free_flight.level_time_one_step``), and int v^2 dt integrates E[v^2 |
    ends] (slope squared plus bridge variance of v).  That assignment alone is
    biased: it ignores the bridge's spread sigma_x ~ (Delta^3 / 96)^(1/2) about
    the mean path, which moves about (sigma_x^2 / 2) P''/P of a bin's time,
    up to 1e-3 where steps are long (measured at r = 0.75: 5-7 sigma of the
    default run); and a crossing estimate that is off moves time between
    neighbouring bins.  The bridge correction removes both in expectation: the
    assignment gives the time s to some bin k_s, the bridge point x(s) lies in
    bin k_x; when they differ, tau moves from bin k_s to bin k_x, and tau V
    with it in int v^2 dt, V = E[v(s)^2 | x(s), ends]
    (``free_flight.bridge_speed_squared_given_position``, whose mean over x(s)
    is the integrand of the assignment).  In expectation this adds the bridge
    law's time in each bin minus the assignment's, whatever the assignment, so
    the sum is exact; it changes nothing when k_s = k_x (most steps), and it
    raises the errors of P(x) by 1-3 % and those of <v^2>_x by 5-12 % (medians
    over the bins of the default run; docs/methods.md).
    A step cut by a collision is left on its mean path, as its collision is
    (crossings by ``free_flight.level_time``, no correction): past the mean
    path's zero the free bridge is not the ball's path, and one point of such
    a step, long and fast near the floor, could move a whole step's tau V into
    a small bin (heavy-tailed noise for no gain in exactness).
  * the flights: for each recorded collision that has an earlier collision
    (in the recording or in equilibration), the time T since that collision
    (its count on log bins, sum T, sum T^2), and the pair (outgoing speed u
    of that earlier collision, return speed abs(v) at this one) on the speed
    bins.  A flight is counted at the collision that ends it, so in a
    stationary shard the expected sum of f(T) over the recorded flights is
    I x (recorded time) x E[f(T)] with E the equilibrium average per
    collision (Palm): unbiased, with no edge effect at either end of the
    recording (docs/methods.md, 'Flights').
  * the bounce chain: for each recorded collision n and lag k = 0 .. BOUNCE_LAGS, the pair
    of outgoing speeds (u_{n-k}, u_n), the earlier from a ring buffer of the last
    BOUNCE_LAGS + 1 collisions (equilibration included): the sums of ln u and u of each and
    of their four products (``tallies.BOUNCE_LAG_SUMS``), which give the autocorrelation of
    ln u_n and the relaxation eigenvalue of the chain (``estimators.bounce_autocorrelation``).
    Counted at the later collision, as a flight is: unbiased, no edge effect.
  * control variates: sums over the recorded steps of the velocity noise
    xi = sqrt(2 dt) normal_r of eq. (vstep) (noise_sum), of v xi (noise_v_sum),
    of v xi / (x + v^2/2 + 4 dt) (noise_scaled_sum) and of normal_r
    (normal_sum), x, v and dt those of the step's start.  dt is fixed before
    the normals are drawn, so each term has mean 0 given the past, and each sum
    has expectation exactly 0 under the simulated process (whole xi also in a
    step cut short by a collision).  Fourteen more (``tallies.MOMENT_CONTROL_SUMS``)
    weigh xi by x, x v, x^2, v^2, v^3, v^4 and x v^2, xi^2 - 2 dt by 1, v, x and
    v^2, and the position noise dt^(3/2) normal_s of eq. (xstep) by 1, v and x,
    the same way.  ``estimators.control_variate_adjusted`` subtracts their
    fitted share from the tallies: the same expectation, less variance of I,
    the moments of x and of the flights, and the bins of P(0, v), P(x) and
    <v^2>_x (docs/methods.md).
  * the time, collisions, int x dt and int x^2 dt of the steps that start in the
    early part of the recording (t < EARLY_FRACTION x shard_time, tallies): the
    shard's own evidence of equilibration, that part against the rest compared by
    ``equilibration``.  Taken as the running sums when the first step starts past
    it, so no step is cut there.

A shard's work is bounded: it stops after ``max_steps`` steps (equilibration
included) even if the simulated time has not been reached, and says so.

A shard can be stopped from another thread (``ShardStop``; ``simulate``'s Ctrl-C): the loop
releases the GIL and looks at its stop flag every ``STOP_CHECK_STEPS`` steps, where it
checks the step budget, so the step itself is unchanged.  A stopped shard has no tallies
(``ShardStopped``); a shard that is not stopped is the same, number for number.

Below r_c = exp(-pi / sqrt 3) (inelastic collapse).  The collision rate I
of eq. (collrate) is infinite there: each collision shrinks the outgoing
speed by a random factor whose mean logarithm is negative, the speeds go
to zero geometrically, and infinitely many collisions happen in a finite
time.  With the paper's rule alone, delta shrinks with v_out and the
simulation follows the collapse until the step budget runs out or the step falls below
COLLAPSED_STEP (speeds ~ 1e-37; the shard then stops and says so, as for
an exhausted budget);
simulated time stops advancing.  A floor on the minimum step, delta >= min_step_floor,
is the regularisation: it takes over from the 1/500 rule once v_out
falls below about min_step_divisor * (2 min_step_floor)^(1/2), and once
v_out falls below about (2 min_step_floor)^(1/2) a single step's noise
exceeds the speed and lifts the particle off the floor: the collapse is
cut off at speeds of order (2 min_step_floor)^(1/2).
What the regularised process gives above that speed scale, and how I grows
as the floor goes to zero, is measured, not assumed (docs/methods.md, 'Below r_c').

The loop is numba-compiled: a shard compiles it on its first call (ten seconds or so), so the Examples
that run a shard are not run as doctests; the unit and statistical tests run shards.
"""

import math

import numpy as np

from ..free_flight import (
    bridge_sample,
    criterion_root,
    cubic_slope,
    first_crossing_time,
    free_flight_step,
    hermite_cubic,
    mean_path_integrals,
    predicted_start,
    root_predictor,
    whole_step_integrals,
)
from ..jit import flag_is_set, fma, njit
from ..pcg64 import next_double, standard_normal, stream_words
from ..settings import ShardSettings, return_law_speed_bins
from ..tallies import EARLY_FRACTION, SCALAR_INDEX, ShardTallies, tally_seed_sequence
from .step_tallies import (
    CONTROL_VARIATES,
    EVERY_TALLY,
    FLIGHTS,
    JOINT,
    MEAN_PATH_INTEGRALS,
    POSITION,
    _bin_index,
    _bridge_correction,
    _linear_bin_index,
    _log_bin_index,
    _tally_second_bridge_point,
    _tally_step,
    _walked_bin_index,
    floor_stratum_end,
)

__all__ = [
    "shard_seed_sequence",
    "simulate_shard",
    "ShardStop",
    "ShardStopped",
    "STOP_CHECK_STEPS",
    "COLLAPSED_STEP",
]

# indices into the scalar tally array of the compiled loop (its layout: tallies.SCALARS)
_TIME = SCALAR_INDEX["time"]
_COLLISIONS = SCALAR_INDEX["collisions"]
_STEPS = SCALAR_INDEX["steps"]
_INT_X = SCALAR_INDEX["int_x"]
_INT_X2 = SCALAR_INDEX["int_x2"]
_EXHAUSTED = SCALAR_INDEX["budget_exhausted"]
_FLIGHTS = SCALAR_INDEX["flights"]
_FLIGHT_TIME_SUM = SCALAR_INDEX["flight_time_sum"]
_FLIGHT_TIME_SQUARED_SUM = SCALAR_INDEX["flight_time_squared_sum"]
_NOISE_SUM = SCALAR_INDEX["noise_sum"]
_NOISE_V_SUM = SCALAR_INDEX["noise_v_sum"]
_NOISE_SCALED_SUM = SCALAR_INDEX["noise_scaled_sum"]
_NORMAL_SUM = SCALAR_INDEX["normal_sum"]
_EARLY_TIME = SCALAR_INDEX["early_time"]
_EARLY_COLLISIONS = SCALAR_INDEX["early_collisions"]
_EARLY_INT_X = SCALAR_INDEX["early_int_x"]
_EARLY_INT_X2 = SCALAR_INDEX["early_int_x2"]
_NOISE_X_SUM = SCALAR_INDEX["noise_x_sum"]
_NOISE_XV_SUM = SCALAR_INDEX["noise_xv_sum"]
_NOISE_X2_SUM = SCALAR_INDEX["noise_x2_sum"]
_NOISE_V2_SUM = SCALAR_INDEX["noise_v2_sum"]
_NOISE_V3_SUM = SCALAR_INDEX["noise_v3_sum"]
_NOISE_V4_SUM = SCALAR_INDEX["noise_v4_sum"]
_NOISE_XV2_SUM = SCALAR_INDEX["noise_xv2_sum"]
_NOISE_SQUARED_SUM = SCALAR_INDEX["noise_squared_sum"]
_NOISE_SQUARED_V_SUM = SCALAR_INDEX["noise_squared_v_sum"]
_NOISE_SQUARED_X_SUM = SCALAR_INDEX["noise_squared_x_sum"]
_NOISE_SQUARED_V2_SUM = SCALAR_INDEX["noise_squared_v2_sum"]
_POSITION_NOISE_SUM = SCALAR_INDEX["position_noise_sum"]
_POSITION_NOISE_V_SUM = SCALAR_INDEX["position_noise_v_sum"]
_POSITION_NOISE_X_SUM = SCALAR_INDEX["position_noise_x_sum"]


def shard_seed_sequence(seed, label: str, shard: int) -> np.random.SeedSequence:
    """The random stream of one (r, shard): independent of job order and cores.

    The r label (see ``restitution.restitution_label``) enters the spawn key as the integer
    spelled by its ASCII bytes, so different r never share a stream.  A root
    ``numpy.random.SeedSequence`` is the int seed's generalisation: its entropy, its spawn
    key followed by (the label's integer, ``shard``), and its pool size; so the root
    ``SeedSequence(seed)`` gives the int ``seed``'s streams, and a root's own children
    (``SeedSequence.spawn``) are unaffected (it is read, not spawned from).

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        The run's root seed (the config's ``seed``, an int >= 0), or a root SeedSequence.
    label : str
        r as the pipeline names it (``restitution.restitution_label``), ASCII.
    shard : int
        The shard's index, >= 0.

    Returns
    -------
    numpy.random.SeedSequence
        The shard's stream: entropy ``seed``, spawn key (the label's integer, ``shard``); for
        a root SeedSequence, its entropy, its spawn key + (the label's integer, ``shard``)
        and its pool size.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.simulation import shard_seed_sequence
    >>> stream = shard_seed_sequence(1, "0.5", 3)
    >>> print(stream.spawn_key, int.from_bytes(b"0.5", "big"))
    (3157557, 3) 3157557
    >>> again = shard_seed_sequence(1, "0.5", 3).generate_state(4)
    >>> print(np.array_equal(stream.generate_state(4), again))
    True
    >>> other_shard = shard_seed_sequence(1, "0.5", 4).generate_state(4)
    >>> print(np.array_equal(again, other_shard))
    False
    >>> root = shard_seed_sequence(np.random.SeedSequence(1), "0.5", 3).generate_state(4)
    >>> print(np.array_equal(root, again))
    True
    """
    r_key = int.from_bytes(label.encode("ascii"), "big")
    if isinstance(seed, np.random.SeedSequence):
        return np.random.SeedSequence(
            entropy=seed.entropy,
            spawn_key=(*seed.spawn_key, r_key, shard),
            pool_size=seed.pool_size,
        )
    return np.random.SeedSequence(entropy=seed, spawn_key=(r_key, shard))


STOP_CHECK_STEPS = 1 << 16


class ShardStop:
    """A request to stop a running shard: ``simulate_shard``'s ``stop``.

    ``set`` makes it, from any thread; the shard then raises ``ShardStopped`` within
    ``STOP_CHECK_STEPS`` steps.

    Examples
    --------
    >>> from bouncing_ball.simulation import ShardStop
    >>> stop = ShardStop()
    >>> stop.is_set()
    False
    >>> stop.set()
    >>> stop.is_set()
    True
    """

    def __init__(self):
        self.flag = np.zeros(1, dtype=np.int64)  # what the compiled loop reads (``flag_is_set``)

    def set(self):
        self.flag[0] = 1

    def is_set(self) -> bool:
        return flag_is_set(self.flag)


class ShardStopped(Exception):
    """A shard stopped by its ``ShardStop`` before it finished: it has no tallies.

    The part it ran is no shard of the run's, whose every tally covers the whole recorded
    time."""


@njit(cache=True, inline="always")
def _tally_bounce_lags(sums, ring_log, ring_speed, newest, history, log_u, u):
    """Add the pairs (u_{n-k}, u_n), k = 0 .. history - 1, of the collision n of outgoing
    speed u (logarithm ``log_u``) to the bounce-lag sums (``tallies.BOUNCE_LAG_SUMS``, rows
    of ``sums``): u_{n-k} is the ring buffer's entry k places before ``newest``, where u_n
    itself is."""
    size = ring_log.shape[0]
    for k in range(history):
        j = newest - k
        if j < 0:
            j += size
        lead_log = ring_log[j]
        lead_u = ring_speed[j]
        sums[0, k] += 1.0
        sums[1, k] += lead_log
        sums[2, k] += lead_u
        sums[3, k] += log_u
        sums[4, k] += u
        sums[5, k] += lead_log * log_u
        sums[6, k] += lead_log * u
        sums[7, k] += lead_u * log_u
        sums[8, k] += lead_u * u


# a step this short only happens in a collapse (v ~ 1e-37); much shorter ones overflow the bridge's
# cubic coefficients (~ x / dt^2) before the speed underflows to zero
COLLAPSED_STEP = 1.0e-80


@njit(cache=True, nogil=True)
def _run(
    stream,
    tally_stream,
    restitution,
    c,
    min_step_divisor,
    min_step_floor,
    equilibration_time,
    recorded_time,
    max_steps,
    v_edges,
    x_edges,
    u_edges,
    f_edges,
    w_edges,
    speed_counts,
    position_time,
    position_v2_time,
    flight_time_counts,
    position_velocity_time,
    return_speed_counts,
    return_law_speed_counts,
    bounce_lag_sums,
    scalars,
    parts,
    stop,
):
    # stop: the stop flag (ShardStop.flag); returns True when it stopped the shard
    # v_edges: speeds (log); x_edges: heights (log); u_edges: velocities of P(x, v) (linear);
    # f_edges: flight times (log); w_edges: outgoing speeds, fine (log, settings.return_law_speed_bins);
    # stream, tally_stream: the PCG64 states (pcg64.stream_words)
    high, low, inc_high, inc_low = stream
    tally_high, tally_low, tally_inc_high, tally_inc_low = tally_stream
    nv = v_edges.shape[0] - 1
    v_log_lo = math.log(v_edges[0])
    v_per_ln = nv / (math.log(v_edges[nv]) - v_log_lo)
    nx = x_edges.shape[0] - 1
    x_log_lo = math.log(x_edges[0])
    x_per_ln = nx / (math.log(x_edges[nx]) - x_log_lo)
    nu = u_edges.shape[0] - 1
    u_lo = u_edges[0]
    u_per_unit = nu / (u_edges[nu] - u_lo)
    nf = f_edges.shape[0] - 1
    f_log_lo = math.log(f_edges[0])
    f_per_ln = nf / (math.log(f_edges[nf]) - f_log_lo)
    log_restitution = math.log(restitution)
    nw = w_edges.shape[0] - 1
    w_log_lo = math.log(w_edges[0])
    w_per_ln = nw / (math.log(w_edges[nw]) - w_log_lo)
    # the two ends of every x bin, the under- and overflow bins unbounded
    x_bin_lower = np.empty(nx + 2)
    x_bin_upper = np.empty(nx + 2)
    x_bin_lower[0] = -np.inf
    for k in range(nx + 1):
        x_bin_lower[k + 1] = x_edges[k]
        x_bin_upper[k] = x_edges[k]
    x_bin_upper[nx + 1] = np.inf

    # start at rest one unit above the floor; equilibration forgets this
    x = 1.0
    v = 0.0
    root, slope_at_root = criterion_root(x, v, c, 0.0)  # s* of eq. (criterion) and f'(s*)
    x_bin = _bin_index(x, x_log_lo, x_per_ln, nx, x_edges)  # kept while recording
    min_root_2delta = 1.0 / min_step_divisor
    delta = max(0.5 * min_root_2delta * min_root_2delta, min_step_floor)
    recording = equilibration_time <= 0.0
    t = 0.0
    t_stop = recorded_time if recording else equilibration_time
    steps = 0  # all steps, against the budget
    recorded_steps = 0
    collisions = 0
    int_x = 0.0
    int_x2 = 0.0
    exhausted = 0
    flights = 0
    flight_time_sum = 0.0
    flight_time_squared_sum = 0.0
    since_collision = 0.0  # time since the last collision (equilibration included)
    collided_before = False
    last_out_bin = 0  # speed bin of the last collision's outgoing speed
    # the outgoing speeds of the last collisions and their logarithms (the bounce-lag sums)
    ring_size = bounce_lag_sums.shape[1]
    ring_log = np.zeros(ring_size)
    ring_speed = np.zeros(ring_size)
    ring_newest = ring_size - 1  # where the latest collision is
    ring_history = 0  # collisions in the ring
    # the control variates (martingales of mean 0, see the module docstring)
    noise_sum = 0.0
    noise_v_sum = 0.0
    noise_scaled_sum = 0.0
    normal_sum = 0.0
    noise_x_sum = 0.0
    noise_xv_sum = 0.0
    noise_x2_sum = 0.0
    noise_v2_sum = 0.0
    noise_v3_sum = 0.0
    noise_v4_sum = 0.0
    noise_xv2_sum = 0.0
    noise_squared_sum = 0.0
    noise_squared_v_sum = 0.0
    noise_squared_x_sum = 0.0
    noise_squared_v2_sum = 0.0
    position_noise_sum = 0.0
    position_noise_v_sum = 0.0
    position_noise_x_sum = 0.0
    # the early part of the recording: the running sums when a step first starts past t_early
    t_early = EARLY_FRACTION * recorded_time if recording else math.inf
    early_time = 0.0
    early_collisions = 0
    early_int_x = 0.0
    early_int_x2 = 0.0
    stopped = False
    next_check = 0  # the next step at which the budget and the stop flag are looked at

    while True:
        if t >= t_stop:
            if recording:
                break
            recording = True
            x_bin = _bin_index(x, x_log_lo, x_per_ln, nx, x_edges)
            t = 0.0
            t_stop = recorded_time
            t_early = EARLY_FRACTION * recorded_time
            continue
        if t >= t_early:
            early_time = t
            early_collisions = collisions
            early_int_x = int_x
            early_int_x2 = int_x2
            t_early = math.inf
        if steps >= next_check:  # one comparison a step for the budget and the stop flag
            if steps >= max_steps:
                exhausted = 1
                break
            if flag_is_set(stop):
                stopped = True
                break
            next_check = min(max_steps, steps + STOP_CHECK_STEPS)
        dt = fma(root, root, delta)  # eq. (criterion) plus delta
        if not dt > COLLAPSED_STEP:  # below r_c without a floor on delta: the speed is going to 0
            exhausted = 1
            break
        if t + dt > t_stop:
            dt = t_stop - t
        # the next root starts from a first-order prediction off this one
        predictor = root_predictor(root, slope_at_root, x, v)
        high, low, normal_r = standard_normal(high, low, inc_high, inc_low)
        high, low, normal_s = standard_normal(high, low, inc_high, inc_low)
        x1, v1 = free_flight_step(x, v, dt, normal_r, normal_s)
        collided = x1 < 0.0
        # the bridge's mean path, where something uses it (a step with no collision
        # integrates x and x^2 from its ends alone)
        if collided or (recording and parts & (POSITION | JOINT)):
            a = hermite_cubic(x, v, x1, v1, dt)
        else:
            a = (x, v, 0.0, 0.0)  # not used
        a0, a1, a2, a3 = a
        if collided:  # the step ends where the mean path first reaches 0
            tau = first_crossing_time(a0, a1, a2, a3, dt, x1)
            x_tau = 0.0
            v_tau = cubic_slope(a1, a2, a3, tau)
        else:
            tau, x_tau, v_tau = dt, x1, v1
        steps += 1
        if recording:
            recorded_steps += 1
            if parts & CONTROL_VARIATES:
                # dt and the state were fixed before the normals were drawn: each term has mean
                # 0 given the past, whether or not the step is then cut at a collision
                xi = math.sqrt(2.0 * dt) * normal_r  # the velocity noise of eq. (vstep)
                noise_sum += xi
                noise_v_sum += v * xi
                noise_scaled_sum += v / (x + 0.5 * v * v + 4.0 * dt) * xi
                normal_sum += normal_r
                # the moments' control variates: weights polynomial in the start state times
                # xi, q = xi^2 - 2 dt (mean 0 given the past) and eta = dt^(3/2) normal_s
                x2 = x * x
                v2 = v * v
                noise_x_sum += x * xi
                noise_xv_sum += x * v * xi
                noise_x2_sum += x2 * xi
                noise_v2_sum += v2 * xi
                noise_v3_sum += v2 * v * xi
                noise_v4_sum += v2 * v2 * xi
                noise_xv2_sum += x * v2 * xi
                q = xi * xi - 2.0 * dt
                noise_squared_sum += q
                noise_squared_v_sum += v * q
                noise_squared_x_sum += x * q
                noise_squared_v2_sum += v2 * q
                eta = dt * math.sqrt(dt) * normal_s
                position_noise_sum += eta
                position_noise_v_sum += v * eta
                position_noise_x_sum += x * eta
            if parts & MEAN_PATH_INTEGRALS:
                if collided:
                    ix, ix2 = mean_path_integrals(a0, a1, a2, a3, dt, tau)
                else:
                    ix, ix2 = whole_step_integrals(x, v, x1, v1, dt)
                int_x += ix
                int_x2 += ix2
            if parts & (POSITION | JOINT):
                # the step's bridge points, (x(s), v(s)), from the tally stream: P(x, v), and the
                # bridge-law correction of P(x), <v^2>_x.  One, s uniform in [0, tau] with weight
                # tau; two in a step from the floor, one in each stratum of floor_stratum_end
                t_low = floor_stratum_end(tau, x, v)
                tally_high, tally_low, u = next_double(
                    tally_high, tally_low, tally_inc_high, tally_inc_low
                )
                tally_high, tally_low, normal_1 = standard_normal(
                    tally_high, tally_low, tally_inc_high, tally_inc_low
                )
                tally_high, tally_low, normal_2 = standard_normal(
                    tally_high, tally_low, tally_inc_high, tally_inc_low
                )
                s = u * tau
                weight = tau
                s2 = s
                if t_low < tau:
                    s = t_low + u * (tau - t_low)
                    weight = tau - t_low
                    tally_high, tally_low, u2 = next_double(
                        tally_high, tally_low, tally_inc_high, tally_inc_low
                    )
                    s2 = u2 * t_low
            if parts & POSITION:
                x_bin, k_s, k_s2 = _tally_step(
                    a,
                    dt,
                    tau,
                    x_tau,
                    v_tau,
                    x_bin,
                    s,
                    s2,
                    collided,
                    x_edges,
                    x_bin_lower,
                    x_bin_upper,
                    position_time,
                    position_v2_time,
                )
            if parts & POSITION:
                # the point itself after the walk: fewer values live across it (numba then
                # keeps pace with the C reference)
                x_s, v_s = bridge_sample(a0, a1, a2, a3, dt, s, normal_1, normal_2)
                # the assignment gave the time s to bin k_s, the bridge puts x(s) in x_cell: the
                # bridge correction (module docstring) makes the tally exact in expectation (not
                # in a step cut by a collision, which keeps the mean path its collision is on)
                x_cell = _walked_bin_index(x_s, k_s, x_bin_lower, x_bin_upper)
                if x_cell != k_s and not collided:
                    _bridge_correction(
                        a1,
                        a2,
                        a3,
                        dt,
                        weight,
                        s,
                        normal_1,
                        k_s,
                        x_cell,
                        position_time,
                        position_v2_time,
                    )
            if parts & JOINT:
                # P(x, v): the point's weight to the cell of (x(s), v(s))
                if not parts & POSITION:
                    x_s, v_s = bridge_sample(a0, a1, a2, a3, dt, s, normal_1, normal_2)
                    x_cell = _bin_index(x_s, x_log_lo, x_per_ln, nx, x_edges)
                position_velocity_time[
                    x_cell, _linear_bin_index(v_s, u_lo, u_per_unit, nu, u_edges)
                ] += weight
            if parts & (POSITION | JOINT) and t_low < tau:
                # the second point of a step from the floor, in [0, t_low] (rare: its own function)
                tally_high, tally_low = _tally_second_bridge_point(
                    tally_high,
                    tally_low,
                    tally_inc_high,
                    tally_inc_low,
                    a,
                    dt,
                    s2,
                    t_low,
                    k_s2,
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
                )
        t += tau
        since_collision += tau
        if collided:
            v_in = abs(v_tau)
            v_out = restitution * v_in  # eq. (restitution)
            log_v_out = math.log(v_out)  # the bins of v_out, and of v_in = v_out / r, from it
            out_bin = _log_bin_index(v_out, log_v_out, v_log_lo, v_per_ln, nv, v_edges)
            ring_newest = 0 if ring_newest == ring_size - 1 else ring_newest + 1
            ring_log[ring_newest] = log_v_out
            ring_speed[ring_newest] = v_out
            if ring_history < ring_size:
                ring_history += 1
            if recording:
                _tally_bounce_lags(
                    bounce_lag_sums,
                    ring_log,
                    ring_speed,
                    ring_newest,
                    ring_history,
                    log_v_out,
                    v_out,
                )
                collisions += 1
                speed_counts[out_bin] += 1
                return_law_speed_counts[
                    _log_bin_index(v_out, log_v_out, w_log_lo, w_per_ln, nw, w_edges)
                ] += 1
                if collided_before and parts & FLIGHTS:  # the flight that ends here
                    flights += 1
                    flight_time_sum += since_collision
                    flight_time_squared_sum += since_collision * since_collision
                    flight_time_counts[
                        _bin_index(since_collision, f_log_lo, f_per_ln, nf, f_edges)
                    ] += 1
                    return_speed_counts[
                        last_out_bin,
                        _log_bin_index(
                            v_in, log_v_out - log_restitution, v_log_lo, v_per_ln, nv, v_edges
                        ),
                    ] += 1
            collided_before = True
            since_collision = 0.0
            last_out_bin = out_bin
            x = 0.0
            x_bin = 0
            v = v_out
            root_2delta = v_out * min_root_2delta
            delta = max(0.5 * root_2delta * root_2delta, min_step_floor)  # below r_c: regularises
            root, slope_at_root = criterion_root(x, v, c, 0.0)  # closed form at x = 0
        else:
            x = x1
            v = v1
            start = predicted_start(predictor, root, x1, v1)
            root, slope_at_root = criterion_root(x, v, c, start)

    scalars[_TIME] = t if recording else 0.0
    scalars[_COLLISIONS] = collisions
    scalars[_STEPS] = recorded_steps
    scalars[_INT_X] = int_x
    scalars[_INT_X2] = int_x2
    scalars[_EXHAUSTED] = exhausted
    scalars[_FLIGHTS] = flights
    scalars[_FLIGHT_TIME_SUM] = flight_time_sum
    scalars[_FLIGHT_TIME_SQUARED_SUM] = flight_time_squared_sum
    scalars[_NOISE_SUM] = noise_sum
    scalars[_NOISE_V_SUM] = noise_v_sum
    scalars[_NOISE_SCALED_SUM] = noise_scaled_sum
    scalars[_NORMAL_SUM] = normal_sum
    scalars[_EARLY_TIME] = early_time
    scalars[_EARLY_COLLISIONS] = early_collisions
    scalars[_EARLY_INT_X] = early_int_x
    scalars[_EARLY_INT_X2] = early_int_x2
    scalars[_NOISE_X_SUM] = noise_x_sum
    scalars[_NOISE_XV_SUM] = noise_xv_sum
    scalars[_NOISE_X2_SUM] = noise_x2_sum
    scalars[_NOISE_V2_SUM] = noise_v2_sum
    scalars[_NOISE_V3_SUM] = noise_v3_sum
    scalars[_NOISE_V4_SUM] = noise_v4_sum
    scalars[_NOISE_XV2_SUM] = noise_xv2_sum
    scalars[_NOISE_SQUARED_SUM] = noise_squared_sum
    scalars[_NOISE_SQUARED_V_SUM] = noise_squared_v_sum
    scalars[_NOISE_SQUARED_X_SUM] = noise_squared_x_sum
    scalars[_NOISE_SQUARED_V2_SUM] = noise_squared_v2_sum
    scalars[_POSITION_NOISE_SUM] = position_noise_sum
    scalars[_POSITION_NOISE_V_SUM] = position_noise_v_sum
    scalars[_POSITION_NOISE_X_SUM] = position_noise_x_sum
    return stopped


def simulate_shard(
    restitution: float,
    seed_sequence: np.random.SeedSequence,
    settings: ShardSettings,
    parts: int = EVERY_TALLY,
    stop: ShardStop = None,
) -> ShardTallies:
    """Run one shard of r = ``restitution`` and return its tallies (pure: no I/O).

    The particle moves by eqs. (xstep), (vstep) with the step of eq. (criterion) and collides
    by eq. (restitution) (the module's account of the method).  It runs
    ``settings.equilibration_time`` first, then records ``settings.shard_time``, or stops
    after ``settings.max_steps`` steps (equilibration included) and says so
    (``budget_exhausted``).  ``settings.min_step_floor`` is a lower bound on delta (0: the
    paper's rule alone); below r_c it is what keeps the simulation going (module docstring).

    Parameters
    ----------
    restitution : float
        r, 0 < r < 1.
    seed_sequence : numpy.random.SeedSequence
        The shard's stream (``shard_seed_sequence``); the bridge points draw from its first
        child (``tallies.tally_seed_sequence``).
    settings : settings.ShardSettings
        The shard's parameters: shard_time, equilibration_time, criterion_c (c of
        eq. (criterion)), min_step_divisor, min_step_floor and max_steps, and the bins
        speed_bins, position_bins, velocity_bins and flight_time_bins.
    parts : int, optional
        The bits of what to record (``EVERY_TALLY``, a shard records them all; the benchmark's
        breakdown leaves ``MEAN_PATH_INTEGRALS``, ``POSITION``, ``JOINT``, ``FLIGHTS`` or
        ``CONTROL_VARIATES`` out); the collisions, their outgoing speeds, the time and the
        steps are always recorded.
    stop : ShardStop, optional
        Set from another thread to stop the shard (the loop runs without the GIL): it raises
        ``ShardStopped`` within ``STOP_CHECK_STEPS`` steps.  Not set, it changes nothing.

    Returns
    -------
    tallies.ShardTallies
        The shard's tallies, on the settings' bins.

    Raises
    ------
    ValueError
        If r is not in (0, 1).
    ShardStopped
        If ``stop`` was set before the shard finished.

    Examples
    --------
    Compiles the loop on its first call (ten seconds or so), so not run as a doctest.  Same stream,
    same numbers:

    >>> from bouncing_ball.settings import ShardSettings
    >>> from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
    >>> settings = ShardSettings(
    ...     shard_time=100.0, equilibration_time=10.0, criterion_c=5, min_step_divisor=10,
    ...     max_steps=10**7,
    ... )
    >>> shard = simulate_shard(0.5, shard_seed_sequence(1, "0.5", 0), settings)  # doctest: +SKIP
    >>> print(shard.time, shard.budget_exhausted, shard.collisions > 0)  # doctest: +SKIP
    100.0 0 True
    >>> again = simulate_shard(0.5, shard_seed_sequence(1, "0.5", 0), settings)  # doctest: +SKIP
    >>> print(again.collisions == shard.collisions, again.int_x == shard.int_x)  # doctest: +SKIP
    True True
    """
    if not 0.0 < restitution < 1.0:
        raise ValueError(f"restitution must lie in (0, 1), got {restitution}")
    rng = np.random.Generator(np.random.PCG64(seed_sequence))
    rng_tally = np.random.Generator(np.random.PCG64(tally_seed_sequence(seed_sequence)))
    arrays = ShardTallies.loop_arrays(settings)
    stopped = _run(
        stream_words(rng),
        stream_words(rng_tally),
        float(restitution),
        settings.criterion_c,
        settings.min_step_divisor,
        settings.min_step_floor,
        settings.equilibration_time,
        settings.shard_time,
        settings.max_steps,
        settings.speed_bins.edges,
        settings.position_bins.edges,
        settings.velocity_bins.edges,
        settings.flight_time_bins.edges,
        return_law_speed_bins(settings.speed_bins).edges,
        arrays["speed_counts"],
        arrays["position_time"],
        arrays["position_v2_time"],
        arrays["flight_time_counts"],
        arrays["position_velocity_time"],
        arrays["return_speed_counts"],
        arrays["return_law_speed_counts"],
        arrays["bounce_lag_sums"],
        arrays["scalars"],
        parts,
        (ShardStop() if stop is None else stop).flag,
    )
    if stopped:
        raise ShardStopped(f"the shard of r = {restitution} was stopped before it finished")
    return ShardTallies.from_loop(settings, arrays)
