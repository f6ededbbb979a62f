"""Parsing r and checking the config (the parts a JSON schema cannot do)."""

import copy
import re
from fractions import Fraction

import numpy as np
import pytest
import yaml
from workflow_support import REPOSITORY

from bouncing_ball.flight_time import FLIGHT_TIME_TABLE_RANGE
from bouncing_ball.restitution import parse_restitution, restitution_grid, restitution_label
from bouncing_ball.settings import MAX_STEPS_LIMIT
from bouncing_ball.workflow.config import (
    MEMORY_BUDGET,
    batch_ranges,
    check_config,
    overlay_per_restitution,
    read_yaml,
    shard_batches,
    shard_count,
    shard_settings,
    simulation_settings,
    study_runs,
)


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


@pytest.mark.parametrize(
    ("value", "exact"),
    [
        (np.float32(0.5), Fraction(1, 2)),
        (np.float32(0.1), Fraction(1, 10)),  # its shortest decimal, as 0.1 is read
        (np.float16(0.3), Fraction(3, 10)),
        (np.float64(0.3), Fraction(3, 10)),
        (np.longdouble("0.25"), Fraction(1, 4)),
    ],
)
def test_numpy_floats_are_read_as_written(value, exact):
    assert parse_restitution(value) == exact


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (np.int64(1), "outside the allowed range"),
        (np.int32(0), "outside the allowed range"),
        (np.bool_(True), "not a number"),
        (np.complex128(0.5), "not a number"),
        (np.float64("nan"), "not a finite number"),
        (np.float32("inf"), "not a finite number"),
        (float("-inf"), "not a finite number"),
    ],
)
def test_numpy_scalars_that_are_not_an_r_are_refused_for_what_they_are(value, message):
    with pytest.raises(ValueError, match=message):
        parse_restitution(value, "r")


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
    assert list(grid) == ["0.25", "0.333333", "0.5", "0.75", "0.95", "0.99"]


@pytest.mark.parametrize(
    ("key", "value"),
    [("quadrature_step", 0.4), ("quadrature_step", 0.05), ("weight_panel_nodes", 9)],
)
def test_solver_settings_are_held_to_the_library_bounds(key, value):
    """The config check calls the library's own check (equilibrium.check_solver_settings)."""
    config = _default_config()
    config["solver"][key] = value
    with pytest.raises(ValueError, match=rf"^solver\.{key} must be .* got {value}"):
        check_config(config)


def test_per_r_overrides_apply_by_label():
    config = _default_config()
    # the other overrides stay: r = 0.99 needs its longer shards (8 relaxation times 1/gamma)
    overrides = config["simulation"]["per_restitution"]
    del overrides["0.75"]
    overrides["3/4"] = {"shard_time": 1234.0}
    check_config(config)
    assert simulation_settings(config, "0.75")["shard_time"] == 1234.0
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


@pytest.mark.parametrize("value", [0.9999995, 0.9999999, "9999999/10000000"])
def test_an_r_whose_label_rounds_to_one_is_refused(value):
    with pytest.raises(ValueError, match=r"restitution\[0\]: .*rounds to 1 .*at most 0.9999994"):
        restitution_grid([value])
    assert restitution_label(parse_restitution(0.9999994)) == "0.999999"


def test_two_different_r_with_one_label_are_said_to_share_it_not_to_repeat():
    with pytest.raises(ValueError, match="share the label 0.5") as error:
        restitution_grid([0.5000001, 0.5])
    assert "repeats" not in str(error.value)


def test_an_override_applies_only_to_its_own_r():
    config = _default_config()
    config["simulation"]["per_restitution"] = {"0.5000001": {"shards": 3}}
    config["restitution"] = [0.5]
    with pytest.raises(ValueError, match="per_restitution.0.5000001: .* share the label 0.5"):
        check_config(config)
    # not an r of the config: a target r0.6 would be 3/5, not 0.6000001
    config["simulation"]["per_restitution"] = {"0.6000001": {"shards": 3}}
    with pytest.raises(ValueError, match="not an r of the config"):
        check_config(config)
    config["simulation"]["per_restitution"] = {"0.6": {"shards": 3}}  # a target-only r: fine
    check_config(config)
    assert simulation_settings(config, "0.6")["shards"] == 3


