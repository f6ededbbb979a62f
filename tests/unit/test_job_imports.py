"""Each figure and table job is a fresh process: its library modules load only what it uses."""

import subprocess
import sys
from pathlib import Path

import pytest

REPOSITORY = Path(__file__).resolve().parents[2]


def loaded(module, heavy):
    """Which of the ``heavy`` packages ``import module`` loads, in a fresh interpreter."""
    code = f"import sys, {module}; print(*[m for m in {heavy!r} if m in sys.modules])"
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=REPOSITORY, capture_output=True, text=True, check=True
    )
    return run.stdout.split()


@pytest.mark.parametrize(
    "module",
    [
        "bouncing_ball.validation",  # the moments and position tables, Fig. 7
        "bouncing_ball.simulation",  # its names load on first use (bb.load, bb.simulate)
        "bouncing_ball.workflow.plotting",  # every figure
        "bouncing_ball.asymptotics",  # r_c for Figs. 1 and 6
        "bouncing_ball.workflow.config",  # the config check at every start of the workflow
    ],
)
def test_job_libraries_load_neither_scipy_nor_numba(module):
    assert loaded(module, ("scipy", "numba")) == []
