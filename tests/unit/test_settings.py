"""ShardSettings: the one home of what a shard is run with."""

import pytest
import yaml
from workflow_support import REPOSITORY

from bouncing_ball.bins import LogBins
from bouncing_ball.settings import ShardSettings
from bouncing_ball.workflow.config import read_config, shard_settings


def _default():
    return shard_settings(read_config(REPOSITORY / "config" / "config.yaml"), "0.25")


def test_the_config_section_the_rule_parameter_and_the_provenance_are_one_mapping():
    settings = _default()
    mapping = settings.as_mapping()
    assert set(mapping) == set(ShardSettings.names())
    assert ShardSettings.from_mapping(mapping) == settings
    # a JSON/YAML round trip (rule parameter, Parquet provenance) gives the same settings
    assert ShardSettings.from_mapping(yaml.safe_load(yaml.safe_dump(mapping))) == settings
    assert isinstance(settings.speed_bins, LogBins) and isinstance(settings.max_steps, int)


def test_per_restitution_overrides_apply_to_their_r_only():
    config = read_config(REPOSITORY / "config" / "config.yaml")
    override = config["simulation"]["per_restitution"]["0.25"]
    assert shard_settings(config, "0.25").shard_time == float(override["shard_time"])
    assert shard_settings(config, "0.5").shard_time == float(config["simulation"]["shard_time"])


@pytest.mark.parametrize(
    ("change", "named"),
    [
        ({"shard_time": -10.0}, "shard_time"),
        ({"criterion_c": 0.0}, "criterion_c"),
        ({"max_steps": 0}, "max_steps"),
        ({"max_steps": 1.5}, "max_steps"),
        ({"min_step_floor": -1e-9}, "min_step_floor"),
    ],
)
def test_a_value_out_of_range_is_refused_naming_it(change, named):
    with pytest.raises(ValueError, match=named):
        _default().replace(**change)
