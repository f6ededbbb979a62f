"""The tallies of P(x, v), drawn on the step's bridge, and of the flights between collisions.

The bridge's joint law of (x(s), v(s)) given both ends of a step is checked against brute
force; the flight tallies against a plain-Python replay of the same trajectory; the 2-D
P(x, v) tally against the 1-D P(x) tally; and the P(x, v) draws against the trajectory
(their own generator: every other tally is the same whatever they draw).
"""

import math
from dataclasses import fields

import numpy as np
import pytest
from default_settings import DEFAULT_SETTINGS
from numba import njit

from bouncing_ball import tallies
from bouncing_ball.bins import LinearBins, LogBins
from bouncing_ball.free_flight import (
    bridge_covariance,
    bridge_sample,
    cubic_slope,
    cubic_value,
    first_crossing_time,
    free_flight_step,
    hermite_cubic,
    largest_safe_step,
)
from bouncing_ball.simulation import loop, shard_seed_sequence, simulate_shard, step_tallies

SETTINGS = DEFAULT_SETTINGS.replace(
    shard_time=300.0,
    equilibration_time=0.0,
    criterion_c=3.0,
    velocity_bins=LinearBins(-6.0, 8.0, 0.25),
    flight_time_bins=LogBins(1e-8, 1e3, 5),
)


def _brute_force_paths(x0, v0, dt, s, n, seed, substeps=200):
    """(x(s), v(s), x(dt), v(dt)) of n free flights from (x0, v0), by Euler sub-steps of the
    Langevin equation dx = v dt, dv = -dt + xi dt, <xi xi> = 2 delta (no exact formula)."""
    rng = np.random.default_rng(seed)
    h = dt / substeps
    x = np.full(n, x0)
    v = np.full(n, v0)
    at_s = None
    for k in range(substeps):
        dv = -h + math.sqrt(2.0 * h) * rng.standard_normal(n)
        x += h * (v + 0.5 * dv)  # trapezoid: the velocity's path is continuous
        v += dv
        if at_s is None and (k + 1) * h >= s - 1e-12:
            at_s = (x.copy(), v.copy())
    return at_s[0], at_s[1], x, v


@pytest.mark.parametrize("u", [0.2, 0.5, 0.85])
def test_bridge_covariance_matches_brute_force(u):
    """The conditional law of (x(s), v(s)) given the step's ends: a Gaussian's conditional
    covariance is the residual covariance of the least-squares regression on the ends, and
    its conditional mean the regression; both from brute-force paths."""
    dt, n = 0.8, 150_000
    s = round(u * 200) / 200 * dt
    xs, vs, x1, v1 = _brute_force_paths(0.3, 0.4, dt, s, n, seed=int(100 * u))
    design = np.column_stack([np.ones(n), x1, v1])
    coefficients, *_ = np.linalg.lstsq(design, np.column_stack([xs, vs]), rcond=None)
    residuals = np.column_stack([xs, vs]) - design @ coefficients
    measured = np.cov(residuals.T)
    var_x, cov_xv, var_v = bridge_covariance(dt, s)
    # sampling error of a variance ~ sqrt(2/n) = 0.3 %; of the covariance ~ (var_x var_v / n)^(1/2)
    assert measured[0, 0] == pytest.approx(var_x, rel=0.02)
    assert measured[1, 1] == pytest.approx(var_v, rel=0.02)
    assert abs(measured[0, 1] - cov_xv) < 5.0 * math.sqrt(var_x * var_v / n) + 0.01 * abs(cov_xv)
    # the conditional mean at some ends is the mean path and its slope
    ends = (0.25, -0.3)
    predicted = np.array([1.0, *ends]) @ coefficients
    a = hermite_cubic(0.3, 0.4, ends[0], ends[1], dt)
    spread = np.sqrt([var_x, var_v])
    assert abs(predicted[0] - cubic_value(*a, s)) < 0.02 * spread[0]
    assert abs(predicted[1] - cubic_slope(a[1], a[2], a[3], s)) < 0.02 * spread[1]


