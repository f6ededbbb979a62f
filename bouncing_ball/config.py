"""Checks of the workflow config that a JSON schema cannot express.

The schema (workflow/schemas/config.schema.yaml) fixes keys, types and
simple ranges; here: r values parsed exactly and unique, bin ranges
ordered, and the keys of the per-r overrides valid r values.  An override
may name an r that is not in ``restitution``: it then applies when that r
is asked for as a target.
"""

from fractions import Fraction

import numpy as np
import yaml

from .bins import LogBins
from .restitution import parse_restitution, restitution_grid, restitution_label


def read_config(path) -> dict:
    """A config file, checked as the workflow checks it (for scripts run by hand)."""
    with open(path) as handle:
        config = yaml.safe_load(handle)
    check_config(config)
    return config


def check_config(config: dict) -> dict[str, Fraction]:
    """Raise ValueError naming the key if the config is inconsistent; return the r grid."""
    grid = restitution_grid(config["restitution"])
    simulation = config["simulation"]
    for name in ("speed_bins", "position_bins"):
        bins = simulation[name]
        if not bins["lo"] < bins["hi"]:
            raise ValueError(
                f"simulation.{name}: lo = {bins['lo']} must be smaller than hi = {bins['hi']}"
            )
    for name, positive in (
        ("solver.output_speeds", True),
        ("exact.speeds", False),
        ("exact.position_grid", True),
    ):
        section, key = name.split(".")
        points = config[section][key]
        if not points["min"] < points["max"]:
            raise ValueError(f"{name}: min = {points['min']} must be smaller than max = {points['max']}")
        if positive and not points["min"] > 0:
            raise ValueError(f"{name}: min = {points['min']} must be positive (the grid is logarithmic)")
    theory_grid = config["theory"]["restitution_grid"]
    if not 0 < theory_grid["min"] < theory_grid["max"] < 1:
        raise ValueError(
            "theory.restitution_grid: need 0 < min < max < 1, "
            f"got min = {theory_grid['min']}, max = {theory_grid['max']}"
        )
    for side in ("small_speed_window", "large_speed_window"):
        window = config["fits"][side]
        if window != "auto" and not window["min"] < window["max"]:
            raise ValueError(f"fits.{side}: min = {window['min']} must be smaller than max = {window['max']}")
    seen = {}
    for key in simulation.get("per_restitution", {}):
        where = f"simulation.per_restitution.{key}"
        label = restitution_label(parse_restitution(key, where))
        if label in seen:
            raise ValueError(f"{where}: the same r as simulation.per_restitution.{seen[label]}")
        seen[label] = key
    return grid


# the keys of config["simulation"] that change the numbers a shard produces
SHARD_SETTINGS = (
    "shard_time",
    "equilibration_time",
    "criterion_c",
    "min_step_divisor",
    "max_steps",
    "speed_bins",
    "position_bins",
)


def simulation_settings(config: dict, label: str) -> dict:
    """The simulation parameters of one r: the defaults with its overrides applied."""
    simulation = config["simulation"]
    settings = {k: v for k, v in simulation.items() if k != "per_restitution"}
    for key, override in simulation.get("per_restitution", {}).items():
        if restitution_label(parse_restitution(key)) == label:
            settings.update(override)
    return settings


def shard_settings(config: dict, label: str) -> dict:
    """What a shard of r = ``label`` is run with: only what changes its result.

    The number of shards is not among them, so adding shards leaves the
    existing ones alone.
    """
    settings = simulation_settings(config, label)
    return {key: settings[key] for key in SHARD_SETTINGS}


def shard_count(config: dict, label: str) -> int:
    return int(simulation_settings(config, label)["shards"])


def exact_settings(config: dict) -> dict:
    """What the exact-solution stage is run with: its section plus the solver's output speeds."""
    return {"output_speeds": config["solver"]["output_speeds"], **config["exact"]}


def log_grid(spec: dict):
    return np.geomspace(float(spec["min"]), float(spec["max"]), int(spec["points"]))


def linear_grid(spec: dict):
    return np.linspace(float(spec["min"]), float(spec["max"]), int(spec["points"]))


def log_bins(spec: dict) -> LogBins:
    return LogBins(float(spec["lo"]), float(spec["hi"]), int(spec["per_decade"]))
