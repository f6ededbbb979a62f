"""The P(x) and <v^2>_x tally of one step against the bridge law, integrated exactly.

Given both ends of a step, x(t) is Gaussian about the mean path m(t) with variance
Var[x(t) | ends] (``free_flight``), so the expected time the step spends in a bin
[lo, hi) is int_0^tau (Phi((hi - m) / sd) - Phi((lo - m) / sd)) dt, and the expected
int v^2 dt there is the same integral of E[v(t)^2 1[lo <= x(t) < hi] | ends], which the
truncated moments of normal_1 give in closed form (``bridge_sample``'s factorisation).
The loop's tally of a step is its mean-path assignment plus the bridge correction of one
point (``simulation``'s module docstring): its mean over many points must be that, within
a z-score of the points' scatter, on a long step where the mean path alone is off by
many of those z (so the test fails without the correction).  A step cut by a collision
keeps its mean path (the collision is placed on it), with crossings solved to ~1e-9.
"""

import math

import numpy as np
import pytest
from numba import njit
from scipy import integrate, optimize, special

from bouncing_ball.free_flight import (
    bridge_sample,
    bridge_speed_squared_given_position,
    cubic_slope,
    cubic_value,
    first_crossing_time,
    hermite_cubic,
    quintic_antiderivative_value,
    speed_squared_coefficients,
)
from bouncing_ball.settings import DEFAULT_POSITION_BINS
from bouncing_ball.simulation.step_tallies import (
    _bin_index,
    _bridge_correction,
    _tally_step,
    _walked_bin_index,
    floor_stratum_end,
)

BINS = DEFAULT_POSITION_BINS  # 1e-3 to 1e3: the narrow bins near the floor this step crosses
EDGES = BINS.edges
LOWER = np.concatenate(([-np.inf], EDGES))
UPPER = np.concatenate((EDGES, [np.inf]))
POINTS = 400_000
Z = 5.0  # 17 visited bins, two quantities: |z| < 5 fails by chance ~2e-5 (a fixed seed)


@njit(cache=True)
def _one_step(a, dt, tau, x_tau, v_tau, k, edges, lower, upper, points, seed):
    """The loop's tally of one step (its ``_tally_step``, ``_walked_bin_index`` and
    ``_bridge_correction``), the assignment once and the correction for ``points`` bridge
    points: (assignment time, assignment v^2, and per bin the mean and mean square of the
    correction of the time and of v^2, and the fraction of points that corrected it)."""
    np.random.seed(seed)
    n = edges.shape[0] + 1
    time_in = np.zeros(n)
    v2_in = np.zeros(n)
    moments = np.zeros((5, n))
    a0, a1, a2, a3 = a
    # the assignment does not depend on s; each point's bin k_s does
    _tally_step(a, dt, tau, x_tau, v_tau, k, 0.0, 0.0, False, edges, lower, upper, time_in, v2_in)
    scratch_time = np.zeros(n)
    scratch_v2 = np.zeros(n)
    for _ in range(points):
        s = np.random.random() * tau
        normal_1 = np.random.standard_normal()
        normal_2 = np.random.standard_normal()
        x_s, v_s = bridge_sample(a0, a1, a2, a3, dt, s, normal_1, normal_2)
        k_end, k_s, _ = _tally_step(
            a, dt, tau, x_tau, v_tau, k, s, s, False, edges, lower, upper, scratch_time, scratch_v2
        )
        x_cell = _walked_bin_index(x_s, k_s, lower, upper)
        if x_cell != k_s:
            scratch_time[:] = 0.0
            scratch_v2[:] = 0.0
            _bridge_correction(
                a1, a2, a3, dt, tau, s, normal_1, k_s, x_cell, scratch_time, scratch_v2
            )
            for j in (x_cell, k_s):
                moments[0, j] += scratch_time[j]
                moments[1, j] += scratch_time[j] ** 2
                moments[2, j] += scratch_v2[j]
                moments[3, j] += scratch_v2[j] ** 2
                moments[4, j] += 1.0
    return time_in, v2_in, moments / points