@njit
def _bridge_samples(a0, a1, a2, a3, dt, t, n, seed):
    np.random.seed(seed)
    out = np.empty((n, 2))
    for i in range(n):
        x, v = bridge_sample(
            a0, a1, a2, a3, dt, t, np.random.standard_normal(), np.random.standard_normal()
        )
        out[i, 0] = x
        out[i, 1] = v
    return out


@pytest.mark.parametrize("u", [0.1, 0.5, 0.7])
def test_bridge_sample_has_the_bridge_mean_and_covariance(u):
    dt, n = 0.5, 200_000
    a = hermite_cubic(0.2, -0.5, 0.05, -1.1, dt)
    samples = _bridge_samples(*a, dt, u * dt, n, 1)
    var_x, cov_xv, var_v = bridge_covariance(dt, u * dt)
    mean = samples.mean(axis=0)
    assert abs(mean[0] - cubic_value(*a, u * dt)) < 5.0 * math.sqrt(var_x / n)
    assert abs(mean[1] - cubic_slope(a[1], a[2], a[3], u * dt)) < 5.0 * math.sqrt(var_v / n)
    covariance = np.cov(samples.T)
    assert covariance[0, 0] == pytest.approx(var_x, rel=0.02)
    assert covariance[1, 1] == pytest.approx(var_v, rel=0.02)
    assert abs(covariance[0, 1] - cov_xv) < 5.0 * math.sqrt(var_x * var_v / n)
    # and at the ends of the step the bridge is pinned (no NaN from a rounding error)
    for t in (0.0, dt, np.nextafter(dt, 0.0)):
        x, v = bridge_sample(*a, dt, t, 1.0, 1.0)
        assert math.isfinite(x) and math.isfinite(v)
    assert bridge_sample(*a, dt, dt, 3.0, -2.0) == pytest.approx((0.05, -1.1), abs=1e-12)


def _replay_collisions(r, seed_sequence, settings):
    """The collisions of a shard, replayed step by step in plain Python with the loop's rules
    (the same stream, so the same trajectory): [(recording, since last collision, impact
    speed, outgoing speed)]."""
    rng = np.random.Generator(np.random.PCG64(seed_sequence))
    x, v = 1.0, 0.0
    delta = max(0.5 / settings.min_step_divisor**2, settings.min_step_floor)
    recording = settings.equilibration_time <= 0.0
    t, t_stop = 0.0, settings.shard_time if recording else settings.equilibration_time
    since, events = 0.0, []
    while True:
        if t >= t_stop:
            if recording:
                return events
            recording, t, t_stop = True, 0.0, settings.shard_time
            continue
        dt = largest_safe_step(x, v, settings.criterion_c) + delta
        dt = min(dt, t_stop - t) if t + dt > t_stop else dt
        x1, v1 = free_flight_step(x, v, dt, rng.standard_normal(), rng.standard_normal())
        a = hermite_cubic(x, v, x1, v1, dt)
        tau = first_crossing_time(*a, dt, x1) if x1 < 0.0 else dt
        t += tau
        since += tau
        if x1 < 0.0:
            v_in = abs(cubic_slope(a[1], a[2], a[3], tau))
            events.append((recording, since, v_in, r * v_in))
            since, x, v = 0.0, 0.0, r * v_in
            delta = max(0.5 * (v / settings.min_step_divisor) ** 2, settings.min_step_floor)
        else:
            x, v = x1, v1


def _bin(bins, value):
    return int(np.searchsorted(bins.edges, value, side="right"))


