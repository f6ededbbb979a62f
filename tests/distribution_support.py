"""Shared by tests/unit/test_distribution*.py: w(F) built once per r and session, and the checks
run at every r."""

import functools
import warnings

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import distribution, solver
from bouncing_ball.asymptotics import large_speed_decay_rate


@functools.cache
def build(r):
    """(solution, WeightFunction) for r."""
    solution = distribution.outgoing_speed_solution(float(r))
    return solution, distribution.interpolated_weight_function(solution)


def check_position_moments(r):
    """int P dx = 1, <x> and <x^2> from P(x) of eq. (P(x)1) against the solver's Ito identities."""
    solution, weight = build(r)
    ito = solver.time_averages(solution)
    norm, first, second = (distribution.position_moment(k, weight) for k in (0, 1, 2))
    assert norm == pytest.approx(1.0, abs=1e-8)
    assert first == pytest.approx(ito["mean_x"], rel=1e-8)
    assert second == pytest.approx(ito["delta_x"] ** 2 + ito["mean_x"] ** 2, rel=1e-8)


def speed_moments(x, weight, solution):
    """int v^n P(x, v) dv, n = 0, 1, 2, on a composite Gauss-Legendre grid in v, and int |v| P."""
    nodes, weights = np.polynomial.legendre.leggauss(16)
    # <v^2>_x grows like x^(1/2); P(0, v) ~ e^(-q v)
    scale = max(1.0, x**0.25, 0.6 / large_speed_decay_rate(weight.restitution))
    edges = scale * np.array([-60.0, -25.0, -10.0, -4.0, -1.5, 0.0, 1.5, 4.0, 10.0, 25.0, 60.0])
    v = np.concatenate([0.5 * (b - a) * nodes + 0.5 * (b + a) for a, b in zip(edges, edges[1:])])
    w = np.concatenate([0.5 * (b - a) * weights for a, b in zip(edges, edges[1:])])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        p = distribution.distribution(x, v, weight, solution)
    return [float(np.sum(w * v**n * p)) for n in (0, 1, 2)], float(np.sum(w * np.abs(v) * p))


def check_moment_identities(r, x=0.5):
    """int P(x, v) dv = P(x), eq. (moment1), and int v^2 P(x, v) dv = int_x^inf P, eq. (moment2)."""
    solution, weight = build(r)
    (zeroth, first, second), absolute_first = speed_moments(x, weight, solution)
    assert zeroth == pytest.approx(float(distribution.position_density(x, weight)), rel=1e-6)
    assert abs(first) <= 1e-6 * absolute_first
    assert second == pytest.approx(float(distribution.position_tail(x, weight)), rel=1e-6)