def _bridge_law(a, dt, tau, lo, hi, start=0.0):
    """Expected time in [lo, hi) and int v^2 dt there over [start, tau], given the ends."""

    def parts(t):
        u = t / dt
        w = max(u * (1.0 - u), 0.0)
        m = cubic_value(*a, t)
        slope = cubic_slope(a[1], a[2], a[3], t)
        sd_x = math.sqrt(2.0 / 3.0) * dt * w * math.sqrt(dt * w)
        b1 = math.sqrt(dt * w) * math.sqrt(1.5) * (1.0 - 2.0 * u)  # v = m' + b1 n1 + b2 n2
        b2_squared = 0.5 * dt * w
        if sd_x == 0.0:
            inside = float(lo <= m < hi)
            return inside, inside * (slope * slope + b1 * b1 + b2_squared)
        alpha = (lo - m) / sd_x if np.isfinite(lo) else -np.inf
        beta = (hi - m) / sd_x if np.isfinite(hi) else np.inf
        p0 = special.ndtr(beta) - special.ndtr(alpha)  # truncated moments of n1
        phi_a = 0.0 if np.isinf(alpha) else math.exp(-0.5 * alpha * alpha) / math.sqrt(2 * math.pi)
        phi_b = 0.0 if np.isinf(beta) else math.exp(-0.5 * beta * beta) / math.sqrt(2 * math.pi)
        p1 = phi_a - phi_b
        p2 = p0 + (alpha * phi_a if phi_a else 0.0) - (beta * phi_b if phi_b else 0.0)
        v2 = slope * slope * p0 + 2.0 * slope * b1 * p1 + b1 * b1 * p2 + b2_squared * p0
        return p0, v2

    time = integrate.quad(lambda t: parts(t)[0], start, tau, limit=400, epsabs=1e-13)[0]
    v2 = integrate.quad(lambda t: parts(t)[1], start, tau, limit=400, epsabs=1e-13)[0]
    return time, v2


def _steps():
    """A long step through several bins (x from 0.02 to 0.44 and back to 0.1) and a step
    cut by a collision at the mean path's first zero."""
    long_dt = 1.2
    long = hermite_cubic(0.02, 1.6, 0.1, -0.9, long_dt)
    cut_dt = 0.3
    cut = hermite_cubic(0.05, -0.3, -0.04, -1.2, cut_dt)
    tau = first_crossing_time(*cut, cut_dt, -0.04)
    return {
        "long": (long, long_dt, long_dt, 0.1, -0.9),
        "collision": (cut, cut_dt, tau, 0.0, cubic_slope(cut[1], cut[2], cut[3], tau)),
    }


def test_a_step_tallies_the_bridge_law_exactly_in_expectation():
    a, dt, tau, x_tau, v_tau = _steps()["long"]
    k = _bin_index(a[0], math.log(EDGES[0]), BINS.n / math.log(EDGES[-1] / EDGES[0]), BINS.n, EDGES)
    time_in, v2_in, moments = _one_step(
        np.array(a), dt, tau, x_tau, v_tau, k, EDGES, LOWER, UPPER, POINTS, 3
    )
    # the assignment integrates E[v^2 | ends] over the step
    sq = speed_squared_coefficients(a[1], a[2], a[3], dt)
    assert v2_in.sum() == pytest.approx(quintic_antiderivative_value(*sq, tau), rel=1e-12)
    assert time_in.sum() == pytest.approx(tau, rel=1e-12)
    exact = np.array([_bridge_law(a, dt, tau, lo, hi) for lo, hi in zip(LOWER, UPPER)])
    assert exact[:, 0].sum() == pytest.approx(tau, rel=1e-9)
    visited = exact[:, 0] > 1e-6 * tau
    assert visited.sum() >= 3
    exact, time_in, v2_in = exact[visited], time_in[visited], v2_in[visited]
    moments = moments[:, visited]
    # the scatter of the points that corrected a bin; where fewer than ~30 did, at least
    # that of 3 such points (a Poisson upper bound when none did), each of the largest size
    # seen there (or tau, resp. tau times the bin's mean E[v^2 | x])
    fired = moments[4] * POINTS
    mean_speed_squared = exact[:, 1] / exact[:, 0]
    for column, assigned, (mean, square), size in (
        (0, time_in, (moments[0], moments[1]), np.full(len(fired), tau)),
        (1, v2_in, (moments[2], moments[3]), tau * mean_speed_squared),
    ):
        rms = np.sqrt(np.where(fired > 0, square * POINTS / np.maximum(fired, 1.0), 0.0))
        size = np.maximum(size, rms)
        variance = np.maximum(square - mean * mean, size * size * 3.0 / POINTS)
        error = np.sqrt(variance / POINTS)
        z = (assigned + mean - exact[:, column]) / error
        assert np.all(np.abs(z) < Z), np.round(z, 2)
        # the assignment alone is far off (the test fails without the correction)
        z_alone = (assigned - exact[:, column]) / error
        assert np.max(np.abs(z_alone)) > 10.0 * Z, np.round(z_alone, 1)


