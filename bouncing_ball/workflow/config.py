"""Checks of the workflow config that a JSON schema cannot express.

The schema (workflow/schemas/config.schema.yaml) fixes keys, types and
simple ranges, and ``check_types`` refuses a number that is not finite (JSON
Schema lets NaN through every bound); here: r values parsed exactly and unique, bin
ranges ordered, the keys of the per-r overrides valid r values, the heights
and speeds the figures compare within the simulation's bins, and the memory
a job would need within ``MEMORY_BUDGET``.  An override
may name an r that is not in ``restitution``: it then applies when that r
is asked for as a target.  Likewise for the studies' file, config/studies.yaml
(``study_runs``; schema workflow/schemas/studies.schema.yaml).
"""

import math
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import jsonschema
import yaml

from ..bins import linear_bins, log_bins
from ..equilibrium import check_solver_settings
from ..restitution import (
    EXACT_RESTITUTIONS,
    SOLVER_RESTITUTION_RANGE,
    check_distribution_range,
    check_solver_range,
    exact_string,
    parse_restitution,
    restitution_grid,
    restitution_label,
    shared_label_message,
)
from ..scales import (
    AUTO,
    OUTSIDE_WARNING,
    SOLVER_TABLE_POINTS,
    estimated_outside_fractions,
    resolve_bins,
    resolve_solver_grids,
)
from ..settings import ShardSettings, return_law_speed_bins
from ..tallies import HISTOGRAMS, HISTOGRAMS_2D

# the config's schema, in the repository that holds this package
SCHEMA = Path(__file__).resolve().parents[1] / "workflow" / "schemas" / "config.schema.yaml"

#: The shard settings that are bin sets: ``"auto"`` (r's scales, ``scales.resolve_bins``),
#: partly automatic, or explicit.
BIN_SETTINGS = ("speed_bins", "position_bins", "velocity_bins", "flight_time_bins")

# the memory one job may ask for, in bytes: ``check_config`` refuses settings whose largest
# arrays would need more (estimated from the settings, before any job runs)
MEMORY_BUDGET = 2 * 2**30


class _UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """YAML's safe loader, refusing a key repeated in one mapping (PyYAML keeps the last).
    libyaml's parser where PyYAML has it (faster than the pure-Python parser, and the schema is
    read at every start of the workflow)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key {key!r} appears twice", key_node.start_mark
                )
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


def read_yaml(path):
    """A YAML file's content; ValueError naming the file and line of a repeated key."""
    with open(path) as handle:
        try:
            return yaml.load(handle, Loader=_UniqueKeyLoader)  # noqa: S506 (a safe loader)
        except yaml.YAMLError as error:
            raise ValueError(f"{path}: {error}") from None


def read_config(path) -> dict:
    """A config file, checked as the workflow checks it (for scripts run by hand)."""
    config = read_yaml(path)
    check_config(config, read_yaml(SCHEMA) if SCHEMA.exists() else None)
    return config


def overlay_per_restitution(config: dict, paths) -> None:
    """Give ``config`` the per-r overrides of the last of ``paths`` (base file first, then
    the overlays) that sets ``simulation.per_restitution``, whole: Snakemake merges the
    files' mappings key by key, so an overlay could add overrides but never remove one.
    Also refuses a key repeated within any of the files (``read_yaml``)."""
    found, chosen = False, None
    for path in paths:
        content = read_yaml(path)
        simulation = content.get("simulation") if isinstance(content, dict) else None
        if isinstance(simulation, dict) and "per_restitution" in simulation:
            found, chosen = True, simulation["per_restitution"]
    if found:
        config["simulation"]["per_restitution"] = chosen or {}


def _is_integer(checker, instance) -> bool:
    return isinstance(instance, int) and not isinstance(instance, bool)


def _non_finite_numbers(instance, path=()):
    """Yield (path, value) of every float in ``instance`` (nested mappings and lists) that is
    not finite."""
    if isinstance(instance, float) and not math.isfinite(instance):
        yield path, instance
    elif isinstance(instance, dict):
        for key, value in instance.items():
            yield from _non_finite_numbers(value, (*path, key))
    elif isinstance(instance, list):
        for index, value in enumerate(instance):
            yield from _non_finite_numbers(value, (*path, index))