@pytest.mark.parametrize("value", [0.99995, 0.01, "1/1000"])
def test_an_r_outside_the_solvers_range_is_refused_before_any_job(value):
    config = _default_config()
    config["restitution"] = [0.5, value]
    with pytest.raises(
        ValueError, match=r"restitution\[1\]: .*outside the range of r where P\(x, v\) is verified"
    ):
        check_config(config)
    config["restitution"] = [0.5]
    config["figures"]["fig4"] = [value]
    with pytest.raises(
        ValueError, match=r"figures.fig4\[0\]: .*outside the range of r where P\(x, v\) is verified"
    ):
        check_config(config)


def _schema():
    return read_yaml(REPOSITORY / "workflow/schemas/config.schema.yaml")


@pytest.mark.parametrize(
    "section, key, value",
    [
        (None, "seed", 1.0),
        ("simulation", "max_steps", 1.0e20),
        ("simulation", "max_steps", 1.0e9),
        ("simulation", "shards", 4.0),
        ("figures", "png_dpi", 200.0),
    ],
)
def test_a_float_where_an_integer_belongs_is_refused_naming_the_key(section, key, value):
    config = _default_config()
    (config if section is None else config[section])[key] = value
    if not (key == "max_steps" and value > MAX_STEPS_LIMIT):  # the library's own bound
        check_config(config)  # the consistency checks alone let a whole-number float through
    where = key if section is None else f"{section}.{key}"
    with pytest.raises(ValueError, match=f"config: {where}: .*integer"):
        check_config(config, _schema())
    check_config(_default_config(), _schema())


def test_the_step_budget_is_bounded_where_the_compiled_loop_counts_it():
    schema = _schema()
    assert schema["$defs"]["step_budget"]["maximum"] == MAX_STEPS_LIMIT < 2**63
    config = _default_config()
    config["simulation"]["max_steps"] = MAX_STEPS_LIMIT + 1
    with pytest.raises(ValueError, match="max_steps"):
        check_config(config, schema)
    with pytest.raises(ValueError, match="max_steps"):
        shard_settings(config, "0.5")


def test_a_key_written_twice_in_a_yaml_file_is_refused_with_its_line(tmp_path):
    path = tmp_path / "overlay.yaml"
    path.write_text("restitution: [0.5]\nseed: 3\nrestitution: [0.25]\n")
    with pytest.raises(
        ValueError, match=r"(?s)overlay.yaml: .*'restitution' appears twice.*line 3"
    ):
        read_yaml(path)
    path.write_text("simulation:\n  per_restitution:\n    '0.5': {shards: 2, shards: 3}\n")
    with pytest.raises(ValueError, match="'shards' appears twice"):
        read_yaml(path)


@pytest.mark.parametrize("cleared", ["{}", "null"])
def test_an_overlay_clears_the_per_r_overrides(tmp_path, cleared):
    base = REPOSITORY / "config" / "config.yaml"
    overlay = tmp_path / "overlay.yaml"
    # without its override r = 0.99 needs shards of 8 relaxation times 1/gamma (7.0e4 each)
    overlay.write_text(
        f"simulation:\n  shards: 2\n  shard_time: 6.0e+5\n  per_restitution: {cleared}\n"
    )
    config = _default_config()  # as Snakemake merges the two files: {} adds nothing
    config["simulation"]["shards"] = 2
    config["simulation"]["shard_time"] = 6.0e5
    if cleared == "null":
        config["simulation"]["per_restitution"] = None
    overlay_per_restitution(config, [base, overlay])
    check_config(config, _schema())
    assert config["simulation"]["per_restitution"] == {}
    assert shard_count(config, "0.25") == 2
    # an overlay that does not name per_restitution keeps the base file's
    overlay.write_text("simulation:\n  shards: 2\n")
    config = _default_config()
    overlay_per_restitution(config, [base, overlay])
    assert shard_count(config, "0.25") == 64


