"""P(x, v) and the flights between collisions against the exact solution at r = 1/2.

P(x, v) of eqs. (fpsol), (psi), (weightfunc2), averaged over each cell of (x, v) by
Gauss-Legendre quadrature, against the simulated time-weighted P(x, v) (drawn on each
step's bridge), cell by cell, with the scatter between shards (sign-flip chi^2 and worst
cell at the 1e-3 level, as for P(0, v)); and the mean flight time between collisions
against 1/I, I = 1/3 the exact collision rate, eq. (collrate).  Seeds are fixed.
"""

from fractions import Fraction

import numpy as np
import pytest
from shard_statistics import simulate_shards

from bouncing_ball import exact
from bouncing_ball.bins import LinearBins
from bouncing_ball.estimators import position_moments_summary
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.validation import sign_flip_test

R = Fraction(1, 2)
SHARDS = 16
SHARD_TIME = 1.0e5
SEED = 17
VELOCITY_BINS = LinearBins(-2.5, 3.5, 0.5)
# the lower edges of the x bins compared (default position bins: 5 per decade), from near
# the floor (x^(1/3) ~ the cell's width in v) to the tail
X_LOWER = (0.1, 0.630957, 2.51189, 10.0)

_X_NODES, _X_WEIGHTS = np.polynomial.legendre.leggauss(3)
_V_NODES, _V_WEIGHTS = np.polynomial.legendre.leggauss(4)


def _cell_average(x_lo, x_hi, v_lo, v_hi):
    """(1 / area) int int P(x, v) dx dv: Gauss-Legendre in ln x (3 nodes) and v (4 nodes)."""
    half_ln = 0.5 * np.log(x_hi / x_lo)
    x = np.exp(0.5 * np.log(x_hi * x_lo) + half_ln * _X_NODES)
    v = 0.5 * (v_hi + v_lo) + 0.5 * (v_hi - v_lo) * _V_NODES
    values = exact.distribution(x[:, None], v[None, :], R)
    integral = half_ln * 0.5 * (v_hi - v_lo) * (_X_WEIGHTS * x) @ values @ _V_WEIGHTS
    return integral / ((x_hi - x_lo) * (v_hi - v_lo))


@pytest.fixture(scope="module")
def shards():
    return simulate_shards({R: SHARD_TIME}, SHARDS, SEED, velocity_bins=VELOCITY_BINS)[R]


def test_distribution_matches_the_exact_solution_cell_by_cell(shards):
    """Smallest error rejected: P(x, v) scaled by 1.02 (checked here on the same shards,
    p < 1e-3)."""
    bins = shards[0].position_bins
    rows = [int(np.argmin(np.abs(bins.lower - lo))) for lo in X_LOWER]
    assert np.allclose(bins.lower[rows], X_LOWER, rtol=1e-5)
    columns = np.arange(1, VELOCITY_BINS.n + 1)  # the finite v bins
    v_lower, v_upper = VELOCITY_BINS.lower[columns], VELOCITY_BINS.upper[columns]
    expected = np.array(
        [
            [
                _cell_average(bins.lower[i], bins.upper[i], lo, hi)
                for lo, hi in zip(v_lower, v_upper)
            ]
            for i in rows
        ]
    )
    area = np.outer(bins.upper[rows] - bins.lower[rows], v_upper - v_lower)
    per_shard = np.stack(
        [s.position_velocity_time[np.ix_(rows, columns)] / (s.time * area) for s in shards]
    )
    error = per_shard.std(axis=0, ddof=1) / np.sqrt(SHARDS)
    assert np.median(error / expected) < 0.015, "run too short for a sharp test"
    deviations = (per_shard - expected).reshape(SHARDS, -1)
    chi2_per_dof, p_chi2, p_worst = sign_flip_test(deviations)
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/dof = {chi2_per_dof:.3f} (p = {p_chi2:.4f}), worst cell p = {p_worst:.4f}; "
        f"z = {np.round((per_shard.mean(axis=0) - expected) / error, 1)}"
    )
    _, p_wrong, _ = sign_flip_test((per_shard - 1.02 * expected).reshape(SHARDS, -1))
    assert p_wrong < 1e-3


def test_mean_flight_time_is_one_over_the_collision_rate(shards):
    """Within 3 standard errors.  Smallest error rejected: 2% (relative error below 0.5%,
    asserted; z = 4)."""
    summary = position_moments_summary(shards, R, solved_outgoing_density(R)).iloc[0]
    expected = 1.0 / exact.position_moments(R)["collision_rate"]  # 3
    value, error = summary.mean_flight_time, summary.mean_flight_time_err
    assert error / expected <= 0.005, "run too short for a sharp test"
    z = (value - expected) / error
    assert abs(z) < 3.0, f"mean flight time {value} +- {error}, exact 1/I = {expected}, z = {z:.2f}"
    # a flight is counted at the collision that ends it: all but at most one per shard
    assert summary.flights >= summary.collisions - SHARDS