def check_types(instance, schema: dict, source: str) -> None:
    """``instance`` against ``schema`` with numbers that are finite and integers that are
    integers.  YAML's ``.nan`` passes every ``minimum`` and ``maximum`` of JSON Schema (each
    comparison with NaN is false) and ``.inf`` every ``minimum``; and JSON Schema (and
    Snakemake's ``validate``) counts 1.0 or 1.0e+20 as an integer, so that a seed of 1.0 or
    a step budget of 1.0e+20 would fail in every job.  ValueError naming the key."""
    for path, value in _non_finite_numbers(instance):
        where = ".".join(str(part) for part in path)
        raise ValueError(
            f"{source}: {where}: {value} is not a finite number (.nan and .inf are not values)"
        )
    base = jsonschema.validators.validator_for(schema)
    strict = jsonschema.validators.extend(
        base, type_checker=base.TYPE_CHECKER.redefine("integer", _is_integer)
    )
    # the error that says most: inside an anyOf ("auto" or a mapping), the mapping's own
    error = jsonschema.exceptions.best_match(strict(schema).iter_errors(instance))
    if error is not None:
        where = ".".join(str(part) for part in error.absolute_path) or "the top level"
        hint = (
            " (write a whole number without a decimal point or exponent, e.g. 1000000000)"
            if isinstance(error.instance, float) and error.validator == "type"
            else ""
        )
        raise ValueError(f"{source}: {where}: {error.message}{hint}")


def check_config(config: dict, schema: dict | None = None) -> dict[str, Fraction]:
    """Raise ValueError naming the key if the config is inconsistent; return the r grid.

    With ``schema`` (workflow/schemas/config.schema.yaml, read), first ``check_types``:
    the workflow passes it, after Snakemake's own ``validate``.
    """
    if schema is not None:
        check_types(config, schema, "config")
    grid = restitution_grid(config["restitution"])
    for name, positive in (
        ("solver.output_speeds", True),
        ("solver.flight_times", True),
        ("solver.position_grid", True),
        ("solver.forces", True),
        ("solver.speeds", False),
        ("exact.speeds", False),
        ("exact.position_grid", True),
    ):
        section, key = name.split(".")
        points = config[section][key]
        if not isinstance(points, dict) or AUTO in (points.get("min"), points.get("max")):
            continue  # r's scales (scales.resolve_grid)
        if not points["min"] < points["max"]:
            raise ValueError(
                f"{name}: min = {points['min']} must be smaller than max = {points['max']}"
            )
        if positive and not points["min"] > 0:
            raise ValueError(
                f"{name}: min = {points['min']} must be positive (the grid is logarithmic)"
            )
    theory_grid = config["theory"]["restitution_grid"]
    if not 0 < theory_grid["min"] < theory_grid["max"] < 1:
        raise ValueError(
            "theory.restitution_grid: need 0 < min < max < 1, "
            f"got min = {theory_grid['min']}, max = {theory_grid['max']}"
        )
    # the library's own bounds (Equilibrium refuses the same), where the 1e-8 target is met
    check_solver_settings(
        config["solver"]["quadrature_step"], config["solver"]["weight_panel_nodes"], "solver."
    )
    solver_grid = config["solver"]["restitution_grid"]
    low, high = SOLVER_RESTITUTION_RANGE
    if not low <= solver_grid["min"] < solver_grid["max"] <= high:
        raise ValueError(
            f"solver.restitution_grid: need {low} <= min < max <= {high} (the solver's accurate range), "
            f"got min = {solver_grid['min']}, max = {solver_grid['max']}"
        )
    for index, value in enumerate(config["restitution"]):
        check_distribution_range(value, f"restitution[{index}]")  # every r of the run is solved
    for index, value in enumerate(config["figures"]["fig13"]):  # P(0, v) alone
        check_solver_range(value, f"figures.fig13[{index}]")
    known = {**figure_restitutions(config, grid), **grid}
    for side in ("small_speed_window", "large_speed_window"):
        window = config["fits"][side]
        if window != "auto" and not window["min"] < window["max"]:
            raise ValueError(
                f"fits.{side}: min = {window['min']} must be smaller than max = {window['max']}"
            )
    seen = {}
    for key in per_restitution(config):
        where = f"simulation.per_restitution.{key}"
        value = parse_restitution(key, where)
        label = restitution_label(value)
        if label in seen:
            raise ValueError(f"{where}: the same r as simulation.per_restitution.{seen[label]}")
        seen[label] = key
        if label in known and known[label] != value:
            raise ValueError(shared_label_message(where, value, known[label]))
        if label not in known and parse_restitution(label) != value:
            raise ValueError(
                f"{where}: r = {key} is not an r of the config (restitution, figures), and "
                f"as a target it would be asked for by its label {label}, which is another r "
                f"({label}); add r = {key} to restitution, or key the override by {label}"
            )
    check_shard_settings(config)
    warn_incomplete_bins(config)
    check_figure_positions(config)
    check_equilibration(config)
    check_memory(config)
    return grid


