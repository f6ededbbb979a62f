"""P(x, v) next to the floor at large v from the solver (bouncing_ball.near_wall) at r where only
the F integral of eq. (fpsol) is an independent computation: the two agree where both work, and
the pipeline's grid of speeds (|v| up to 22 / q) is answered at x = 0.0126 and 1.26.  Slow: each
r builds w(F) (``python -m benchmarks`` times it)."""

import numpy as np
import pytest

from bouncing_ball import Equilibrium
from bouncing_ball.asymptotics import large_speed_decay_rate
from bouncing_ball.distribution import DISTRIBUTION_NOISE, distribution_by_force_rule
from bouncing_ball.near_wall import NEAR_WALL_REACH, distribution_near_wall, near_wall_points
from bouncing_ball.workflow.solver_tables import distribution_table


@pytest.mark.parametrize("r", [0.5, 0.95, 0.99])
def test_the_series_matches_the_force_integral_where_both_work(r):
    """At v = 6 / q and 22 / q, x from 2e-8 v^3 (inside the F integral's reach) to
    NEAR_WALL_REACH v^3: the series from the solver's P(0, v) against the fixed rule from its
    w(F), within DISTRIBUTION_NOISE of the largest P(x, v) at that x plus both error
    estimates."""
    eq = Equilibrium(r)
    q = large_speed_decay_rate(r)
    for v in (6.0 / q, 22.0 / q):
        x = np.array([2e-8, 1e-7, 5e-7, 0.99 * NEAR_WALL_REACH]) * v**3
        near, near_error = distribution_near_wall(x, v, eq.solution.outgoing_speed_density, r)
        for xi, value, value_error in zip(x, near, near_error):
            speeds = np.array([v, 0.3 * xi ** (1 / 3), xi ** (1 / 3), 3.0 * xi ** (1 / 3)])
            rule, rule_error = distribution_by_force_rule(xi, speeds, eq.weight_function)
            allowed = DISTRIBUTION_NOISE * rule.max() + rule_error[0] + value_error
            assert abs(value - rule[0]) <= allowed


@pytest.mark.parametrize("r", [0.95, 0.99])
def test_the_pipeline_grid_is_answered_next_to_the_floor(r):
    """The solve rule's P(x, v) table at x = 0.0126 and 1.26 for |v| up to 22 / q, which reaches
    past the F integral's speeds there (r = 0.95 at x = 0.0126 from v = 91; r = 0.99 at 1.26
    from v = 420; at 0.95, x = 1.26 it reaches them all): every value finite and positive, and pxv the same numbers."""
    eq = Equilibrium(r)
    top = 22.0 / large_speed_decay_rate(r)
    speeds = np.linspace(-top, top, 41)
    positions = np.array([0.012589, 1.2589])
    table, _ = distribution_table(eq, positions, speeds)
    values = table["pxv"].to_numpy().reshape(positions.size, speeds.size)
    assert near_wall_points(positions[:, None], speeds[None, :])[0].any()
    assert np.all(np.isfinite(values)) and np.all(values > 0.0)
    np.testing.assert_array_equal(eq.pxv(positions[:, None], speeds[None, :]), values)
