"""The control variates of the moments at r = 1/2 (tallies.MOMENT_CONTROL_SUMS, corrected
by estimators.position_moments_summary): every sum has mean 0 under the simulated process,
and the corrected <x>, Delta x, I and <T> agree with the exact values of eq. (xandDeltax)
(<T> = 1 / I), <T^2> with the solver's, each with a smaller error than the plain estimate.

64 shards, as in the default run: the corrected moments use all of MOMENT_CONTROLS (they
need SHARDS_PER_CONTROL x 18 = 54 shards or more), fitted as in the default run.  Seed fixed, so the outcome is deterministic.
"""

from fractions import Fraction

import numpy as np
import pytest
from exact_results import TIME_AVERAGES
from shard_statistics import simulate_shards

from bouncing_ball import flight_time, solver
from bouncing_ball.estimators import position_moments_summary
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.tallies import MOMENT_CONTROL_SUMS, MOMENT_CONTROLS, SHARDS_PER_CONTROL

R = Fraction(1, 2)
SHARDS = 64
SHARD_TIME = 1.5e5
SEED = 20261125
# the largest relative standard error of each corrected moment the test accepts: a bias of 4
# times this is rejected (z = 4 against the |z| < 3 of the test)
MAX_RELATIVE_ERROR = {
    "mean_x": 0.0008,
    "delta_x": 0.0035,
    "collision_rate": 0.0008,
    "mean_flight_time": 0.0008,
    "flight_time_second_moment": 0.0008,
}


def _expected(quantity):
    if quantity == "mean_flight_time":  # the mean time between collisions
        return 1.0 / TIME_AVERAGES[R]["collision_rate"]
    if quantity == "flight_time_second_moment":
        return flight_time.flight_time_second_moment(solver.solve_outgoing_speed_density(0.5))
    return TIME_AVERAGES[R][quantity]


@pytest.fixture(scope="module")
def shards():
    assert SHARDS_PER_CONTROL * len(MOMENT_CONTROLS) <= SHARDS  # all, not RATE_CONTROLS
    return simulate_shards({R: SHARD_TIME}, SHARDS, SEED)[R]


def _per_time(shards):
    return np.array([[getattr(s, name) / s.time for name in MOMENT_CONTROL_SUMS] for s in shards])


@pytest.mark.parametrize("name", MOMENT_CONTROL_SUMS)
def test_every_control_sum_has_mean_zero(shards, name):
    """Each sum over a shard's steps, per unit time: its mean over the shards within 4 of its
    standard errors of 0 (14 sums: a false alarm about 2e-3 of the time with normal sums).
    Smallest error rejected: a mean of 7 standard errors (z = 4 after a 3-sigma fluctuation
    towards 0)."""
    per_time = _per_time(shards)[:, MOMENT_CONTROL_SUMS.index(name)]
    z = per_time.mean() / (per_time.std(ddof=1) / np.sqrt(len(per_time)))
    assert abs(z) < 4.0, f"{name}: z = {z:.2f}"


@pytest.mark.parametrize("quantity", list(MAX_RELATIVE_ERROR))
def test_corrected_moments_match_exact_values(shards, quantity):
    """Each corrected moment within 3 of its errors of the exact value, and its error below
    the plain estimate's.  Smallest error rejected (z = 4, relative errors below
    MAX_RELATIVE_ERROR, asserted): 0.32% in <x>, I, <T> and <T^2>, 1.4% in Delta x."""
    summary = position_moments_summary(shards, R, solved_outgoing_density(R)).iloc[0]
    value, error = summary[f"{quantity}_controlled"], summary[f"{quantity}_controlled_err"]
    expected = _expected(quantity)
    assert error / expected <= MAX_RELATIVE_ERROR[quantity], "run too short for a sharp test"
    z = (value - expected) / error
    assert abs(z) < 3.0, f"{quantity} = {value} +- {error}, exact {expected}, z = {z:.2f}"
    assert error < summary[f"{quantity}_err"]