def check_shard_settings(config: dict) -> None:
    """The shard settings of every r (the ``simulation`` section, and it with each override of
    ``simulation.per_restitution``) checked by ``settings.ShardSettings``, the library's own
    check: the pipeline and ``simulate`` refuse the same settings.  ValueError naming the
    section otherwise."""
    known = known_restitutions(config)
    first = next(iter(known))  # the bins follow some r
    cases = {"simulation": simulation_settings(config, first, overrides=False)}
    for key in per_restitution(config):
        cases[f"simulation.per_restitution.{key}"] = simulation_settings(
            config, restitution_label(parse_restitution(key))
        )
    for label in known:  # the bins of each r, partly automatic or not, ordered
        settings = simulation_settings(config, label)
        for name in BIN_SETTINGS:
            bins = settings[name]
            if not bins["lo"] < bins["hi"]:
                raise ValueError(
                    f"simulation.{name} at r = {label}: lo = {bins['lo']:.6g} must be smaller "
                    f"than hi = {bins['hi']:.6g} (an end not given follows r's scales)"
                )
    for where, settings in cases.items():
        try:
            ShardSettings.from_mapping(settings)
        except (TypeError, ValueError) as error:
            raise ValueError(f"{where}: {error}") from None


class IncompleteTableWarning(UserWarning):
    """Explicit bins or grids that leave more than ``scales.OUTSIDE_WARNING`` of a
    distribution outside their range at some r."""


# the solver's grids of a distribution, as the simulation's bins they match: (config key,
# bin setting whose tails it shares)
_SOLVER_GRIDS = {
    "output_speeds": "speed_bins",
    "position_grid": "position_bins",
    "flight_times": "flight_time_bins",
}


def warn_incomplete_bins(config: dict) -> None:
    """Warn (``IncompleteTableWarning``), naming r, the key and the fraction, where a bin set of
    the simulation or a grid of the solver with an end fixed by the config leaves more than
    ``scales.OUTSIDE_WARNING``
    of its distribution outside, by the asymptotic forms (``scales.estimated_outside_fractions``);
    ``auto`` ranges follow r and leave about 1e-6 at each end."""
    import warnings

    simulation = config["simulation"]
    for label in known_restitutions(config):
        settings = simulation_settings(config, label)
        estimates = estimated_outside_fractions(settings, _restitution_of_label(config, label))
        solver = solver_settings(config, label)
        grids = {
            name: {"lo": solver[key]["min"], "hi": solver[key]["max"], "per_decade": 1}
            for key, name in _SOLVER_GRIDS.items()
        }
        solved = estimated_outside_fractions(
            {**grids, "velocity_bins": settings["velocity_bins"]},
            _restitution_of_label(config, label),
        )
        cases = [
            (f"simulation.{name}", estimates[name], simulation.get(name), ("lo", "hi"))
            for name in BIN_SETTINGS
        ]
        cases += [
            (f"solver.{key}", solved[name], config["solver"][key], ("min", "max"))
            for key, name in _SOLVER_GRIDS.items()
        ]
        for key, fraction, spec, ends in cases:
            # an end the config fixes (the others follow r)
            fixed = isinstance(spec, dict) and any(spec.get(end, AUTO) != AUTO for end in ends)
            if fixed and fraction > OUTSIDE_WARNING:
                warnings.warn(
                    f"{key} leaves about {fraction:.1e} of the distribution at r = {label} "
                    f"outside its range (more than {OUTSIDE_WARNING:g}); give it as auto to "
                    "follow the scales of each r",
                    IncompleteTableWarning,
                    stacklevel=2,
                )


