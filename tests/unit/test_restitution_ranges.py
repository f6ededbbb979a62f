"""The two ranges of r, each checked in one place (``restitution.check_solver_range``,
``restitution.check_distribution_range``): every public entry point refuses an r outside its
range with the message of that range, before it solves anything."""

import pytest
from workflow_support import REPOSITORY

import bouncing_ball as bb
from bouncing_ball import distribution, quasi_elastic, relaxation, solver
from bouncing_ball.restitution import (
    DISTRIBUTION_RESTITUTION_RANGE,
    SOLVER_RESTITUTION_RANGE,
    check_distribution_range,
    check_solver_range,
)
from bouncing_ball.workflow.config import check_config, read_yaml

SOLVER_MESSAGE = (
    r"is outside the solver's range of r, "
    rf"{SOLVER_RESTITUTION_RANGE[0]} <= r <= {SOLVER_RESTITUTION_RANGE[1]}"
)
DISTRIBUTION_MESSAGE = (
    r"is outside the range of r where P\(x, v\) is verified, "
    rf"{DISTRIBUTION_RESTITUTION_RANGE[0]} <= r <= {DISTRIBUTION_RESTITUTION_RANGE[1]}"
)
# below both ranges, above the solver's, and between the two upper bounds (the solver answers,
# the whole distribution is not verified)
BELOW, ABOVE_THE_SOLVER, ABOVE_THE_DISTRIBUTION = "1/100", 0.99995, 0.9995


@pytest.mark.parametrize(
    "solve",
    [
        solver.solve_outgoing_speed_density,
        relaxation.bounce_chain_relaxation,
        relaxation.continuum_edge,
        bb.Equilibrium,
        lambda r: quasi_elastic.scaled_speed_curves([r], [1.0]),
    ],
    ids=["solver", "relaxation", "continuum_edge", "Equilibrium", "scaled_speed_curves"],
)
@pytest.mark.parametrize("r", [BELOW, ABOVE_THE_SOLVER])
def test_what_solves_eq_inteq_refuses_r_outside_the_solvers_range(solve, r):
    with pytest.raises(ValueError, match=SOLVER_MESSAGE):
        solve(r)


@pytest.mark.parametrize("r", [BELOW, ABOVE_THE_SOLVER, ABOVE_THE_DISTRIBUTION])
def test_what_builds_w_refuses_r_outside_the_distributions_range(r):
    with pytest.raises(ValueError, match=DISTRIBUTION_MESSAGE):
        distribution.outgoing_speed_solution(r)


@pytest.mark.parametrize("method", ["px", "v2_given_x", "weight"])
def test_equilibrium_between_the_ranges_refuses_w_with_the_distributions_range(method):
    equilibrium = bb.Equilibrium(ABOVE_THE_DISTRIBUTION)  # solves only when asked
    assert not equilibrium.distribution_available
    with pytest.raises(ValueError, match=DISTRIBUTION_MESSAGE):
        getattr(equilibrium, method)(1.0)


def test_the_config_refuses_each_r_with_its_range():
    config = read_yaml(REPOSITORY / "config" / "config.yaml")
    config["restitution"] = [0.5, ABOVE_THE_DISTRIBUTION]  # every r of a run is solved whole
    with pytest.raises(ValueError, match=r"restitution\[1\]: .*" + DISTRIBUTION_MESSAGE):
        check_config(config)
    config = read_yaml(REPOSITORY / "config" / "config.yaml")
    config["figures"]["fig13"] = [ABOVE_THE_SOLVER]  # P(0, v) alone
    with pytest.raises(ValueError, match=r"figures.fig13\[0\]: .*" + SOLVER_MESSAGE):
        check_config(config)


@pytest.mark.parametrize(
    "check, bounds",
    [
        (check_solver_range, SOLVER_RESTITUTION_RANGE),
        (check_distribution_range, DISTRIBUTION_RESTITUTION_RANGE),
    ],
)
def test_each_range_holds_its_bounds_exactly(check, bounds):
    """The bounds are decimals read as written (0.02 is 1/50): both are inside, and the
    neighbouring fractions outside."""
    from fractions import Fraction

    for bound in bounds:
        assert check(bound) == Fraction(str(bound))
    with pytest.raises(ValueError):
        check(Fraction(str(bounds[0])) - Fraction(1, 10**12))
    with pytest.raises(ValueError):
        check(Fraction(str(bounds[1])) + Fraction(1, 10**12))
