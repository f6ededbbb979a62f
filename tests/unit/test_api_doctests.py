"""The Examples of the public API's and the physics modules' docstrings run as doctests (cheap
ones: the exact solutions, the solve at r = 1/2, tiny simulations, and pure numpy/scipy
functions; none compiles a numba function)."""

import doctest
import importlib

import pytest

MODULES = [
    "bouncing_ball.equilibrium",
    "bouncing_ball.monte_carlo",
    "bouncing_ball.asymptotics",
    "bouncing_ball.bins",
    "bouncing_ball.comparison",
    "bouncing_ball.equilibration",
    "bouncing_ball.fits",
    "bouncing_ball.flight_time",
    "bouncing_ball.jit",
    "bouncing_ball.settings",
]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name, capsys):
    module = importlib.import_module(name)
    result = doctest.testmod(
        module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False
    )
    report = capsys.readouterr().out
    assert result.attempted > 0, f"{name} has no Examples"
    assert result.failed == 0, report