def check_figure_positions(config: dict) -> None:
    """The heights of the P(x, v) curves (``solver.positions``, ``exact.positions``) and the
    outgoing speeds of Fig. 11 (``figures.return_speeds``): no repeats, and those the figures
    compare with the simulation inside its bins.  Fig. 8 draws, with the curve at x > 0, the
    cells of the x bin that holds x, and Fig. 11 one panel per speed bin that holds a speed: an
    underflow or overflow bin there would be set against a value at one end of it.
    ValueError naming the key otherwise."""
    for section in ("solver", "exact"):
        positions = config[section]["positions"]
        for index, x in enumerate(positions):
            where = f"{section}.positions[{index}]"
            if x in positions[:index]:
                raise ValueError(
                    f"{where}: x = {x} repeats {section}.positions[{positions.index(x)}]"
                )
    for label in restitution_grid(config["figures"]["fig8"], "figures.fig8"):
        position_bins = log_bins(simulation_settings(config, label)["position_bins"])
        for index, x in enumerate(config["solver"]["positions"]):
            if x > 0 and not (position_bins.lo <= x < position_bins.hi):
                raise ValueError(
                    f"solver.positions[{index}]: x = {x} is outside the position bins of "
                    f"r = {label} (simulation.position_bins) [{position_bins.lo:.6g}, "
                    f"{position_bins.hi:.6g}): Fig. 8 would draw the simulation's underflow or "
                    "overflow bin against the curve at x; use 0 or an x inside the bins"
                )
    for label in restitution_grid(config["figures"]["fig11"], "figures.fig11"):
        speed_bins = log_bins(simulation_settings(config, label)["speed_bins"])
        shown = {}
        for index, speed in enumerate(config["figures"]["return_speeds"]):
            where = f"figures.return_speeds[{index}]"
            if not speed_bins.lo <= speed < speed_bins.hi:
                raise ValueError(
                    f"{where}: u = {speed} is outside the speed bins of r = {label} "
                    f"(simulation.speed_bins) [{speed_bins.lo:.6g}, {speed_bins.hi:.6g}): "
                    "Fig. 11 draws one panel per speed bin"
                )
            bin_index = int(
                math.floor(math.log10(speed / speed_bins.lo) * speed_bins.per_decade + 1e-9)
            )
            if bin_index in shown:
                raise ValueError(
                    f"{where}: u = {speed} is in the speed bin of figures.return_speeds"
                    f"[{shown[bin_index]}] at r = {label}: each panel of Fig. 11 is one speed "
                    "bin"
                )
            shown[bin_index] = index


# the peak memory of a solve job per point of its output grids, in bytes (tracemalloc at
# r = 0.05, 1/2 and 0.75, with a margin): the flight-time density integrates McKean's law
# over every node of the solution at each T; P(x) and <v^2>_x take each x on its own F nodes
# (distribution._force_nodes, the most at x = SMALLEST_POSITION), held for one x at a time, so
# the position grid's cost per point is its rows alone, far below the bound here (the slope of
# the peak between 100 and 1000 points from 1e-300 to 1e12, the nodes a fixed cost besides)
SOLVER_BYTES_PER_POINT = {
    "solver.flight_times": 1.2e6,
    "solver.position_grid": 2.5e4,
    "solver.output_speeds": 5.0e3,
}
# the bytes a cell of a shard's tallies takes: 8 in a shard's arrays (the merge holds every
# shard's, and its jackknife two more copies), 64 as a row of a batch table
# (batches.batch_to_frame: shard, tally, four edges, value)
BYTES_PER_CELL_IN_MEMORY, BYTES_PER_CELL_IN_A_TABLE = 3 * 8, 64


