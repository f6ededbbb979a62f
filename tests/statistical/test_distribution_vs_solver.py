"""P(x) and P(x, v) at r = 0.25 and 0.75, where the paper has no exact solution, from
the solver's P(0, v) (w(F) of eq. (weightfunc), P(x) of eq. (P(x)1), P(x, v) of eq. (fpsol))
against the simulation: P(x) on the simulation's x bins, P(x, v) on its cells of x bin x v bin
(v bins of 0.5 at r = 0.25, 1 at r = 0.75, where the distribution is wider), in every bin or cell
with at least 1e-3 of the recorded time.  chi^2 per bin and the worst bin against their
sign-flip null distributions at the 1e-3 level, and the same data reject each prediction scaled
by 1.01 (p < 1e-3).  r = 1/2 against the exact solution is test_distribution_and_flights.py
(P(x, v)) and test_simulation_exact.py (P(x)).  The solver's error (~1e-8 and below) is
negligible against the simulation's (~1e-3); seeds are fixed (solver_runs.py).
"""

import numpy as np
import pytest
from distribution_support import build
from solver_runs import MINIMUM_TIME_FRACTION, SHARDS, assert_agrees, shards, times

from bouncing_ball import distribution
from bouncing_ball.validation import sign_flip_test

RESTITUTIONS = [0.25, 0.75]
# v bins of the simulation joined per cell, per r
JOINED_VELOCITY_BINS = {0.25: 1, 0.75: 2}
# the x bins of P(x, v) start here: below, the cell averages are not checked against an
# independent computation (distribution.distribution_cell_average); this leaves out 10 cells
# with x in [1e-3, 1e-2) at r = 0.25 and none at r = 0.75
LOWEST_CELL_X = 0.01
SPEED_NODES = 4  # per panel in v: good to 1e-7 (tests/unit/test_distribution_cells.py)


def _position_bins(run):
    """The finite x bins with at least MINIMUM_TIME_FRACTION of the time, and each shard's P(x)."""
    bins = run[0].position_bins
    fraction = sum(s.position_time for s in run) / times(run).sum()
    usable = np.isfinite(bins.upper) & (bins.lower > 0.0) & (fraction >= MINIMUM_TIME_FRACTION)
    lower, upper = bins.lower[usable], bins.upper[usable]
    per_shard = np.stack([s.position_time[usable] / (s.time * (upper - lower)) for s in run])
    return lower, upper, per_shard


@pytest.fixture(scope="module", params=RESTITUTIONS, ids=str)
def position(request):
    r = request.param
    lower, upper, per_shard = _position_bins(shards(r))
    return r, per_shard, distribution.position_bin_average(lower, upper, build(r)[1])


@pytest.fixture(scope="module", params=RESTITUTIONS, ids=str)
def cells(request):
    """r, each shard's P(x, v) in the compared cells, and the solver's cell averages."""
    r = request.param
    run = shards(r)
    x_bins, v_bins = run[0].position_bins, run[0].velocity_bins
    join = JOINED_VELOCITY_BINS[r]
    columns = np.arange(1, v_bins.n + 1).reshape(-1, join)  # the finite v bins, joined
    v_lower, v_upper = v_bins.lower[columns[:, 0]], v_bins.upper[columns[:, -1]]
    in_cell = np.stack([s.position_velocity_time[:, columns].sum(axis=-1) for s in run])
    fraction = in_cell.sum(axis=0) / times(run).sum()
    rows = np.isfinite(x_bins.upper) & (x_bins.lower >= LOWEST_CELL_X * (1 - 1e-9))
    ix, iv = np.nonzero(rows[:, None] & (fraction >= MINIMUM_TIME_FRACTION))
    x_lower, x_upper = x_bins.lower[ix], x_bins.upper[ix]
    area = (x_upper - x_lower) * (v_upper[iv] - v_lower[iv])
    per_shard = in_cell[:, ix, iv] / (times(run)[:, None] * area)
    expected = distribution.distribution_cell_average(
        x_lower, x_upper, v_lower[iv], v_upper[iv], build(r)[1], speed_nodes=SPEED_NODES
    )
    return r, per_shard, expected


def test_position_density_agrees(position):
    """Smallest error rejected: P(x) scaled by 1.01 (the power test below)."""
    r, per_shard, expected = position
    error = per_shard.std(axis=0, ddof=1) / np.sqrt(SHARDS)
    assert len(expected) >= 15, "too few populated bins for a meaningful chi^2"
    assert np.median(error / expected) < 0.005, "run too short for a sharp test"
    assert_agrees(per_shard, expected)


def test_position_density_detects_a_one_percent_error(position):
    """The solver's P(x) scaled by 1.01 is rejected by the same shards, p < 1e-3."""
    _, per_shard, expected = position
    _, p_chi2, _ = sign_flip_test(per_shard - 1.01 * expected)
    assert p_chi2 < 1e-3


def test_distribution_agrees_cell_by_cell(cells):
    """Smallest error rejected: P(x, v) scaled by 1.01 (the power test below)."""
    r, per_shard, expected = cells
    error = per_shard.std(axis=0, ddof=1) / np.sqrt(SHARDS)
    assert len(expected) >= 100, "too few populated cells"
    assert np.median(error / expected) < 0.02, "run too short for a sharp test"
    assert_agrees(per_shard, expected)


def test_distribution_detects_a_one_percent_error(cells):
    """The solver's P(x, v) scaled by 1.01 is rejected by the same shards, p < 1e-3."""
    _, per_shard, expected = cells
    _, p_chi2, _ = sign_flip_test(per_shard - 1.01 * expected)
    assert p_chi2 < 1e-3
