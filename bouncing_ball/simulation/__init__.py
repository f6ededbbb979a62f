"""The Monte Carlo simulation of the paper's Sec. IV: the compiled shard loop, ``simulate``
and its ``SimulationResult``, and the transient each shard discards.

The modules, in the order they build on each other:

- ``step_tallies``: what the loop records at each step (compiled): bins, the path's tallies
  by the Brownian bridge, the floor stratum;
- ``loop``: the shard loop itself (compiled), ``simulate_shard``, and each shard's random
  streams (``shard_seed_sequence``);
- ``equilibration``: how long a shard discards before it records, and the check of the early
  part of its recording against the rest;
- ``seeds``: the root seed of a run, as given and as recorded;
- ``run``: ``simulate``, shards in this process or on several, stopped by a Ctrl-C
  (``SimulationInterrupted``);
- ``result``: ``SimulationResult``, its tables and scalars in the units of the run, ``save``
  and ``load``.

``simulate`` is the workflow's machinery, called directly: shard k of r draws from
``shard_seed_sequence(seed, label of r, k)`` (``workflow.batches.simulate_batch``), so a shard
of ``simulate`` is the workflow's shard k for the same seed and settings, whatever the number of
processes; the tables are ``estimators``' (the workflow's merge stage).

Every name is importable from ``bouncing_ball.simulation`` itself; each is loaded on first use,
so that importing the package loads neither numba (the loop) nor scipy (the equilibration
check).
"""

import importlib

__all__ = [
    "simulate",
    "SimulationResult",
    "SimulationInterrupted",
    "load",
    "DEFAULT_SETTINGS",
    "SCALARS",
    "COLUMN_DIMENSIONS",
    "MEAN_PATH_INTEGRALS",
    "POSITION",
    "JOINT",
    "FLIGHTS",
    "CONTROL_VARIATES",
    "EVERY_TALLY",
    "FLOOR_STRATUM_HEIGHT",
    "floor_stratum_end",
    "shard_seed_sequence",
    "simulate_shard",
    "ShardStop",
    "ShardStopped",
    "STOP_CHECK_STEPS",
    "early_check",
    "early_check_record",
    "early_check_message",
    "window_estimates",
    "WARN_P",
    "REFUSE_P",
    "QUANTITIES",
    "EQUILIBRATION_RELAXATION_TIMES",
    "MIN_EQUILIBRATION_TIME",
    "SHARD_RELAXATION_TIMES",
    "EquilibrationWarning",
    "equilibration_relaxation_time",
    "default_equilibration_time",
    "relaxation_time_bound",
    "equilibration_problems",
    "warn_equilibration_problems",
    "relaxation_record",
    "early_check_power",
    "early_check_power_table",
    "COLLAPSED_STEP",
    "RELAXATION_BOUND_MARGIN",
    "SYMBOLS",
    "VERDICTS",
    "PARENT_CHECK_INTERVAL",
    "WAIT_INTERVAL",
    "RESULT_KIND",
]

# public name -> the module of this package that defines it (imported on first access,
# PEP 562)
_HOMES = {
    "simulate": "run",
    "SimulationResult": "result",
    "SimulationInterrupted": "run",
    "load": "result",
    "DEFAULT_SETTINGS": "run",
    "SCALARS": "result",
    "COLUMN_DIMENSIONS": "result",
    "MEAN_PATH_INTEGRALS": "step_tallies",
    "POSITION": "step_tallies",
    "JOINT": "step_tallies",
    "FLIGHTS": "step_tallies",
    "CONTROL_VARIATES": "step_tallies",
    "EVERY_TALLY": "step_tallies",
    "FLOOR_STRATUM_HEIGHT": "step_tallies",
    "floor_stratum_end": "step_tallies",
    "shard_seed_sequence": "loop",
    "simulate_shard": "loop",
    "ShardStop": "loop",
    "ShardStopped": "loop",
    "STOP_CHECK_STEPS": "loop",
    "early_check": "equilibration",
    "early_check_record": "equilibration",
    "early_check_message": "equilibration",
    "window_estimates": "equilibration",
    "WARN_P": "equilibration",
    "REFUSE_P": "equilibration",
    "QUANTITIES": "equilibration",
    "EQUILIBRATION_RELAXATION_TIMES": "equilibration",
    "MIN_EQUILIBRATION_TIME": "equilibration",
    "SHARD_RELAXATION_TIMES": "equilibration",
    "EquilibrationWarning": "equilibration",
    "equilibration_relaxation_time": "equilibration",
    "default_equilibration_time": "equilibration",
    "relaxation_time_bound": "equilibration",
    "equilibration_problems": "equilibration",
    "warn_equilibration_problems": "equilibration",
    "relaxation_record": "equilibration",
    "early_check_power": "equilibration",
    "early_check_power_table": "equilibration",
    "COLLAPSED_STEP": "loop",
    "RELAXATION_BOUND_MARGIN": "equilibration",
    "SYMBOLS": "equilibration",
    "VERDICTS": "equilibration",
    "PARENT_CHECK_INTERVAL": "run",
    "WAIT_INTERVAL": "run",
    "RESULT_KIND": "result",
}


def __getattr__(name):
    if name in _HOMES:
        value = getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