def tally_cells(simulation: dict) -> dict[str, int]:
    """{tally: cells} of one shard's tallies (each bin range with under- and overflow), from
    the explicit bins of a config-shaped ``simulation`` mapping of one r
    (``simulation_settings``)."""
    bins = {
        "speed_bins": log_bins(simulation["speed_bins"]),
        "position_bins": log_bins(simulation["position_bins"]),
        "velocity_bins": linear_bins(simulation["velocity_bins"]),
        "flight_time_bins": log_bins(simulation["flight_time_bins"]),
        "return_law_speed_bins": return_law_speed_bins(log_bins(simulation["speed_bins"])),
    }
    cells = {name: bins[spec].n + 2 for name, (spec, _, _) in HISTOGRAMS.items()}
    for name, ((first, second), _, _) in HISTOGRAMS_2D.items():
        cells[name] = (bins[first].n + 2) * (bins[second].n + 2)
    return cells


# the settings behind each tally's cells, as the config names them
TALLY_KEYS = {
    "outgoing_speed": "simulation.speed_bins",
    "outgoing_speed_fine": "simulation.speed_bins (at 100 bins per decade)",
    "position_time": "simulation.position_bins",
    "position_v2_time": "simulation.position_bins",
    "flight_time": "simulation.flight_time_bins",
    "position_velocity_time": "simulation.velocity_bins and simulation.position_bins",
    "return_speed": "simulation.speed_bins (squared: every pair of speed bins)",
}


def _gib(size: float) -> str:
    return f"{size / 2**30:.3g} GiB"


def check_memory(config: dict) -> None:
    """Refuse settings with which a job would need more than ``MEMORY_BUDGET`` bytes: the
    solve job's output grids, and the merge of the shards of an r (every shard's tallies,
    one batch table at a time) and the job that simulates a batch (its table); the per-r
    overrides of ``shards`` and ``shards_per_job`` included.  ValueError naming the key."""
    for key, per_point in SOLVER_BYTES_PER_POINT.items():
        section, name = key.split(".")
        spec = config[section][name]
        points = spec.get("points", AUTO) if isinstance(spec, dict) else AUTO
        points = SOLVER_TABLE_POINTS[name] if points == AUTO else points
        if points * per_point > MEMORY_BUDGET:
            raise ValueError(
                f"{key}: {points} points would need about {_gib(points * per_point)} in the "
                f"solve job, more than a job's {_gib(MEMORY_BUDGET)}; use at most "
                f"{int(MEMORY_BUDGET // per_point)} points"
            )
    overridden = {restitution_label(parse_restitution(key)): key for key in per_restitution(config)}
    for label in {**known_restitutions(config), **overridden}:
        settings = simulation_settings(config, label)
        shards, per_job = int(settings["shards"]), int(settings["shards_per_job"])
        per_job = min(per_job, shards)
        check_merge_memory(
            settings,
            shards,
            per_job,
            f"simulation.per_restitution.{overridden[label]} ({shards} shards, {per_job} a job)"
            if label in overridden
            else f"r = {label}: simulation.shards = {shards}, shards_per_job = {per_job}",
        )


def check_merge_memory(simulation: dict, shards: int, per_job: int, whose: str) -> None:
    """Refuse shard bins (``simulation``, config-shaped) with which merging ``shards`` shards
    stored ``per_job`` to a file would need more than ``MEMORY_BUDGET`` bytes; ``whose``
    names the settings in the message."""
    cells = tally_cells(simulation)
    total = sum(cells.values())
    merge = total * (shards * BYTES_PER_CELL_IN_MEMORY + per_job * BYTES_PER_CELL_IN_A_TABLE)
    if merge > MEMORY_BUDGET:
        largest = max(cells, key=cells.get)
        raise ValueError(
            f"{TALLY_KEYS[largest]}: the tallies of a shard have {total} cells "
            f"({largest}: {cells[largest]}); with {whose} merging them would need "
            f"about {_gib(merge)}, more than a job's {_gib(MEMORY_BUDGET)}: use wider "
            "bins or a narrower range"
        )


def per_restitution(config: dict) -> dict:
    """The per-r overrides, {r as written: {setting: value}}; none if the section is
    absent or null (an overlay clears the base file's with ``per_restitution: null``)."""
    return config["simulation"].get("per_restitution") or {}


# the figures with an r list of their own (config["figures"]): each r is simulated for them
SIMULATED_FIGURES = ("fig4", "fig5", "fig8", "fig10", "fig11")