@pytest.mark.parametrize("equilibration_time", [0.0, 30.0])
def test_flight_tallies_match_a_replay_of_the_trajectory(equilibration_time):
    settings = SETTINGS.replace(equilibration_time=equilibration_time)
    stream = shard_seed_sequence(11, "0.5", 0)
    shard = simulate_shard(0.5, stream, settings)
    events = _replay_collisions(0.5, stream, settings)
    recorded = [k for k, event in enumerate(events) if event[0]]
    assert len(recorded) == shard.collisions > 50
    # a flight is counted at the collision that ends it, if an earlier one exists
    flights = [k for k in recorded if k > 0]
    assert shard.flights == len(flights) == shard.collisions - (recorded[0] == 0)
    durations = np.array([events[k][1] for k in flights])
    assert shard.flight_time_sum == pytest.approx(durations.sum(), rel=1e-12)
    assert shard.flight_time_squared_sum == pytest.approx((durations**2).sum(), rel=1e-12)
    expected = np.zeros_like(shard.flight_time_counts)
    returns = np.zeros_like(shard.return_speed_counts)
    for k in flights:
        expected[_bin(settings.flight_time_bins, events[k][1])] += 1
        u_bin = _bin(settings.speed_bins, events[k - 1][3])
        returns[u_bin, _bin(settings.speed_bins, events[k][2])] += 1
    assert np.array_equal(shard.flight_time_counts, expected)
    assert np.array_equal(shard.return_speed_counts, returns)
    if equilibration_time == 0.0:
        # no collision before the recording: the flights fill the time from the first
        # recorded collision to the last (the replay's clock: the time of each collision)
        times = np.cumsum([event[1] for event in events])
        assert shard.flight_time_sum == pytest.approx(times[-1] - times[0], rel=1e-12)
        assert shard.flight_time_sum < shard.time
    else:
        assert recorded[0] > 0  # the first recorded flight began during equilibration


def test_distribution_tally_adds_up_to_the_position_tally_and_the_time():
    """Summed over v, the time in the (x, v) cells is the 1-D P(x) tally within the sampling
    error (both are exact in expectation); summed over everything, the recorded time."""
    shards = [
        simulate_shard(0.5, shard_seed_sequence(5, "0.5", k), SETTINGS.replace(shard_time=5.0e4))
        for k in range(16)
    ]
    for shard in shards:
        assert shard.position_velocity_time.sum() == pytest.approx(shard.time, rel=1e-12)
        assert shard.position_velocity_time.min() >= 0.0
    difference = np.stack(
        [(s.position_velocity_time.sum(axis=1) - s.position_time) / s.time for s in shards]
    )
    occupied = np.stack([s.position_time for s in shards]).min(axis=0) > 0.0
    assert occupied.sum() >= 20
    mean = difference.mean(axis=0)[occupied]
    error = difference.std(axis=0, ddof=1)[occupied] / math.sqrt(len(shards))
    z = mean / error
    # ~26 correlated bins, t statistics of 15 degrees of freedom
    assert np.max(np.abs(z)) < 4.5, np.round(z, 2)
    assert np.mean(z**2) < 2.5, np.round(z, 2)


def test_bridge_points_leave_the_trajectory_and_the_other_tallies_alone(monkeypatch):
    stream = shard_seed_sequence(4, "0.75", 0)
    settings = SETTINGS.replace(shard_time=500.0, equilibration_time=10.0)
    first = simulate_shard(0.75, stream, settings)
    # another stream for the P(x, v) draws only
    monkeypatch.setattr(
        loop,
        "tally_seed_sequence",
        lambda s: np.random.SeedSequence(entropy=s.entropy, spawn_key=(*s.spawn_key, 9)),
    )
    second = simulate_shard(0.75, stream, settings)
    # the bridge points give P(x, v) and correct P(x) and <v^2>_x; nothing else uses them
    drawn = {"position_velocity_time", "position_time", "position_v2_time"}
    for name in drawn:
        assert not np.array_equal(getattr(first, name), getattr(second, name))
    for field in fields(tallies.ShardTallies):
        if field.name not in drawn:
            assert np.array_equal(getattr(first, field.name), getattr(second, field.name))


def test_linear_bin_index_agrees_with_the_edges():
    bins = LinearBins(-6.0, 8.0, 0.25)
    edges = bins.edges
    assert bins.n == 56 and edges[-1] == pytest.approx(8.0)
    per_unit = bins.n / (edges[-1] - edges[0])
    values = np.concatenate(
        [edges, np.nextafter(edges, -np.inf), np.random.default_rng(0).uniform(-7, 9, 2000)]
    )
    for value in values:
        expected = int(np.searchsorted(edges, value, side="right"))
        assert step_tallies._linear_bin_index(value, edges[0], per_unit, bins.n, edges) == expected
    assert np.isneginf(bins.lower[0]) and np.isposinf(bins.upper[-1])