def test_speed_squared_given_position_averages_to_the_bridge_variance():
    """Averaged over normal_1 (Gauss-Hermite, exact for this quadratic), E[v^2 | x(t), ends]
    is E[v(t)^2 | ends] = m'(t)^2 + Var[v(t) | ends], the assignment's integrand."""
    nodes, weights = np.polynomial.hermite_e.hermegauss(6)
    weights = weights / weights.sum()
    dt = 0.7
    a = hermite_cubic(0.3, 0.4, 0.2, -1.1, dt)
    for t in (0.0, 0.1, 0.35, 0.6, dt):
        mean = sum(
            w * bridge_speed_squared_given_position(a[1], a[2], a[3], dt, t, n)
            for n, w in zip(nodes, weights)
        )
        sq = speed_squared_coefficients(a[1], a[2], a[3], dt)
        # S'(t) = d/dt t (s1 + t (s2 + ...)) is the integrand
        derivative = sum((j + 1) * c * t**j for j, c in enumerate(sq))
        assert mean == pytest.approx(derivative, rel=1e-12, abs=1e-14)


def test_a_step_cut_by_a_collision_keeps_its_mean_path():
    """The loop leaves a collision's step on the mean path its collision is placed on (no
    bridge correction; crossings by ``level_time``): its time and int E[v^2 | ends] dt per
    bin are those of m(t) on [0, tau], against crossings found by scipy's brentq."""
    a, dt, tau, x_tau, v_tau = _steps()["collision"]
    k = _bin_index(a[0], math.log(EDGES[0]), BINS.n / math.log(EDGES[-1] / EDGES[0]), BINS.n, EDGES)
    time_in = np.zeros(BINS.n + 2)
    v2_in = np.zeros(BINS.n + 2)
    k_end, _, _ = _tally_step(
        np.array(a),
        dt,
        tau,
        x_tau,
        v_tau,
        k,
        0.5 * tau,
        0.5 * tau,
        True,
        EDGES,
        LOWER,
        UPPER,
        time_in,
        v2_in,
    )
    assert k_end == 0
    sq = speed_squared_coefficients(a[1], a[2], a[3], dt)
    # the mean path falls monotonically here: one crossing per edge between m(0) and 0
    assert all(cubic_slope(a[1], a[2], a[3], t) < 0.0 for t in np.linspace(0.0, tau, 50))
    times = [0.0]
    for edge in EDGES[::-1]:
        if 0.0 < edge < a[0]:
            times.append(optimize.brentq(lambda t, e=edge: cubic_value(*a, t) - e, 0.0, tau))
    times.append(tau)
    bins = [k - j for j in range(len(times) - 1)]
    for j, (t0, t1) in zip(bins, zip(times[:-1], times[1:])):
        # level_time's crossings are good to ~1e-9 of the piece (tested at 1e-8)
        assert time_in[j] == pytest.approx(t1 - t0, abs=1e-8 * tau)
        expected = quintic_antiderivative_value(*sq, t1) - quintic_antiderivative_value(*sq, t0)
        assert v2_in[j] == pytest.approx(expected, abs=1e-8 * v2_in.sum())
    assert time_in.sum() == pytest.approx(tau, rel=1e-12)