def figure_restitutions(config: dict, grid: dict | None = None) -> dict[str, Fraction]:
    """{label: exact r} of the panels of Figs. 4 and 5 (config["figures"]).

    They need not be in ``restitution``: a figure asks for what it shows.  Fig. 5's
    r must have an exact solution; an r that shares a label with one of
    ``restitution`` must be the same r.
    """
    grid = restitution_grid(config["restitution"]) if grid is None else grid
    shown = {}
    for figure in SIMULATED_FIGURES:
        values = config["figures"][figure]
        for index, (label, value) in enumerate(
            restitution_grid(values, f"figures.{figure}").items()
        ):
            where = f"figures.{figure}[{index}]"
            if figure == "fig5" and value not in EXACT_RESTITUTIONS:
                raise ValueError(
                    f"{where}: r = {values[index]!r} has no exact solution (only 1/2 and 1/3)"
                )
            if figure != "fig5":  # drawn with the solver's answers
                check_distribution_range(values[index], where)
            for other in (grid, shown):
                if label in other and other[label] != value:
                    raise ValueError(shared_label_message(where, value, other[label]))
            shown[label] = value
    return shown


def known_restitutions(config: dict) -> dict[str, Fraction]:
    """{label: exact r} of every r the config names: ``restitution`` and the figures' panels."""
    grid = restitution_grid(config["restitution"])
    return {**figure_restitutions(config, grid), **grid}


#: ``simulation.equilibration_time`` (or an override's) that follows from the relaxation time
#: at each r: ``simulation.equilibration.default_equilibration_time``
AUTO_EQUILIBRATION = "auto"


def simulation_settings(config: dict, label: str, overrides: bool = True) -> dict:
    """The simulation parameters of one r: the defaults with its overrides applied, every
    bin set that is ``auto`` (or partly so, or missing) made explicit from r's scales
    (``scales.resolve_bins``), and ``equilibration_time: auto`` replaced by
    ``simulation.equilibration.default_equilibration_time`` at that r (the r of
    ``restitution``, the figures or the overrides with that label, or the label read as r).
    With ``overrides`` False, the section's own settings at that r, without r's overrides."""
    simulation = config["simulation"]
    settings = {"min_step_floor": 0.0}  # optional key: the paper's rule alone
    settings.update({k: v for k, v in simulation.items() if k != "per_restitution"})
    for key, override in per_restitution(config).items():
        if overrides and restitution_label(parse_restitution(key)) == label:
            settings.update(override)
    exact = _restitution_of_label(config, label)
    settings = resolve_bins(settings, exact)
    if isinstance(settings["shard_time"], dict):
        settings["shard_time"] = _in_relaxation_times(
            settings["shard_time"]["relaxation_times"], exact, label
        )
    if settings["equilibration_time"] == AUTO_EQUILIBRATION:
        # imported here: the relaxation time needs the solver (scipy, numba), which importing
        # this module does not load
        from ..simulation.equilibration import default_equilibration_time

        settings["equilibration_time"] = default_equilibration_time(exact)
    return settings


def _in_relaxation_times(count: float, exact: Fraction, label: str) -> float:
    """``count`` relaxation times of the process at r (``Equilibrium.relaxation_time``),
    rounded up to two significant digits; ValueError at or below r_c, where there is none."""
    from ..simulation.equilibration import _two_digits_up, equilibration_relaxation_time

    relaxation = equilibration_relaxation_time(exact)
    if relaxation is None:
        raise ValueError(
            f"simulation.shard_time at r = {label}: {{relaxation_times: {count}}} needs a "
            "relaxation time, and at or below r_c the outgoing speeds collapse; give a time"
        )
    return _two_digits_up(count * relaxation)


def _restitution_of_label(config: dict, label: str) -> Fraction:
    """The r the config names by ``label`` (``restitution``, the figures' lists, the
    overrides' keys), or the label read as r."""
    named = [*config["restitution"], *per_restitution(config)]
    for figure in SIMULATED_FIGURES:
        named.extend(config["figures"].get(figure) or [])
    for value in named:
        try:
            exact = parse_restitution(value)
        except ValueError:
            continue  # check_config names it
        if restitution_label(exact) == label:
            return exact
    return parse_restitution(label)


