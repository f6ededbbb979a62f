"""Equilibrium and ExactEquilibrium as Python objects: they pickle, copy and cross process
boundaries answering the same numbers; the solves and w(F) are kept for every live object;
the solver settings are held to the library's bounds, which the config's schema and README
repeat; ``check`` is held to the accuracy target it states; r given as a numpy scalar."""

import collections
import copy
import operator
import pickle
import re
import weakref
from concurrent.futures import ProcessPoolExecutor
from fractions import Fraction

import numpy as np
import pytest
import yaml
from workflow_support import REPOSITORY

import bouncing_ball as bb
from bouncing_ball import distribution, solver
from bouncing_ball.equilibrium import (
    KEPT_SOLVES,
    QUADRATURE_STEP_RANGE,
    WEIGHT_PANEL_NODES_RANGE,
    check_solver_settings,
    solved,
)
from bouncing_ball.workflow import solver_tables

X = np.array([1e-3, 0.1, 1.0, 10.0])
V = np.array([-2.0, 0.5, 3.0])


@pytest.fixture(scope="module")
def half():
    """Equilibrium at r = 1/2 with everything a copy could carry computed (w(F), accuracy)."""
    eq = bb.Equilibrium("1/2")
    eq.px(1.0), eq.accuracy, eq.position_accuracy
    return eq


def _answers(eq) -> dict:
    """What the object answers, method by method."""
    return {
        "p0v": eq.p0v(V[1:]),
        "px": eq.px(X),
        "v2_given_x": eq.v2_given_x(X),
        "pxv": eq.pxv(X[:, None], V),
        "weight": eq.weight(X),
        "flight_time_density": eq.flight_time_density(X),
        "observables": np.array(list(eq.observables().values())),
        "position_accuracy": eq.position_accuracy,
    }


def _same_answers(copied, original):
    ours, theirs = _answers(copied), _answers(original)
    for name, value in theirs.items():
        np.testing.assert_array_equal(ours[name], value, err_msg=name)


def _no_rebuilding(monkeypatch):
    """Make a solve, an accuracy estimate or a w(F) build fail the test."""

    def refuse(*args, **kwargs):
        raise AssertionError("rebuilt what the copy carries")

    monkeypatch.setattr(solved, "_solution", refuse)
    monkeypatch.setattr(solver, "accuracy_estimate", refuse)
    monkeypatch.setattr(distribution, "interpolated_weight_function", refuse)


@pytest.mark.parametrize(
    "duplicate",
    [
        lambda eq: pickle.loads(pickle.dumps(eq)),
        lambda eq: pickle.loads(pickle.dumps(eq, protocol=0)),
        copy.copy,
        copy.deepcopy,
    ],
    ids=["pickle", "pickle-protocol-0", "copy", "deepcopy"],
)
def test_a_copy_answers_the_same_numbers_without_solving_again(duplicate, half, monkeypatch):
    _no_rebuilding(monkeypatch)
    copied = duplicate(half)
    assert type(copied) is bb.Equilibrium and copied is not half
    assert (copied.restitution, copied.quadrature_step, copied.weight_panel_nodes) == (
        half.restitution,
        half.quadrature_step,
        half.weight_panel_nodes,
    )
    assert copied.accuracy == half.accuracy
    _same_answers(copied, half)
    assert repr(copied) == repr(half)


@pytest.mark.parametrize("duplicate", [lambda eq: pickle.loads(pickle.dumps(eq)), copy.deepcopy])
def test_an_exact_equilibrium_copies(duplicate):
    exact = bb.ExactEquilibrium("1/2")
    copied = duplicate(exact)
    assert type(copied) is bb.ExactEquilibrium
    _same_answers(copied, exact)


def test_an_equilibrium_crosses_process_boundaries(half):
    """Sent to a worker and back (the worker's answer and the object it returns)."""
    with ProcessPoolExecutor(max_workers=1) as pool:
        px = pool.submit(operator.methodcaller("px", X), half).result()
        returned = pool.submit(copy.copy, half).result()
    np.testing.assert_array_equal(px, half.px(X))
    _same_answers(returned, half)


# --- the solves and w(F) are kept for every live Equilibrium


@pytest.fixture
def counted_builds(monkeypatch, half):
    """Count the solves and w(F) builds, each answering r = 1/2's (instantly), in a process
    cache of its own."""
    counts = collections.Counter()

    def solution(exact, step):
        counts["solves"] += 1
        return half.solution

    def weight_function(solution, panel_nodes):
        counts["weight functions"] += 1
        return object()

    monkeypatch.setattr(solved, "_solution", solution)
    monkeypatch.setattr(distribution, "interpolated_weight_function", weight_function)
    monkeypatch.setattr(solved, "_LIVE_SOLVES", weakref.WeakValueDictionary(), raising=False)
    monkeypatch.setattr(solved, "_RECENT_SOLVES", collections.OrderedDict(), raising=False)
    return counts