def test_shards_are_batched_into_jobs_and_more_shards_keep_the_full_batches():
    assert batch_ranges(3, 2) == [(0, 1), (2, 2)]
    assert batch_ranges(64, 16) == [(0, 15), (16, 31), (32, 47), (48, 63)]
    assert batch_ranges(80, 16)[:4] == batch_ranges(64, 16)
    assert batch_ranges(2, 5) == [(0, 1)]
    config = _default_config()
    assert shard_batches(config, "0.75") == batch_ranges(64, 16)
    config["simulation"]["per_restitution"]["0.75"]["shards_per_job"] = 1  # e.g. a cluster
    assert shard_batches(config, "0.75") == [(k, k) for k in range(64)]
    assert len(shard_batches(config, "0.25")) == 4


def _small_config():
    with open(REPOSITORY / ".test" / "config" / "config.yaml") as handle:
        return yaml.safe_load(handle)


def _set(config, key, value):
    *parents, last = key.split(".")
    node = config
    for parent in parents:
        node = node[parent]
    node[last] = value
    return config


NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize(
    "key, value, where",
    [
        ("fits.max_bias", NAN, "fits.max_bias"),
        ("solver.forces.max", INF, "solver.forces.max"),
        ("solver.positions", [INF], "solver.positions.0"),
        ("solver.positions", [NAN], "solver.positions.0"),
        ("exact.positions", [0, NAN], "exact.positions.1"),
        ("simulation.speed_bins.hi", INF, "simulation.speed_bins.hi"),
        ("simulation.velocity_bins.hi", INF, "simulation.velocity_bins.hi"),
        ("simulation.velocity_bins.lo", -INF, "simulation.velocity_bins.lo"),
        ("figures.return_speeds", [NAN], "figures.return_speeds.0"),
        ("simulation.shard_time", INF, "simulation.shard_time"),
        ("simulation.criterion_c", INF, "simulation.criterion_c"),
        ("simulation.equilibration_time", NAN, "simulation.equilibration_time"),
        (
            "simulation.per_restitution",
            {"0.5": {"shard_time": INF}},
            "simulation.per_restitution.0.5",
        ),
        ("restitution", [0.5, NAN], "restitution.1"),
        ("fits.small_speed_window", {"min": 1.0e-3, "max": INF}, "fits.small_speed_window.max"),
    ],
)
def test_a_number_that_is_not_finite_is_refused_naming_the_key(key, value, where):
    config = _set(_small_config(), key, value)
    with pytest.raises(ValueError, match=rf"config: {where}.*is not a finite number"):
        check_config(config, _schema())


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("figures.return_speeds", [1.0e6], r"figures.return_speeds\[0\]: u = 1000000.0 is outside"),
        ("figures.return_speeds", [0.3, 0.31], r"figures.return_speeds\[1\]: .*speed bin of"),
        ("solver.positions", [0, 2.0e3], r"solver.positions\[1\]: x = 2000.0 is outside"),
        ("solver.positions", [0, 0.1, 0.1], r"solver.positions\[2\]: x = 0.1 repeats .*\[1\]"),
        ("exact.positions", [0, 0.1, 0], r"exact.positions\[2\]: x = 0 repeats .*\[0\]"),
    ],
)
def test_what_a_figure_compares_with_the_simulation_lies_inside_its_bins(key, value, message):
    config = _set(_small_config(), key, value)
    with pytest.raises(ValueError, match=message):
        check_config(config, _schema())


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("solver.position_grid.points", 10_000_000, "solver.position_grid.points: .*maximum"),
        ("solver.position_grid.points", 90_000, "solver.position_grid: 90000 points would need"),
        ("solver.flight_times.points", 10_000, "solver.flight_times: 10000 points would need"),
        ("solver.restitution_grid.points", 100_000_000, "solver.restitution_grid.points: "),
        ("theory.restitution_grid.points", 100_000_000, "theory.restitution_grid.points: "),
        ("exact.position_grid.points", 10_000_000, "exact.position_grid.points: "),
        ("simulation.velocity_bins.width", 1.0e-7, "simulation.velocity_bins and simulation.pos"),
        ("simulation.velocity_bins.width", 1.0e-4, "simulation.velocity_bins and simulation.pos"),
        ("simulation.speed_bins.per_decade", 5000, r"simulation.speed_bins \(squared"),
        ("simulation.shards", 10**9, "simulation.shards: .*maximum"),
        (
            "simulation.per_restitution",
            {"0.5": {"shards": 200_000, "shards_per_job": 1000}},
            r"per_restitution.0.5 \(200000 shards",
        ),
    ],
)
def test_settings_that_need_more_memory_than_a_job_may_use_are_refused(key, value, message):
    config = _set(_small_config(), key, value)
    with pytest.raises(ValueError, match=message):
        check_config(config, _schema())