@njit(cache=True)
def _floor_step_corrections(a, dt, tau, x_tau, v_tau, t_low, edges, lower, upper, draws, seed):
    """The loop's bridge correction of a step from the floor, per draw: with t_low < tau its
    two stratified points (``floor_stratum_end``: s in [t_low, tau] with weight tau - t_low,
    s in [0, t_low] with weight t_low), with t_low = tau one uniform point of weight tau.
    Returns per bin the mean and mean square over draws of the time and the v^2 moved."""
    np.random.seed(seed)
    n = edges.shape[0] + 1
    moments = np.zeros((4, n))
    scratch_time = np.zeros(n)
    scratch_v2 = np.zeros(n)
    step_time = np.zeros(n)
    step_v2 = np.zeros(n)
    for _ in range(draws):
        u = np.random.random()
        s, weight, s2, weight2 = u * tau, tau, u * tau, 0.0
        if t_low < tau:
            s, weight = t_low + u * (tau - t_low), tau - t_low
            s2, weight2 = np.random.random() * t_low, t_low
        _, k_s, k_s2 = _tally_step(
            a, dt, tau, x_tau, v_tau, 0, s, s2, False, edges, lower, upper, scratch_time, scratch_v2
        )
        step_time[:] = 0.0
        step_v2[:] = 0.0
        for point in range(2 if t_low < tau else 1):
            if point == 1:
                s, weight, k_s = s2, weight2, k_s2
            normal_1 = np.random.standard_normal()
            x_s, _ = bridge_sample(a[0], a[1], a[2], a[3], dt, s, normal_1, 0.0)
            x_cell = _walked_bin_index(x_s, k_s, lower, upper)
            if x_cell != k_s:
                _bridge_correction(
                    a[1], a[2], a[3], dt, weight, s, normal_1, k_s, x_cell, step_time, step_v2
                )
        moments[0] += step_time
        moments[1] += step_time**2
        moments[2] += step_v2
        moments[3] += step_v2**2
    return moments / draws


def test_a_step_from_the_floor_stratifies_its_bridge_points():
    """A long step from the floor (v_out = 4.8, the criterion's D ~ (v / c)^2 = 1.7) crosses
    the narrow bins near the floor in its first 0.003 time units.  With one uniform point, a
    point lands there rarely and then moves the whole step's tau V; the loop's two points,
    one in [0, t_low] and one in [t_low, tau] (``floor_stratum_end``), keep the tally exact
    in expectation (|z| < 5 against the bridge law in every bin the step visits, the time
    and the v^2 moved) and cut the per-draw variance of the v^2 moved in the bins below
    x = 0.01 at least tenfold (about 20-40 times here)."""
    dt = 1.73
    v0 = 4.81
    x1, v1 = 7.12175739315327, 3.638032257132148  # free_flight_step(0, v0, dt, 0.3, -0.2)
    a = np.array(hermite_cubic(0.0, v0, x1, v1, dt))
    t_low = floor_stratum_end(dt, 0.0, v0)
    assert t_low == pytest.approx(0.1 / v0) and t_low < dt
    assert floor_stratum_end(dt, 1e-3, v0) == dt and floor_stratum_end(0.01, 0.0, v0) == 0.01
    draws = 400_000
    stratified = _floor_step_corrections(a, dt, dt, x1, v1, t_low, EDGES, LOWER, UPPER, draws, 5)
    uniform = _floor_step_corrections(a, dt, dt, x1, v1, dt, EDGES, LOWER, UPPER, draws, 5)
    time_in = np.zeros(BINS.n + 2)
    v2_in = np.zeros(BINS.n + 2)
    _tally_step(a, dt, dt, x1, v1, 0, 0.0, 0.0, False, EDGES, LOWER, UPPER, time_in, v2_in)
    # the bins are crossed on time scales from 1e-4 to 1: integrated piece by piece, so that
    # quad resolves each crossing
    pieces = [0.0, 2e-4, 5e-4, 1e-3, 2e-3, 4e-3, 0.01, 0.03, 0.1, 0.3, 1.0, dt]
    exact = np.array(
        [
            np.sum(
                [_bridge_law(a, dt, t1, lo, hi, t0) for t0, t1 in zip(pieces[:-1], pieces[1:])],
                axis=0,
            )
            for lo, hi in zip(LOWER, UPPER)
        ]
    )
    assert exact[:, 0].sum() == pytest.approx(dt, rel=1e-6)
    visited = exact[:, 0] > 1e-7 * dt
    assert visited[2:6].all()
    for column, assigned in ((0, time_in), (1, v2_in)):
        mean, square = stratified[2 * column], stratified[2 * column + 1]
        error = np.sqrt(np.maximum(square - mean**2, 1e-30) / draws)
        z = ((assigned + mean - exact[:, column]) / error)[visited]
        assert np.all(np.abs(z) < Z), np.round(z, 2)
    # where a uniform point fired at all in these draws (in the lowest bins it is too rare)
    uniform_variance = uniform[3] - uniform[2] ** 2
    low = (UPPER <= 0.01 * (1 + 1e-9)) & visited & (uniform_variance > 0.0)
    assert low.sum() >= 2
    ratio = uniform_variance[low] / (stratified[3] - stratified[2] ** 2)[low]
    assert np.all(ratio > 10.0), np.round(ratio, 1)
