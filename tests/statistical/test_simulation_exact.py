"""The simulation against the paper's exact results at r = 1/2 and r = 1/3.

CI-sized runs (16 shards per r) that are still sharp: each test asserts the errors its
power rests on before it compares, and names the smallest error it rejects.  Seeds are
fixed, so the outcome is deterministic.  Run with the default config's criterion constant c
at both r, and with the paper's c = 5 at r = 1/2.
"""

import functools
from fractions import Fraction

import numpy as np
import pytest
from exact_results import TIME_AVERAGES
from shard_statistics import CRITERION_C, outgoing_speed_bins, simulate_shards

from bouncing_ball import exact
from bouncing_ball.estimators import (
    outgoing_speed_histogram,
    position_histogram,
    position_moments_summary,
)
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.validation import sign_flip_test

SHARDS = 16
SHARD_TIME = {Fraction(1, 2): 4.0e5, Fraction(1, 3): 7.0e5}
SEED = 20061121
# the largest relative standard error of each time average that the test accepts: a bias
# of 4 times this is rejected (z = 4 against the |z| < 3 of the test)
MAX_RELATIVE_ERROR = {"mean_x": 0.006, "delta_x": 0.01, "collision_rate": 0.0025}
# P(0, v) scaled by 1 + this is rejected (r = 1/2 has fewer collisions: I = 1/3, not 3/4)
OUTGOING_SPEED_POWER = {Fraction(1, 2): 0.015, Fraction(1, 3): 0.01}


# the default config's c at both r, and the paper's c = 5 (where that differs) at r = 1/2: c
# enters the step rule alone (eq. (criterion)), whose form does not depend on r, and r = 1/2
# has every check (P(x) and <v^2>_x besides the moments and P(0, v)), so that a c = 5 run at
# r = 1/3 (the longer shards) repeats the c = 3 run's claims there
RESTITUTIONS_AT = {CRITERION_C: list(TIME_AVERAGES), 5.0: [Fraction(1, 2)]}
CRITERIA = sorted(RESTITUTIONS_AT)
CASES = [pytest.param(c, r, id=f"c={c:g}-{r}") for c in CRITERIA for r in RESTITUTIONS_AT[c]]


@functools.cache
def _runs(c):
    """{r: shards} at criterion constant c, simulated once per session."""
    times = {r: SHARD_TIME[r] for r in RESTITUTIONS_AT[c]}
    return simulate_shards(times, SHARDS, SEED, criterion_c=c)


@pytest.mark.parametrize(("c", "r"), CASES)
@pytest.mark.parametrize("quantity", ["mean_x", "delta_x", "collision_rate"])
def test_moments_match_exact_values(c, r, quantity):
    """<x>, Delta x and I of eq. (xandDeltax) within 3 standard errors.  Smallest error
    rejected: 4 times MAX_RELATIVE_ERROR (asserted), 2.4% in <x>, 4% in Delta x, 1% in I."""
    shards = _runs(c)
    summary = position_moments_summary(shards[r], r, solved_outgoing_density(r)).iloc[0]
    value, error = summary[quantity], summary[f"{quantity}_err"]
    expected = TIME_AVERAGES[r][quantity]
    assert error / expected <= MAX_RELATIVE_ERROR[quantity], "run too short for a sharp test"
    z = (value - expected) / error
    assert abs(z) < 3.0, f"{quantity} = {value} +- {error}, exact {expected}, z = {z:.2f}"


@pytest.mark.parametrize(("c", "r"), CASES)
def test_collision_rate_with_control_variates_matches_exact_value(c, r):
    """I corrected by the martingale control variates (the summary's
    collision_rate_controlled, estimators.control_variate_rate): the exact value within 3
    errors, an error smaller than the plain estimator's, at each c.  Smallest error rejected:
    0.6% (relative error at most 0.15%, asserted; z = 4)."""
    shards = _runs(c)
    summary = position_moments_summary(shards[r], r, solved_outgoing_density(r)).iloc[0]
    value, error = summary["collision_rate_controlled"], summary["collision_rate_controlled_err"]
    expected = TIME_AVERAGES[r]["collision_rate"]
    assert error / expected <= 0.0015, "run too short for a sharp test"
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


