"""Parsing r and checking the config (the parts a JSON schema cannot do)."""

import copy
from fractions import Fraction

import pytest
import yaml
from workflow_support import REPOSITORY

from bouncing_ball.config import check_config, simulation_settings
from bouncing_ball.restitution import parse_restitution, restitution_grid, restitution_label


def test_labels_follow_the_design():
    assert restitution_label(Fraction(1, 3)) == "0.333333"
    assert restitution_label(0.75) == "0.75"
    assert restitution_label(parse_restitution("1/2")) == "0.5"
    assert restitution_label(parse_restitution(0.25)) == "0.25"


def test_fractions_stay_exact():
    assert parse_restitution("1/3") == Fraction(1, 3)
    assert parse_restitution(0.3) == Fraction(3, 10)
    assert parse_restitution("0.333333") != Fraction(1, 3)


@pytest.mark.parametrize(
    "value, message",
    [
        (0, "outside"),
        (1, "outside"),
        (-0.5, "outside"),
        ("1/0", "divides by zero"),
        ("abc", "not a number"),
        (True, "not a number"),
        (None, "not a number"),
        ("4/3", "outside"),
    ],
)
def test_bad_r_named(value, message):
    with pytest.raises(ValueError, match=message) as error:
        restitution_grid([0.5, value])
    assert "restitution[1]" in str(error.value)


def test_repeated_r_refused_also_in_another_spelling():
    with pytest.raises(ValueError, match=r"restitution\[1\].*repeats"):
        restitution_grid([0.5, "1/2"])
    with pytest.raises(ValueError, match="non-empty"):
        restitution_grid([])


def _default_config():
    with open(REPOSITORY / "config" / "config.yaml") as handle:
        return yaml.safe_load(handle)


def test_default_config_is_consistent():
    grid = check_config(_default_config())
    assert list(grid) == ["0.25", "0.333333", "0.5", "0.75"]


def test_per_r_overrides_apply_by_label():
    config = _default_config()
    config["simulation"]["per_restitution"] = {"3/4": {"shard_time": 123.0}}
    check_config(config)
    assert simulation_settings(config, "0.75")["shard_time"] == 123.0
    assert simulation_settings(config, "0.5")["shard_time"] == config["simulation"]["shard_time"]


def test_bad_bins_and_overrides_named():
    config = _default_config()
    bad = copy.deepcopy(config)
    bad["simulation"]["speed_bins"]["lo"] = 1e3
    with pytest.raises(ValueError, match="simulation.speed_bins"):
        check_config(bad)
    bad = copy.deepcopy(config)
    bad["simulation"]["per_restitution"] = {"1.5": {"shards": 2}}
    with pytest.raises(ValueError, match="per_restitution.1.5"):
        check_config(bad)
