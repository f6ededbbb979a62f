"""The solver near r = 1 against the quasi-elastic forms of bouncing_ball.quasi_elastic: I, <x>,
Delta x and the scaled P(0, v) at r = 0.99, 0.999, 0.9999 approach their limits with the
predicted first correction.  Split from the unit tier because each r costs a solve of eq. (inteq)."""

import numpy as np
import pytest

import bouncing_ball as bb
from bouncing_ball import quasi_elastic as qe

RESTITUTIONS = qe.TABLE_RESTITUTIONS


@pytest.mark.parametrize("r", RESTITUTIONS)
@pytest.mark.parametrize("name", ["collision_rate", "mean_x", "delta_x"])
def test_first_correction_matches_the_solver(name, r):
    """c1 measured = (solver / leading - 1) / epsilon is the predicted c1 plus c2 epsilon +
    O(epsilon^2): within 2 |c2| epsilon (the factor 2 leaves room for |c3| epsilon < |c2|).  The
    solver's own error (1e-8 relative at most) adds 1e-8 / epsilon^2 <= 1e-4 |c2| at 0.9999."""
    epsilon = qe.quasi_elastic_epsilon(r)
    scaling = qe.SCALINGS[name]
    solver = getattr(bb.Equilibrium(r), name)
    measured = (solver / qe.quasi_elastic_form(name, r, order=0) - 1.0) / epsilon
    assert measured == pytest.approx(scaling.first, abs=2.0 * abs(scaling.second) * epsilon)


def _second_order_room(w, epsilon):
    """2 epsilon^2 (1/w + 1 + w^2): the room for the epsilon^2 term of the scaled P(0, v).  The
    solver's c2(w) = (scaled / limit - 1 - epsilon p1(w)) / epsilon^2 is the same at r = 0.99,
    0.999, 0.9999 to 2 % (19 at w = 0.1, -2.4 at w ~ 2.5, 113 at w = 12): it grows like 1/w at
    small w, where P(0, v) crosses over to v^-beta, and like w^2 at large w; over
    0.1 <= w <= 12 it lies within 1.78 (1/w + 1 + w^2), so the factor 2 leaves some room."""
    return 2.0 * epsilon**2 * (1.0 / w + 1.0 + w**2)


@pytest.mark.parametrize("r", RESTITUTIONS)
def test_scaled_speed_density_collapses_onto_the_limit_with_the_first_correction(r):
    """epsilon^-3 P(0, w / epsilon) against (27/32) e^(-3w/2) (1 + epsilon p1(w)),
    p1 = 5/2 - 3w/2, for 0.1 <= w <= 12: within the second order's room
    (``_second_order_room``).  A wrong p1 fails: 5/2 - w (the slope of q(r) left out), p1 + 0.1
    and the limit alone (p1 = 0) are each outside that room at some w."""
    epsilon = qe.quasi_elastic_epsilon(r)
    w = np.geomspace(0.1, 12.0, 25)
    scaled = bb.Equilibrium(r).p0v(w / epsilon) / epsilon**3
    ratio = scaled / qe.scaled_speed_density(w)
    room = _second_order_room(w, epsilon)
    p1 = qe.speed_density_first_correction(w)
    assert np.all(np.abs(ratio - 1.0 - epsilon * p1) <= room)
    for wrong in (2.5 - w, p1 + 0.1, 0.0 * w):
        assert np.any(np.abs(ratio - 1.0 - epsilon * wrong) > room), wrong


def test_the_table_holds_every_quantity_at_every_r():
    """``quasi_elastic_table``: one row per quantity and r, measured c1 next to the predicted."""
    table = qe.quasi_elastic_table()
    quantities = 3 + len(qe.TABLE_SCALED_SPEEDS)
    assert len(table) == quantities * len(RESTITUTIONS)
    assert set(table["r"]) == set(RESTITUTIONS)
    assert np.all(np.isfinite(table[["scaled", "limit", "c1_measured", "c1_predicted"]]))


def test_scaled_speed_curves_approach_the_limit_with_the_first_correction():
    """Fig. 13's table: at r = 0.999 the measured first coefficient is the predicted p1(w) up to
    O(epsilon) c2 with |c2| below the p1's size at these w (the tests above bound it more
    tightly at more r); the limit column is the limiting law, and bad w is refused."""
    w = np.array([0.3, 1.0, 3.0])
    curves = qe.scaled_speed_curves([0.999], w)
    assert list(curves.columns) == [
        "r", "epsilon", "w", "scaled_p0v", "limit", "c1_measured", "c1_predicted"
    ]  # fmt: skip
    assert np.allclose(curves.limit, qe.scaled_speed_density(w), rtol=1e-15)
    epsilon = 1e-3
    assert np.all(
        np.abs(curves.c1_measured - curves.c1_predicted) < 2.0 * epsilon * (5 + 3 * w) ** 2
    )
    for bad in ([0.0, 1.0], [np.inf], [[1.0]], []):
        with pytest.raises(ValueError, match="scaled_speeds"):
            qe.scaled_speed_curves([0.999], bad)


@pytest.fixture(scope="module", params=[0.01, 0.005])
def process_relaxation(request):
    """The tilted bounce operator's rate at r = 1 - epsilon and its error estimate."""
    from bouncing_ball.time_relaxation import time_relaxation, time_relaxation_accuracy

    relaxation = time_relaxation(1.0 - request.param)
    return request.param, relaxation, time_relaxation_accuracy(relaxation)


def test_the_relaxation_time_approaches_64_over_9_eps2_with_the_first_correction(
    process_relaxation,
):
    """1 / gamma = (64/9) epsilon^-2 (1 + c1 epsilon + c2 epsilon^2 + ...) with c1 = -1: the
    measured c1 = (epsilon^2 / (gamma 64/9) - 1) / epsilon within 2 |c2| epsilon (the fitted
    c2 of SCALINGS, the factor 2 room for the next order) plus 3 times the solver's error
    estimate over epsilon (``time_relaxation_accuracy``, relative, in gamma and 1 / gamma
    alike).  The leading order alone is held within |c1| epsilon + 2 |c2| epsilon^2 of 1: a
    constant 8/3 (the bounce chain's) fails that; a first correction of the other sign, or
    -epsilon/2, fails the second (by 2 and 0.5, against tolerances below 0.02)."""
    epsilon, relaxation, accuracy = process_relaxation
    scaling = qe.SCALINGS["relaxation_time"]
    assert relaxation.isolated
    assert qe.relaxation_time(1.0 - epsilon) == pytest.approx(scaling.limit * epsilon**-2)
    ratio = relaxation.time / qe.relaxation_time(1.0 - epsilon)
    numerical = 3.0 * accuracy
    next_order = 2.0 * abs(scaling.second) * epsilon
    assert ratio == pytest.approx(1.0, abs=(1.0 + next_order) * epsilon + numerical)
    measured = (ratio - 1.0) / epsilon
    print(f"epsilon = {epsilon}: c1 = {measured:.5f}, accuracy {accuracy:.2g}")
    assert measured == pytest.approx(scaling.first, abs=next_order + numerical / epsilon)