@pytest.mark.parametrize(("c", "r"), CASES)
def test_outgoing_speed_density_chi_square(c, r):
    """eq. (P(0,v)) with eq. (constants), no free parameter, for every bin with
    at least 100 collisions: chi^2 per bin and the worst bin, each against its
    sign-flip null distribution, at the 1e-3 level.  Smallest error rejected: P(0, v)
    scaled by 1.01 at r = 1/3, by 1.015 at r = 1/2 (the power test below)."""
    shards = _runs(c)
    lower, upper, per_shard = outgoing_speed_bins(shards[r])
    deviations = per_shard - exact.outgoing_speed_bin_average(lower, upper, r)
    assert len(lower) >= 30, "too few populated bins for a meaningful chi^2"
    chi2_per_dof, p_chi2, p_worst = sign_flip_test(deviations)
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/dof = {chi2_per_dof:.3f} (p = {p_chi2:.4f}), worst bin p = {p_worst:.4f}"
    )


@pytest.mark.parametrize(("c", "r"), CASES)
def test_outgoing_speed_density_rejects_a_small_error(c, r):
    """The power of the chi^2 above, from the same run's shards: eq. (P(0,v)) scaled by
    1 + OUTGOING_SPEED_POWER (1% at r = 1/3, 1.5% at r = 1/2) is rejected, p < 1e-3."""
    shards = _runs(c)
    lower, upper, per_shard = outgoing_speed_bins(shards[r])
    wrong = (1.0 + OUTGOING_SPEED_POWER[r]) * exact.outgoing_speed_bin_average(lower, upper, r)
    _, p_chi2, _ = sign_flip_test(per_shard - wrong)
    assert p_chi2 < 1e-3


@pytest.mark.parametrize(("c", "r"), CASES)
def test_outgoing_speed_density_with_the_return_law_control(c, r):
    """P(0, v) corrected by its return-law control (``p0v_controlled``,
    estimators.return_law_prediction, which uses eq. (kernel3) and the solver's P(0, u) only
    to weigh u inside a fine bin) against eq. (P(0,v)) in every bin with 0.01 <= v <= 5:
    every |z| < 5 (with 16 shards z is t-distributed with 15 degrees of freedom: a false
    alarm in about 0.5% of runs over 27 bins), and the worst relative error at most half
    the plain estimator's.  Smallest error rejected: 5 times the largest relative error
    (asserted at most 1%), 5%."""
    shards = _runs(c)
    table = outgoing_speed_histogram(shards[r], r, solved_outgoing_density(r))
    band = table[(table.v >= 0.01) & (table.v <= 5.0)]
    truth = exact.outgoing_speed_bin_average(band.v_lo.to_numpy(), band.v_hi.to_numpy(), r)
    relative = (band.p0v_controlled_err / band.p0v_controlled).to_numpy()
    plain = (band.p0v_err / band.p0v).to_numpy()
    assert relative.max() <= 0.01, f"run too short for a sharp test: {relative.max():.4f}"
    assert relative.max() <= 0.5 * plain.max(), (relative.max(), plain.max())
    z = (band.p0v_controlled.to_numpy() - truth) / band.p0v_controlled_err.to_numpy()
    assert np.abs(z).max() < 5.0, np.round(z, 2)


def _position_bins_up_to_50(table):
    return table[(table.x_lo >= 0.1 - 1e-12) & (table.x_lo < 50.0)]


def _assert_sharp(table, quantity):
    """The relative errors the docstrings' power rests on: below 0.5% in the bins below
    x = 10, below 2% above."""
    relative = (table[f"{quantity}_err"] / table[quantity]).to_numpy()
    below = table.x_hi.to_numpy() <= 10.0 * (1.0 + 1e-9)
    assert np.max(relative[below]) < 0.005 and np.max(relative) < 0.02, (
        f"run too short for a sharp test: {np.round(relative, 4)}"
    )


