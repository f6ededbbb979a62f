"""The simulation against the paper's exact results at r = 1/2 and r = 1/3.

CI-sized runs (a few core-seconds per r) that are still sharp: the relative
standard error of <x>, Delta x and I is asserted to be 1% or less before the
3-sigma comparison is made.  Seeds are fixed, so the outcome is deterministic.
Run with the default config's criterion constant c and with the paper's c = 5.
"""

from fractions import Fraction

import numpy as np
import pytest
from exact_results import TIME_AVERAGES
from shard_statistics import CRITERION_C, outgoing_speed_bins, sign_flip_p_values, simulate_shards

from bouncing_ball import exact
from bouncing_ball.histograms import (
    position_histogram,
    position_moments_summary,
)

SHARDS = 16
SHARD_TIME = {Fraction(1, 2): 4.0e5, Fraction(1, 3): 7.0e5}
SEED = 20061121


# the default config's c, and the paper's c = 5 where that differs
CRITERIA = sorted({CRITERION_C, 5.0})


@pytest.fixture(scope="module", params=CRITERIA, ids=lambda c: f"c={c:g}")
def shards(request):
    return simulate_shards(SHARD_TIME, SHARDS, SEED, criterion_c=request.param)


@pytest.mark.parametrize("r", list(TIME_AVERAGES), ids=str)
@pytest.mark.parametrize("quantity", ["mean_x", "delta_x", "collision_rate"])
def test_moments_match_exact_values(shards, r, quantity):
    summary = position_moments_summary(shards[r], float(r)).iloc[0]
    value, error = summary[quantity], summary[f"{quantity}_err"]
    expected = TIME_AVERAGES[r][quantity]
    assert error / expected <= 0.01, "run too short for a sharp test"
    z = (value - expected) / error
    assert abs(z) < 3.0, f"{quantity} = {value} +- {error}, exact {expected}, z = {z:.2f}"


@pytest.mark.parametrize("r", list(TIME_AVERAGES), ids=str)
def test_collision_rate_with_control_variates_matches_exact_value(shards, r):
    """I corrected by the martingale control variates (the summary's
    collision_rate_controlled, histograms.control_variate_rate): the exact value within 3
    errors, an error smaller than the plain estimator's, at each c."""
    summary = position_moments_summary(shards[r], float(r)).iloc[0]
    value, error = summary["collision_rate_controlled"], summary["collision_rate_controlled_err"]
    expected = TIME_AVERAGES[r]["collision_rate"]
    z = (value - expected) / error
    assert abs(z) < 3.0, f"I = {value} +- {error}, exact {expected}, z = {z:.2f}"
    plain_error = summary["collision_rate_err"]
    assert error < plain_error, f"error {error:.3g} with the controls, {plain_error:.3g} without"


@pytest.mark.parametrize("r", list(TIME_AVERAGES), ids=str)
def test_exact_module_reproduces_paper_closed_forms(r):
    # the comparison values above, recomputed from P(x) of eq. (P(x)2)
    computed = exact.position_moments(r)
    assert computed["normalization"] == pytest.approx(1.0, rel=1e-9)
    for quantity, expected in TIME_AVERAGES[r].items():
        assert computed[quantity] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("r", list(TIME_AVERAGES), ids=str)
def test_outgoing_speed_density_chi_square(shards, r):
    """eq. (P(0,v)) with eq. (constants), no free parameter, for every bin with
    at least 100 collisions: chi^2 per bin and the worst bin, each against its
    sign-flip null distribution, at the 1e-3 level."""
    lower, upper, per_shard = outgoing_speed_bins(shards[r])
    deviations = per_shard - exact.outgoing_speed_bin_average(lower, upper, r)
    assert len(lower) >= 30, "too few populated bins for a meaningful chi^2"
    chi2_per_dof, p_chi2, p_worst = sign_flip_p_values(deviations)
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/dof = {chi2_per_dof:.3f} (p = {p_chi2:.4f}), worst bin p = {p_worst:.4f}"
    )


def _position_bins_up_to_50(table):
    return table[(table.x_lo >= 0.1 - 1e-12) & (table.x_lo < 50.0)]


def test_position_density_half(shards):
    """P(x) = (1/3) K0(sqrt(2x/3)) at r = 1/2, eq. (P(x)2), for x in [0.1, 50]."""
    r = Fraction(1, 2)
    table = _position_bins_up_to_50(position_histogram(shards[r]))
    expected = exact.position_bin_average(table.x_lo, table.x_hi, r)
    z = (table.px - expected) / table.px_err
    assert len(z) >= 10
    assert np.all(np.abs(z) < 3.0), f"z = {np.round(z.to_numpy(), 2)}"


def test_speed_squared_given_position_half(shards):
    """<v^2>_x of eq. (moment2) at r = 1/2 for x in [0.1, 50]: the worst bin
    against its sign-flip null at the 1e-3 level, errors below 2%."""
    r = Fraction(1, 2)
    table = _position_bins_up_to_50(position_histogram(shards[r]))
    assert float(np.max(table.v2_given_x_err / table.v2_given_x)) < 0.02
    rows = table.index.to_numpy()
    per_shard = np.stack([s.position_v2_time[rows] / s.position_time[rows] for s in shards[r]])
    expected = exact.speed_squared_given_position_bin_average(table.x_lo, table.x_hi, r)
    _, _, p_worst = sign_flip_p_values(per_shard - np.asarray(expected))
    assert p_worst > 1e-3, f"worst bin p = {p_worst:.4f}"