def test_the_memory_budget_leaves_room_for_the_default_and_the_quick_configs():
    check_config(_default_config(), _schema())
    check_config(_small_config(), _schema())
    config = _set(_small_config(), "simulation.velocity_bins.width", 0.01)  # 25 times finer
    config["simulation"]["shards"] = 64
    check_config(config, _schema())
    assert MEMORY_BUDGET == 2 * 2**30


def test_a_study_whose_bins_need_more_memory_than_a_job_may_use_is_refused():
    studies = read_yaml(REPOSITORY / "config" / "studies.yaml")
    study_runs(copy.deepcopy(studies), _default_config())
    studies["r075"]["simulation"] = {"velocity_bins": {"lo": -24, "hi": 20, "width": 1.0e-3}}
    with pytest.raises(ValueError, match=r"velocity_bins .*the shards of r075 \(run c3\)"):
        study_runs(studies, _default_config())


@pytest.mark.parametrize(
    "key, value",
    [
        ("solver.output_speeds.min", 1.0e-120),
        ("solver.position_grid.min", 1.0e-310),
        ("solver.position_grid.max", 1.0e13),
        ("exact.position_grid.min", 1.0e-310),
        ("solver.speeds.min", -2.0e6),
        ("solver.speeds.max", 2.0e6),
        ("exact.speeds.max", 2.0e6),
        ("solver.forces.min", 1.0e-5),
    ],
)
def test_a_grid_beyond_what_the_library_computes_is_refused_naming_the_key(key, value):
    config = _set(_small_config(), key, value)
    with pytest.raises(ValueError, match=rf"config: {key}: .*(less|greater) than the m"):
        check_config(config, _schema())


@pytest.mark.parametrize("section", ["solver", "exact"])
def test_a_position_beyond_the_largest_height_is_refused_naming_the_key(section):
    config = _set(_small_config(), f"{section}.positions", [0, 1.0e13])
    with pytest.raises(ValueError, match=rf"config: {section}.positions"):
        check_config(config, _schema())


@pytest.mark.parametrize(
    "key, value, relation",
    [("solver.flight_times.min", 1.0e-250, "less"), ("solver.flight_times.max", 1.0e14, "greater")],
)
def test_flight_times_beyond_the_library_table_range_are_refused(key, value, relation):
    """Below 1e-100 the flight-time density leaves the range of doubles at some r; beyond 1e5
    (past the longest flights at r = 0.999) each T costs T^(1/2) nodes: refused before any
    job, naming the key."""
    config = _set(_small_config(), key, value)
    with pytest.raises(
        ValueError, match=rf"{re.escape(key)}: {re.escape(repr(value))} is {relation} than"
    ):
        check_config(config, _schema())


def test_the_schema_and_the_readme_bound_flight_times_by_the_library_range():
    bounds = _schema()["properties"]["solver"]["properties"]["flight_times"]["allOf"][1][
        "properties"
    ]
    assert (bounds["min"]["minimum"], bounds["max"]["maximum"]) == FLIGHT_TIME_TABLE_RANGE
    low, high = FLIGHT_TIME_TABLE_RANGE
    readme = (REPOSITORY / "config" / "README.md").read_text()
    stated = f"{low:.1e} <= min < max <= {high:.1e}".replace("e+0", "e+")  # 1.0e+4
    assert stated in readme


@pytest.mark.parametrize("value", [0.99999, 0.01, "one"])
def test_a_fig13_r_outside_the_solver_range_is_refused(value):
    config = _default_config()
    config["figures"]["fig13"] = [0.99, value]
    with pytest.raises(ValueError, match=r"figures.fig13\[1\]"):
        check_config(config)
