"""The CI-sized runs that P(x), P(x, v) and the flights are tested on against the solver
(test_distribution_vs_solver.py, test_flights_vs_solver.py): 16 shards per r at r = 0.25, 1/3,
1/2, 0.75, simulated once per pytest session and shared by both modules, with the selections of
bins both use."""

import functools
from fractions import Fraction

import numpy as np
from shard_statistics import simulate_shards

from bouncing_ball.bins import LinearBins
from bouncing_ball.validation import sign_flip_test

SHARDS = 16
SEED = 20061123
# recorded time per shard: each run rejects every prediction scaled by 1.01 (P(x), P(x, v),
# flight-time density) at p < 1e-3, with time to spare for the 60 s budget of these tests
SHARD_TIME = {0.25: 1.25e5, Fraction(1, 3): 1.0e5, Fraction(1, 2): 2.0e5, 0.75: 1.5e6}
# v of P(x, v): cells of 0.5 (tests may join neighbours; the outer v bins are not compared)
VELOCITY_BINS = LinearBins(-12.0, 12.0, 0.5)
# a time tally's bin or cell is compared when it holds this share of the recorded time (its
# standard error is then ~1% or less): the analogue of the 100 collisions of a count's bin
MINIMUM_TIME_FRACTION = 1e-3
MINIMUM_COUNT = 100  # a count's bin (flight times, return speeds) is compared from 100 on


@functools.cache
def _all_shards():
    return simulate_shards(SHARD_TIME, SHARDS, SEED, velocity_bins=VELOCITY_BINS)


def shards(r):
    """The run at r (one of SHARD_TIME), a list of ShardTallies."""
    return _all_shards()[r]


def times(run):
    return np.array([s.time for s in run])


def assert_agrees(per_shard, expected):
    """Shard-level values (shards x bins) agree with ``expected``: chi^2 and the worst bin
    against the sign-flip null (``validation.sign_flip_test``), p > 1e-3 each."""
    chi2_per_dof, p_chi2, p_worst = sign_flip_test(per_shard - expected)
    error = per_shard.std(axis=0, ddof=1) / np.sqrt(SHARDS)
    z = (per_shard.mean(axis=0) - expected) / error
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/dof = {chi2_per_dof:.3f} (p = {p_chi2:.4f}), worst p = {p_worst:.4f}, "
        f"{len(expected)} bins, z = {np.round(z, 1)}"
    )