def _sweep(count, first=101):
    """``count`` r close to 0.1 that no other test asks for."""
    return [Fraction(k, 1009) for k in range(first, first + count)]


def test_a_sweep_over_more_r_than_are_kept_builds_each_once(counted_builds):
    sweep = [bb.Equilibrium(r) for r in _sweep(KEPT_SOLVES + 2)]
    for _ in range(2):
        weights = [eq.weight_function for eq in sweep]
    assert counted_builds == {"solves": len(sweep), "weight functions": len(sweep)}
    assert [eq.weight_function for eq in sweep] == weights
    again = bb.Equilibrium(sweep[0].restitution)  # the same r, while the first lives
    assert again.solution is sweep[0].solution and again.weight_function is weights[0]
    assert counted_builds["solves"] == len(sweep)


def test_a_dropped_equilibrium_is_kept_only_among_the_recent_ones(counted_builds):
    first = _sweep(1, first=200)[0]
    bb.Equilibrium(first)  # dropped at once
    bb.Equilibrium(first)
    assert counted_builds["solves"] == 1  # kept among the recent ones
    for r in _sweep(KEPT_SOLVES, first=300):
        bb.Equilibrium(r)
    bb.Equilibrium(first)
    assert counted_builds["solves"] == 2 + KEPT_SOLVES  # pushed out: its memory is freed


# --- the solver settings: one set of bounds for the library and the config


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({"quadrature_step": 1e-3}, r"quadrature_step must be a number from 0.1 to 0.3.*below"),
        ({"quadrature_step": 0.5}, r"quadrature_step .* got 0.5: above"),
        ({"quadrature_step": "0.25"}, "quadrature_step"),
        ({"weight_panel_nodes": 2}, r"weight_panel_nodes must be a whole number from 10 to 40"),
        ({"weight_panel_nodes": 4}, r"got 4: with fewer, P\(x\)"),
        ({"weight_panel_nodes": 9}, "weight_panel_nodes"),
        ({"weight_panel_nodes": 41}, "weight_panel_nodes"),
        ({"weight_panel_nodes": 12.5}, "weight_panel_nodes"),
        ({"weight_panel_nodes": True}, "weight_panel_nodes"),
    ],
)
def test_settings_outside_the_bounds_are_refused_before_any_solve(settings, match, monkeypatch):
    _no_rebuilding(monkeypatch)
    with pytest.raises(ValueError, match=match):
        bb.Equilibrium(0.6, **settings)


def test_the_bounds_themselves_are_accepted():
    for step in QUADRATURE_STEP_RANGE:
        for nodes in WEIGHT_PANEL_NODES_RANGE:
            assert check_solver_settings(step, nodes) == (step, nodes)
    assert check_solver_settings(np.float64(0.25), np.int64(12)) == (0.25, 12)
    assert check_solver_settings() == (solver.DEFAULT_STEP, distribution.PANEL_CHEBYSHEV_NODES)


def test_the_schema_and_the_config_readme_carry_the_library_bounds():
    schema = yaml.safe_load((REPOSITORY / "workflow/schemas/config.schema.yaml").read_text())
    section = schema["properties"]["solver"]["properties"]
    readme = (REPOSITORY / "config/README.md").read_text()
    for name, bounds in (
        ("quadrature_step", QUADRATURE_STEP_RANGE),
        ("weight_panel_nodes", WEIGHT_PANEL_NODES_RANGE),
    ):
        assert (section[name]["minimum"], section[name]["maximum"]) == bounds
        row = next(line for line in readme.splitlines() if line.startswith(f"| `solver.{name}`"))
        low, high = re.search(r"(\d+(?:\.\d+)?) to (\d+(?:\.\d+)?)", row).groups()
        assert (float(low), float(high)) == bounds, row


# --- check() is held to the accuracy it states


def test_check_refuses_a_position_accuracy_beyond_its_target():
    """w(F) on 4 panel nodes (set past the settings check) puts P(x) 1e-5 off at r = 1/3."""
    eq = bb.Equilibrium("1/3")
    eq.weight_panel_nodes = 4
    assert eq.position_accuracy > solver.ACCURACY_TARGET
    with pytest.raises(
        ValueError, match=r"r = 0.333333: .*position_accuracy = .*weight_panel_nodes = 4"
    ):
        solver_tables.check(eq, {})


# --- r as a numpy scalar


def test_r_may_be_a_numpy_scalar(half):
    assert bb.Equilibrium(np.float32(0.5)).solution is half.solution
    assert bb.ExactEquilibrium(np.float64(0.5)).restitution == Fraction(1, 2)
    with pytest.raises(ValueError, match=r"^r: r = np.int64\(1\) is outside"):
        bb.Equilibrium(np.int64(1))
