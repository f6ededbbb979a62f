"""Each r's own scales (bouncing_ball.scales): the automatic ranges hold all but about 1e-6 of
each distribution at each end, against the exact r = 1/2 and 1/3 solutions and the solver."""

import math
import warnings

import numpy as np
import pytest
from scales_support import END_BOUND, collisions_outside
from scipy import integrate
from workflow_support import REPOSITORY

from bouncing_ball import ExactEquilibrium, scales, simulate
from bouncing_ball.bins import log_bins
from bouncing_ball.workflow.config import IncompleteTableWarning, check_config, read_config


@pytest.mark.parametrize("r", ["1/2", "1/3"])
def test_the_speed_range_holds_the_exact_collisions(r):
    """Against the paper's exact P(0, v): each end leaves between 1e-8 and 1e-5 of the
    collisions (a range too wide would cost bins for nothing, one too narrow leaves the
    distribution out)."""
    exact = ExactEquilibrium(r)
    lo, hi = scales.outgoing_speed_range(r)
    below, above = collisions_outside(exact, lo, hi)
    assert 1e-8 < below < END_BOUND
    assert above < END_BOUND


def test_the_position_range_holds_the_exact_time():
    """Against the exact P(x) at r = 1/2 (eq. (P(x)1)): the time below x_lo and above x_hi."""
    exact = ExactEquilibrium("1/2")
    lo, hi = scales.position_range("1/2")

    def time_density(log_x):
        x = np.exp(log_x)
        return x * exact.px(x)

    below = integrate.quad(time_density, math.log(lo) - 60.0, math.log(lo), limit=200)[0]
    above = integrate.quad(time_density, math.log(hi), math.log(hi) + 8.0, limit=200)[0]
    assert 1e-8 < below < END_BOUND
    assert above < END_BOUND


def test_tail_fractions_continue_the_ends_of_a_table():
    """Gamma(2): the mass z e^-z dz below 1e-3 is 5.0e-7 and above 30 is 31 e^-30 = 2.9e-12;
    the power law of the table's last two points gives both within a few per cent."""
    z = np.geomspace(1e-3, 30.0, 400)
    below, above = scales.tail_fractions(z, z * np.exp(-z))
    exact_below = 1.0 - (1.0 + 1e-3) * math.exp(-1e-3)
    assert below == pytest.approx(exact_below, rel=1e-2)
    assert above == pytest.approx(31.0 * math.exp(-30.0), rel=0.1)
    # an end whose slope does not bound its tail (z^-2 down to 0) is unbounded
    assert scales.tail_fractions(z, z**-2.0)[0] == math.inf


def test_automatic_bins_are_a_function_of_r_and_the_settings_only():
    """Every shard of r shares them; an explicit end is kept; the automatic ends lie on the
    grid 10^(k / per_decade), so the bins of two r share their edges."""
    first = scales.resolve_bins({"speed_bins": "auto"}, "0.99")
    assert first == scales.resolve_bins({"speed_bins": "auto"}, 0.99)
    bins = first["speed_bins"]
    for end in (bins["lo"], bins["hi"]):
        k = math.log10(end) * bins["per_decade"]
        assert k == pytest.approx(round(k), abs=1e-9)
    kept = scales.resolve_bins({"speed_bins": {"lo": 1e-3, "per_decade": 20}}, 0.99)
    assert kept["speed_bins"]["lo"] == 1e-3 and kept["speed_bins"]["per_decade"] == 20
    assert kept["speed_bins"]["hi"] >= scales.outgoing_speed_range(0.99)[1]
    explicit = {"lo": 1e-4, "hi": 1e2, "per_decade": 10}
    assert scales.resolve_bins({"speed_bins": explicit}, 0.99)["speed_bins"] == explicit
    # near r = 1 the ranges grow like (1 - r)^-1 for speeds and (1 - r)^-2 for heights
    ratio = scales.outgoing_speed_range(0.999)[1] / scales.outgoing_speed_range(0.99)[1]
    assert ratio == pytest.approx(10.0, rel=0.01)
    ratio = scales.position_range(0.999)[1] / scales.position_range(0.99)[1]
    assert ratio == pytest.approx(100.0, rel=0.02)


def test_a_floor_takes_the_speed_bins_below_the_collapse_it_cuts_off():
    floored = scales.resolve_bins({"min_step_floor": 1e-12}, 0.05)["speed_bins"]
    assert floored["lo"] <= 1e-20 * math.sqrt(2e-12)
    plain = scales.resolve_bins({}, 0.05)["speed_bins"]
    assert plain["lo"] <= scales.smallest_simulated_speed()


@pytest.mark.parametrize("r, shard_time", [(0.5, 2e4), (0.99, 2e6)])
def test_simulate_follows_the_scales_of_r(r, shard_time):
    """simulate's default bins hold the whole distribution at r: with fixed bins at r = 0.99
    (speeds to 100, heights to 1e3) 55 % of the collisions and 90 % of the time fall outside;
    here the under- and overflow bins hold at most 1e-4 of each."""
    result = simulate(r, shards=2, shard_time=shard_time, seed=4, progress=False)
    for table, outside in result.outside_fractions.items():
        assert outside["outside"] <= 1e-4, table
    fixed = simulate(
        r,
        shards=2,
        shard_time=shard_time,
        seed=4,
        progress=False,
        settings={"speed_bins": {"lo": 1e-4, "hi": 100, "per_decade": 10}},
    )
    expected = scales.estimated_outside_fractions(fixed.settings.as_mapping(), r)["speed_bins"]
    measured = fixed.outside_fractions["p0v"]["outside"]
    assert (measured > 0.1) == (expected > 0.1)  # the warning's estimate tells the two apart


def test_explicit_bins_that_leave_much_out_are_warned_about_by_name():
    config = read_config(REPOSITORY / "config" / "config.yaml")
    with warnings.catch_warnings():
        warnings.simplefilter("error", IncompleteTableWarning)
        check_config(config)  # the default config follows every r: no warning
    config["simulation"]["position_bins"] = {"lo": 1e-3, "hi": 1e3, "per_decade": 5}
    with pytest.warns(IncompleteTableWarning, match=r"simulation.position_bins .* r = 0.99 "):
        check_config(config)


def test_the_automatic_bins_fit_a_job():
    """At r just above r_c the speed bins reach the simulation's smallest speed, 43 decades:
    the tallies (the return-speed pairs are the speed bins squared) still fit a merge job."""
    bins = log_bins(scales.resolve_bins({}, 0.17)["speed_bins"])
    assert bins.n < 500