def check_equilibration(config: dict) -> None:
    """Refuse, naming r, the relaxation time and the key, a simulated r whose shards
    (``simulation_settings``) are too short for the relaxation time there
    (``simulation.equilibration.equilibration_problems``), before any job runs."""
    from ..simulation.equilibration import equilibration_problems

    for label, exact in known_restitutions(config).items():
        settings = simulation_settings(config, label)
        problems = equilibration_problems(
            exact_string(exact),
            settings["shard_time"],
            settings["equilibration_time"],
            f'simulation.per_restitution."{label}".',
        )
        if problems:
            raise ValueError("; ".join(problems))


def shard_settings(config: dict, label: str) -> ShardSettings:
    """What a shard of r = ``label`` is run with: only what changes its result."""
    return ShardSettings.from_mapping(simulation_settings(config, label))


def shard_count(config: dict, label: str) -> int:
    return int(simulation_settings(config, label)["shards"])


def batch_ranges(count: int, per_job: int) -> list[tuple[int, int]]:
    """Shards 0 .. count - 1 in consecutive batches of ``per_job`` (the last may be smaller),
    as (first, last) pairs, last included: one workflow job simulates each batch.

    A batch ends at a multiple of ``per_job``, so more shards leave the full batches as
    they are and add batches after them."""
    if count < 1 or per_job < 1:
        raise ValueError(
            f"need count >= 1 and per_job >= 1, got count = {count}, per_job = {per_job}"
        )
    return [(first, min(first + per_job, count) - 1) for first in range(0, count, per_job)]


def shard_batches(config: dict, label: str) -> list[tuple[int, int]]:
    """The batches of the shards of r = ``label`` (``batch_ranges`` of ``simulation.shards``
    and ``simulation.shards_per_job``, with the per-r overrides)."""
    settings = simulation_settings(config, label)
    return batch_ranges(int(settings["shards"]), int(settings["shards_per_job"]))


def solver_settings(config: dict, label: str) -> dict:
    """What one solve of r = ``label`` is run with (not the r grid of Fig. 6, which has its
    own job): the ``solver`` section with every ``"auto"`` grid made explicit at r
    (``scales.resolve_solver_grids``)."""
    settings = {
        key: config["solver"][key]
        for key in (
            "quadrature_step",
            "output_speeds",
            "flight_times",
            "position_grid",
            "positions",
            "speeds",
            "forces",
            "weight_panel_nodes",
        )
    }
    return resolve_solver_grids(settings, _restitution_of_label(config, label))


def exact_settings(config: dict, label: str) -> dict:
    """What the exact solution of r = ``label`` is computed with: the ``exact`` section plus
    the solver's output speeds at that r (``solver_settings``)."""
    return {"output_speeds": solver_settings(config, label)["output_speeds"], **config["exact"]}


# ---- the studies (config/studies.yaml; workflow/rules/studies.smk) ----


@dataclass(frozen=True)
class StudyRun:
    """One run of a study: shards of one r with one c and seed, filed under
    results/studies/{study}/{run}/shards{first}-{last}.parquet (batches of
    ``simulation.shards_per_job`` shards)."""

    study: str
    run: str
    restitution: Fraction
    seed: int
    shards: int
    settings: ShardSettings

    @property
    def label(self) -> str:
        return restitution_label(self.restitution)

    def as_mapping(self) -> dict:
        """JSON-ready: what a report's rule is told about the run (params)."""
        return {
            "run": self.run,
            "r": exact_string(self.restitution),
            "r_label": self.label,
            "criterion_c": self.settings.criterion_c,
            "seed": self.seed,
            "shards": self.shards,
        }


def _study_settings(config: dict, label: str, study: dict, where: str, **changes) -> ShardSettings:
    """The main config's shard settings of r = ``label``, with the study's ``simulation``
    overrides and ``changes`` (shard_time, criterion_c) applied."""
    overrides = dict(study.get("simulation", {}))
    for name in ("speed_bins", "position_bins", "velocity_bins", "flight_time_bins"):
        bins = overrides.get(name)
        if bins is not None and not bins["lo"] < bins["hi"]:
            raise ValueError(
                f"{where}.simulation.{name}: lo = {bins['lo']} must be smaller than hi = {bins['hi']}"
            )
    try:
        return shard_settings(config, label).replace(**overrides, **changes)
    except ValueError as error:
        raise ValueError(f"{where}: {error}") from None


