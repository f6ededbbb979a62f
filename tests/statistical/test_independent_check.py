"""The independent check rejects two deliberately wrong simulations at r = 1/2.

The moments table and the validation rows judge agreement on estimators whose expectation is
the simulated process's own (plain tallies, and the martingale-controlled ``*_martingale``);
the estimates corrected with the flight-law and return-law controls of eq. (kernel3)
(``*_controlled``) lean on the theory under test.  Two simulations that are wrong on purpose,
both judged as r = 1/2 against the exact results:

- the bounce: run at r' = 1/2 + 1e-3 (<x> about +0.4 %, I about -0.4 %);
- the flight: a step rule with c = 0.5 of eq. (criterion), below ``settings.MIN_CRITERION_C``
  (the settings are built valid and c set on a copy: the public check stays as it is).

The independent estimates reject both (|z| > 5 where the bias is about 7 to 18 of their
errors; P(0, v)'s sign-flip p at its floor).  What the eq. (kernel3) estimates do: under the
bounce error they move as far as the independent ones, with a smaller error (a larger z);
under the flight error they exaggerate it (I +7 % against the simulation's own +2 %).
Seed fixed: the outcome is deterministic.
"""

import copy
from concurrent.futures import ProcessPoolExecutor
from fractions import Fraction

import numpy as np
import pytest
from exact_results import TIME_AVERAGES
from shard_statistics import DEFAULT_SETTINGS

from bouncing_ball.estimators import outgoing_speed_histogram, position_moments_summary
from bouncing_ball.settings import MIN_CRITERION_C
from bouncing_ball.simulation import shard_seed_sequence, simulate_shard
from bouncing_ball.solver import solved_outgoing_density
from bouncing_ball.validation import outgoing_speed_checks, shard_ratios

HALF = Fraction(1, 2)
SHARDS = 64  # as the default run: all of MOMENT_CONTROLS and the flight-law controls
SEED = 77
# the wrong simulations: (r simulated, c of eq. (criterion), recorded time per shard)
WRONG = {
    "bounce": (0.5 + 1e-3, DEFAULT_SETTINGS.criterion_c, 2.4e5),
    "flight": (0.5, 0.5, 6.0e4),
}
# |z| the independent estimates must exceed: the biases are about 7-18 of their errors
REJECTED = 5.0


def _shard(arguments):
    restitution, criterion_c, shard_time, shard = arguments
    settings = copy.copy(DEFAULT_SETTINGS.replace(shard_time=shard_time))
    object.__setattr__(settings, "criterion_c", criterion_c)  # past the public check
    return simulate_shard(restitution, shard_seed_sequence(SEED, "0.5", shard), settings)


@pytest.fixture(scope="module", params=sorted(WRONG))
def wrong(request):
    restitution, criterion_c, shard_time = WRONG[request.param]
    with ProcessPoolExecutor(2) as pool:
        shards = list(
            pool.map(_shard, [(restitution, criterion_c, shard_time, k) for k in range(SHARDS)])
        )
    return (
        request.param,
        shards,
        position_moments_summary(shards, HALF, solved_outgoing_density(HALF)).iloc[0],
    )


def _z(summary, quantity, suffix):
    truth = TIME_AVERAGES[HALF][quantity]
    value, error = summary[f"{quantity}{suffix}"], summary[f"{quantity}{suffix}_err"]
    return (value - truth) / error, value / truth - 1.0


def test_the_flight_error_is_below_the_public_bound():
    assert WRONG["flight"][1] < MIN_CRITERION_C


def test_the_independent_moments_reject_the_wrong_simulation(wrong):
    _, _, summary = wrong
    assert summary["kernel3_controls"]  # the eq. (kernel3) columns are there to compare
    for quantity in ("collision_rate", "mean_x"):
        z, _ = _z(summary, quantity, "_martingale")
        assert abs(z) > REJECTED, (quantity, z)


def test_the_plain_p0v_rejects_the_wrong_simulation(wrong):
    """chi^2/n of the plain P(0, v) bins against the exact bin averages, and its sign-flip p at
    the floor of 10^4 flips."""
    _, shards, _ = wrong
    rows = {
        row["check"]: row
        for row in outgoing_speed_checks(
            outgoing_speed_histogram(shards, HALF, solved_outgoing_density(HALF)),
            HALF,
            len(shards),
            per_shard=shard_ratios(shards),
        )
    }
    assert rows["p0v_chi2_per_bin"]["value"] > 2.0
    assert rows["p0v_chi2_per_bin"]["p_sign_flip"] < 1e-3


def test_what_the_kernel3_estimates_do(wrong):
    """The bounce error: the eq. (kernel3) I moves as far as the independent one (within 3 of
    its errors) and claims a larger z.  The flight error: the eq. (kernel3) I is off by more
    than twice the simulation's own bias."""
    name, _, summary = wrong
    z, shift = _z(summary, "collision_rate", "_martingale")
    z_kernel3, shift_kernel3 = _z(summary, "collision_rate", "_controlled")
    error = summary["collision_rate_martingale_err"] / TIME_AVERAGES[HALF]["collision_rate"]
    if name == "bounce":
        assert abs(shift_kernel3 - shift) < 3.0 * error
        assert abs(z_kernel3) > abs(z)
    else:
        assert np.sign(shift_kernel3) == np.sign(shift)
        assert abs(shift_kernel3) > 2.0 * abs(shift) + 3.0 * error
