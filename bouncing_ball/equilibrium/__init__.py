"""The equilibrium state at one r, as one object: ``Equilibrium`` (any r the solver answers)
and ``ExactEquilibrium`` (the paper's r = 1/2 and 1/3 solutions), with the same attributes and
methods, so that one can stand in for the other.

``Equilibrium(r)`` solves eq. (inteq) for P(0, v) once, with the given quadrature step
(``distribution.outgoing_speed_solution``: its nodes reach where P(0, v) falls to e^-690, as
w(F) at small F needs), and builds the weight function w(F) of eq. (weightfunc) from that
solution (``distribution``) the first time a position-dependent quantity is asked for (P(x),
<v^2>_x, P(x, v), w(F)).  The solve and w(F) are shared by every ``Equilibrium`` of the same r
and settings in a process, and kept for as long as any of them lives (and for the last
``KEPT_SOLVES`` asked for besides).  The settings are held to where the 1e-8 accuracy target is
met (``QUADRATURE_STEP_RANGE``, ``WEIGHT_PANEL_NODES_RANGE``, ``check_solver_settings``; the
config's ``solver`` section is checked by the same function).  It is the workflow's solve rule
(scripts/solve.py writes its tables to ``results/solver/r{r}/``), so every number is the one
the rule writes for the same settings.  Above ``restitution.DISTRIBUTION_RESTITUTION_RANGE``
(up to ``SOLVER_RESTITUTION_RANGE``) it gives P(0, v), the time averages, the flight times and the
exponents, and its position-dependent methods raise ValueError naming r and the range.

Its accuracy is measured, not assumed: ``accuracy`` is the solver's own estimate, the largest
relative change of P(0, v) for 1e-3 <= v <= 20 against a finer solve
(``solver.accuracy_estimate``); ``position_accuracy`` is how far int P(x) dx, <x> and Delta x
from P(x) of eq. (P(x)1) are from 1 and from the Ito identities of the solver (a test of the
whole w(F) route).

Every method takes arrays and broadcasts like numpy (a scalar in, a numpy scalar out).  Input
that has no answer (a negative height, a NaN, shapes that do not broadcast) raises ValueError
naming the argument; nothing returns a silent NaN.

Both classes pickle and copy (``copy.copy``, ``copy.deepcopy``), so they cross process
boundaries (multiprocessing, joblib): an ``Equilibrium`` travels with its solve and whatever it
has computed from it (kilobytes), and the copy answers the same numbers without solving again.

Importing this module loads neither scipy nor numba (the config check of every workflow start
uses ``check_solver_settings``); the solver loads them on first use.  The modules:

- ``checks``: the settings ``Equilibrium`` accepts (``check_solver_settings``) and the checks of
  every method's arguments;
- ``base``: ``EquilibriumBase``, every public method and property both classes share;
- ``solved``: ``Equilibrium``, from the solver's P(0, v) and its w(F);
- ``closed_form``: ``ExactEquilibrium``, from the paper's exact solutions (``bouncing_ball.exact``).

Every name is importable from ``bouncing_ball.equilibrium`` itself.
"""

from .base import (
    EquilibriumBase,
)
from .checks import (
    EXACT_ACCURACY,
    QUADRATURE_STEP_RANGE,
    SPEED_PANEL,
    WEIGHT_PANEL_NODES_RANGE,
    check_solver_settings,
)
from .closed_form import (
    ExactEquilibrium,
)
from .solved import (
    KEPT_SOLVES,
    Equilibrium,
)

__all__ = [
    "EquilibriumBase",
    "Equilibrium",
    "ExactEquilibrium",
    "EXACT_ACCURACY",
    "SPEED_PANEL",
    "QUADRATURE_STEP_RANGE",
    "WEIGHT_PANEL_NODES_RANGE",
    "KEPT_SOLVES",
    "check_solver_settings",
]
