"""ShardSettings: the one home of what a shard is run with."""

import numpy as np
import pytest
import yaml
from workflow_support import REPOSITORY

from bouncing_ball.bins import LogBins
from bouncing_ball.settings import (
    MAX_MIN_STEP_FLOOR,
    MAX_SHARDS,
    MAX_STEPS_LIMIT,
    MIN_CRITERION_C,
    ShardSettings,
)
from bouncing_ball.workflow.config import check_config, read_config, shard_settings


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


def _schemas():
    return {
        name: yaml.safe_load(
            (REPOSITORY / "workflow" / "schemas" / f"{name}.schema.yaml").read_text()
        )
        for name in ("config", "studies")
    }


def test_the_schemas_bounds_are_the_librarys_constants():
    """The config schema's bounds on the shard settings are the ones ShardSettings enforces."""
    config, studies = _schemas()["config"], _schemas()["studies"]
    simulation = config["properties"]["simulation"]["properties"]
    override = simulation["per_restitution"]["additionalProperties"]["properties"]
    assert simulation["criterion_c"]["minimum"] == MIN_CRITERION_C
    assert (
        studies["properties"]["criterion_bias"]["properties"]["criterion_c"]["items"]["minimum"]
        == MIN_CRITERION_C
    )
    assert (
        studies["properties"]["r075"]["properties"]["runs"]["additionalProperties"]["properties"][
            "criterion_c"
        ]["minimum"]
        == MIN_CRITERION_C
    )
    for floor in (
        simulation["min_step_floor"],
        override["min_step_floor"],
        studies["$defs"]["simulation"]["properties"]["min_step_floor"],
    ):
        assert (floor["minimum"], floor["maximum"]) == (0, MAX_MIN_STEP_FLOOR)
    assert config["$defs"]["step_budget"]["maximum"] == MAX_STEPS_LIMIT
    assert studies["$defs"]["simulation"]["properties"]["max_steps"]["maximum"] == MAX_STEPS_LIMIT
    assert simulation["shards"]["maximum"] == override["shards"]["maximum"] == MAX_SHARDS


@pytest.mark.parametrize(
    ("change", "named"),
    [
        ({"criterion_c": 0.5}, "criterion_c"),
        ({"criterion_c": MIN_CRITERION_C * (1 - 1e-9)}, "criterion_c"),
        ({"min_step_floor": 1e-3}, "min_step_floor"),
        ({"min_step_floor": MAX_MIN_STEP_FLOOR * (1 + 1e-9)}, "min_step_floor"),
        ({"shard_time": float("inf")}, "shard_time"),
        ({"min_step_divisor": float("inf")}, "min_step_divisor"),
        ({"equilibration_time": float("nan")}, "equilibration_time"),
    ],
)
def test_the_library_refuses_what_the_config_schema_refuses(change, named):
    """simulate's settings and the pipeline's config are held to the same bounds, the
    schema's: a biasing criterion constant or step floor, an infinite time."""
    with pytest.raises(ValueError, match=named):
        _default().replace(**change)
    config = read_config(REPOSITORY / "config" / "config.yaml")
    config["simulation"].update(change)
    with pytest.raises(ValueError, match=f"^simulation: .*{named}"):
        check_config(config)  # the config check is the library's, without the schema too


def test_the_bounds_themselves_are_allowed():
    settings = _default().replace(criterion_c=MIN_CRITERION_C, min_step_floor=MAX_MIN_STEP_FLOOR)
    assert settings.criterion_c == MIN_CRITERION_C


def test_a_per_r_override_is_checked_by_the_library_naming_its_r():
    config = read_config(REPOSITORY / "config" / "config.yaml")
    config["simulation"]["per_restitution"] = {"0.5": {"min_step_floor": 1e-3}}
    with pytest.raises(ValueError, match=r"^simulation.per_restitution.0.5: .*min_step_floor"):
        check_config(config)


@pytest.mark.parametrize(
    "value", [np.int64(50), np.int32(50), np.float32(50.0), np.float64(50.0), np.uint8(50)]
)
def test_numpy_scalars_are_numbers(value):
    settings = _default().replace(shard_time=value, max_steps=np.int64(10**9))
    assert settings.shard_time == 50.0 and type(settings.shard_time) is float
    assert settings.max_steps == 10**9 and type(settings.max_steps) is int


@pytest.mark.parametrize("value", ["50", None, True, [50.0]])
def test_what_is_not_a_number_is_refused_as_such(value):
    with pytest.raises(TypeError, match="shard_time must be a number"):
        _default().replace(shard_time=value)