def study_runs(studies: dict, config: dict) -> dict[str, dict[str, StudyRun]]:
    """{study: {run: StudyRun}} of config/studies.yaml (already checked against its schema),
    with the checks a schema cannot express; ValueError naming the key otherwise.

    criterion_bias: one run per (r, c), named r{label}_c{c}; every r must have an exact
    solution and a shard_time.  The seed is shared, so the runs at one r with different c
    draw the same streams (shard k of r: ``(seed, r label, k)``).
    r075: the runs as named in the file; their seeds must differ (the report pools them).
    coverage: ``runs`` runs per r, named r{label}_run{k}, run k with seed ``seed + k``
    (independent streams; the runs of different r differ by the r label of the streams).
    Settings not in the study come from the main config's ``simulation`` section.
    """
    runs: dict[str, dict[str, StudyRun]] = {}
    where = "criterion_bias"
    study = studies["criterion_bias"]
    grid, times = _exact_grid_and_shard_times(study, where)
    runs[where] = {}
    for label, value in grid.items():
        for c in study["criterion_c"]:
            name = f"r{label}_c{float(c):g}"
            if name in runs[where]:
                raise ValueError(f"{where}.criterion_c: c = {c} repeats another value")
            settings = _study_settings(
                config, label, study, where, shard_time=times[label], criterion_c=c
            )
            runs[where][name] = StudyRun(
                where, name, value, study["seed"], study["shards"], settings
            )
    where = "r075"
    study = studies["r075"]
    value = parse_restitution(study["restitution"], f"{where}.restitution")
    label = restitution_label(value)
    runs[where] = {}
    seeds = {}
    for name, run in study["runs"].items():
        if run["seed"] in seeds:
            raise ValueError(
                f"{where}.runs.{name}: seed {run['seed']} is also the seed of run {seeds[run['seed']]}; "
                "the report pools the runs, which must be independent"
            )
        seeds[run["seed"]] = name
        settings = _study_settings(
            config,
            label,
            study,
            f"{where}.runs.{name}",
            shard_time=study["shard_time"],
            criterion_c=run["criterion_c"],
        )
        runs[where][name] = StudyRun(where, name, value, run["seed"], run["shards"], settings)
    where = "coverage"
    study = studies["coverage"]
    grid, times = _exact_grid_and_shard_times(study, where)
    runs[where] = {}
    width = len(str(study["runs"] - 1))
    for label, value in grid.items():
        settings = _study_settings(config, label, study, where, shard_time=times[label])
        for k in range(study["runs"]):
            name = f"r{label}_run{k:0{width}d}"
            runs[where][name] = StudyRun(
                where, name, value, study["seed"] + k, study["shards"], settings
            )
    for study, named in runs.items():
        for name, run in named.items():
            # a study shard is a file of its own; its report reads every shard of its study,
            # the coverage report one run at a time
            merged = run.shards if study == "coverage" else sum(o.shards for o in named.values())
            check_merge_memory(
                run.settings.as_mapping(), merged, 1, f"the shards of {study} (run {name})"
            )
    return runs


def _exact_grid_and_shard_times(study: dict, where: str) -> tuple[dict, dict]:
    """A study's r values ({label: r}), each with an exact solution, and its ``shard_time``
    per r label ({label: time}, one for every r); ValueError naming the key otherwise."""
    grid = restitution_grid(study["restitution"], f"{where}.restitution")
    for value in grid.values():
        if value not in EXACT_RESTITUTIONS:
            raise ValueError(
                f"{where}.restitution: r = {value} has no exact solution (only 1/2 and 1/3)"
            )
    times = {}
    for key, shard_time in study["shard_time"].items():
        label = restitution_label(parse_restitution(key, f"{where}.shard_time.{key}"))
        if label not in grid:
            raise ValueError(f"{where}.shard_time.{key}: r = {key} is not in {where}.restitution")
        if label in times:
            raise ValueError(f"{where}.shard_time.{key}: the same r as another key")
        times[label] = shard_time
    missing = [str(value) for label, value in grid.items() if label not in times]
    if missing:
        raise ValueError(f"{where}.shard_time: no shard_time for r = {', '.join(missing)}")
    return grid, times