@pytest.mark.parametrize("c", CRITERIA, ids=lambda c: f"c={c:g}")
def test_position_density_half(c):
    """P(x) = (1/3) K0(sqrt(2x/3)) at r = 1/2, eq. (P(x)2), for x in [0.1, 50]: every bin
    within 3 standard errors.  Smallest error rejected (z = 4): 2% in any one bin below
    x = 10, 8% in one above (``_assert_sharp``)."""
    shards = _runs(c)
    r = Fraction(1, 2)
    table = _position_bins_up_to_50(position_histogram(shards[r]))
    _assert_sharp(table, "px")
    expected = exact.position_bin_average(table.x_lo, table.x_hi, r)
    z = (table.px - expected) / table.px_err
    assert len(z) >= 10
    assert np.all(np.abs(z) < 3.0), f"z = {np.round(z.to_numpy(), 2)}"


@pytest.mark.parametrize("c", CRITERIA, ids=lambda c: f"c={c:g}")
def test_speed_squared_given_position_half(c):
    """<v^2>_x of eq. (moment2) at r = 1/2 for x in [0.1, 50]: the worst bin
    against its sign-flip null at the 1e-3 level.  Smallest error rejected (z = 4): 2% in
    any one bin below x = 10, 8% in one above (``_assert_sharp``)."""
    shards = _runs(c)
    r = Fraction(1, 2)
    table = _position_bins_up_to_50(position_histogram(shards[r]))
    _assert_sharp(table, "v2_given_x")
    rows = table.index.to_numpy()
    per_shard = np.stack([s.position_v2_time[rows] / s.position_time[rows] for s in shards[r]])
    expected = exact.speed_squared_given_position_bin_average(table.x_lo, table.x_hi, r)
    _, _, p_worst = sign_flip_test(per_shard - np.asarray(expected))
    assert p_worst > 1e-3, f"worst bin p = {p_worst:.4f}"


# near the floor: the x bins from 1e-3 to 0.1 (the bins, r's scales, reach further down, where
# few steps put their time)
FLOOR_REGION_START, FLOOR_REGION = 1.0e-3, 0.1
# P(x) and <v^2>_x there scaled by 1 + this are rejected
FLOOR_REGION_POWER = 0.015


@pytest.mark.parametrize(("c", "r"), CASES)
@pytest.mark.parametrize("quantity", ["px", "v2_given_x"])
def test_position_near_the_floor_matches_exact_values(c, r, quantity):
    """P(x) of eq. (P(x)2) and <v^2>_x of eq. (moment2) in the bins below x = 0.1, where a
    step that starts or ends at the floor puts its time: z = (simulation - exact) / error per
    bin, chi^2 per bin and the worst bin against their sign-flip null distributions at the
    1e-3 level.  Smallest error rejected: 1.5% in every bin (checked here on the same
    shards: p < 1e-3), or 2% in any one bin (relative errors below 0.5%, asserted; z = 4)."""
    shards = _runs(c)
    table = position_histogram(shards[r])
    table = table[
        (table.x_lo >= FLOOR_REGION_START * (1.0 - 1e-9))
        & (table.x_hi <= FLOOR_REGION * (1.0 + 1e-9))
    ]
    assert len(table) >= 8, "too few bins below x = 0.1"
    error = table[f"{quantity}_err"] / table[quantity]
    assert float(np.max(error)) < 0.005, "run too short for a sharp test"
    rows = table.index.to_numpy()
    lower, upper = table.x_lo.to_numpy(), table.x_hi.to_numpy()
    if quantity == "px":
        per_shard = np.stack(
            [s.position_time[rows] / (s.time * (upper - lower)) for s in shards[r]]
        )
        expected = exact.position_bin_average(lower, upper, r)
    else:
        per_shard = np.stack([s.position_v2_time[rows] / s.position_time[rows] for s in shards[r]])
        expected = exact.speed_squared_given_position_bin_average(lower, upper, r)
    expected = np.asarray(expected, dtype=float)
    chi2_per_bin, p_chi2, p_worst = sign_flip_test(per_shard - expected)
    z = (table[quantity].to_numpy() - expected) / table[f"{quantity}_err"].to_numpy()
    assert p_chi2 > 1e-3 and p_worst > 1e-3, (
        f"chi^2/n = {chi2_per_bin:.2f} (p = {p_chi2:.4f}), worst p = {p_worst:.4f}; "
        f"z = {np.round(z, 2)}"
    )
    _, p_wrong, _ = sign_flip_test(per_shard - (1.0 + FLOOR_REGION_POWER) * expected)
    assert p_wrong < 1e-3
