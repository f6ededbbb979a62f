"""The settings ``Equilibrium`` accepts, and the checks of what its methods are given:
real arrays, heights, bins, each refused with a ValueError naming the argument."""

import numbers

import numpy as np

from ..units import PhysicalUnits

__all__ = [
    "EXACT_ACCURACY",
    "SPEED_PANEL",
    "QUADRATURE_STEP_RANGE",
    "WEIGHT_PANEL_NODES_RANGE",
    "check_solver_settings",
]

#: The solver's trapezoidal step h in s = ln v + v^(1/2) that ``Equilibrium`` and rule solve
#: accept (the config's ``solver.quadrature_step``), bounds included.  Up to 0.3 P(0, v)
#: (``Equilibrium.accuracy``) and P(x) (``Equilibrium.position_accuracy``) meet the 1e-8 target
#: at every r of ``DISTRIBUTION_RESTITUTION_RANGE``; the error grows like exp(-2 pi^2 / (3 h))
#: and misses it from 0.4 on (2e-5 at 0.5).  Below 0.1 the error is already at rounding, while
#: the solver's dense matrices grow like h^-2 (h = 1e-3 exhausts the memory).
QUADRATURE_STEP_RANGE = (0.1, 0.3)
#: The Chebyshev nodes per panel of ln F of the interpolated w(F) that ``Equilibrium`` and rule
#: solve accept (the config's ``solver.weight_panel_nodes``), bounds included.  From 10, P(x)
#: meets the 1e-8 target at every r of ``DISTRIBUTION_RESTITUTION_RANGE`` with a margin of more
#: than ten (``position_accuracy`` and P(x) against 16 nodes, r from 0.02 to 0.9 in steps of
#: 0.02, and 0.99, where the step 0.3 and 10 nodes hold ``position_accuracy`` at ~3e-11); at 9 the margin is 2.5, at 8 P(x) misses it (3e-8 at r = 0.15).  Above 40 the cost
#: grows with nothing to gain.
WEIGHT_PANEL_NODES_RANGE = (10, 40)
#: The widest panel in ln v of ``Equilibrium.p0v_bin_average``'s Gauss-Legendre rule
#: (``bins.outgoing_speed_bin_average`` on each panel): a bin wider than this is split.
SPEED_PANEL = 0.5
#: ``ExactEquilibrium.accuracy``: the relative tolerance its quadratures are asked for and
#: meet (the time averages and flight times against the solver at its finest settings,
#: tests/unit/test_equilibrium.py); P(0, v) and, at r = 1/2, P(x) are closed forms.
EXACT_ACCURACY = 1e-11


# ---------------------------------------------------------------------------------------------
# input checks


def _why_outside(value, bounds, above: str, below: str) -> str:
    """Why a number outside a setting's ``bounds`` is refused (nothing for another value)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return ""
    low, high = bounds
    return f": {above}" if value > high else f": {below}" if value < low else ""


def check_solver_settings(quadrature_step=None, weight_panel_nodes=None, where: str = ""):
    """The solver settings of ``Equilibrium`` and of rule solve, checked: the step within
    ``QUADRATURE_STEP_RANGE``, the panel nodes a whole number within
    ``WEIGHT_PANEL_NODES_RANGE``, where P(0, v) of eq. (inteq) and P(x) of eq. (P(x)1) meet the
    1e-8 accuracy target.  The config check (``workflow.config.check_config``) calls it on the
    config's ``solver`` section.

    Parameters
    ----------
    quadrature_step : float, optional
        The solver's trapezoidal step in s = ln v + v^(1/2), 0.1 <= step <= 0.3 (None:
        ``solver.DEFAULT_STEP``).
    weight_panel_nodes : int, optional
        Chebyshev nodes per panel of the interpolated w(F), 10 to 40 (None:
        ``distribution.PANEL_CHEBYSHEV_NODES``).
    where : str, optional
        Put before the names in errors (``"solver."`` for the config).

    Returns
    -------
    quadrature_step : float
    weight_panel_nodes : int

    Raises
    ------
    ValueError
        Naming the setting, its value and its range.

    Examples
    --------
    >>> from bouncing_ball.equilibrium import check_solver_settings
    >>> check_solver_settings(0.25, 12)
    (0.25, 12)
    >>> check_solver_settings(0.25, 4, where="solver.")
    Traceback (most recent call last):
    ...
    ValueError: solver.weight_panel_nodes must be a whole number from 10 to 40, got 4: ...
    """
    if quadrature_step is None:
        from .. import solver

        quadrature_step = solver.DEFAULT_STEP
    if weight_panel_nodes is None:
        from .. import distribution

        weight_panel_nodes = distribution.PANEL_CHEBYSHEV_NODES
    step, nodes = quadrature_step, weight_panel_nodes
    low, high = QUADRATURE_STEP_RANGE
    if isinstance(step, bool) or not isinstance(step, numbers.Real) or not low <= step <= high:
        raise ValueError(
            f"{where}quadrature_step must be a number from {low} to {high}, got {step!r}"
            + _why_outside(
                step,
                QUADRATURE_STEP_RANGE,
                "above, P(0, v) misses the 1e-8 accuracy target",
                "below, the solver's matrices outgrow the memory with nothing to gain",
            )
            + " (equilibrium.QUADRATURE_STEP_RANGE)"
        )
    low, high = WEIGHT_PANEL_NODES_RANGE
    if (
        isinstance(nodes, bool)
        or not isinstance(nodes, numbers.Integral)
        or not low <= nodes <= high
    ):
        raise ValueError(
            f"{where}weight_panel_nodes must be a whole number from {low} to {high}, got {nodes!r}"
            + _why_outside(
                nodes,
                WEIGHT_PANEL_NODES_RANGE,
                "more cost more with nothing to gain",
                "with fewer, P(x) of eq. (P(x)1) misses the 1e-8 accuracy target",
            )
            + " (equilibrium.WEIGHT_PANEL_NODES_RANGE)"
        )
    return float(step), int(nodes)


def _real_array(value, name: str) -> np.ndarray:
    """``value`` as a float array; TypeError naming ``name`` if it is not real numbers,
    ValueError if it holds NaN or an infinity."""
    try:
        array = np.asarray(value)
    except ValueError as error:  # ragged nested lists
        raise ValueError(f"{name}: not an array of numbers ({error})") from None
    if array.dtype == bool or not (
        np.issubdtype(array.dtype, np.integer) or np.issubdtype(array.dtype, np.floating)
    ):
        raise TypeError(f"{name} must be real numbers, got {value!r} (dtype {array.dtype})")
    array = array.astype(float)
    if np.isnan(array).any():
        raise ValueError(f"{name} contains NaN")
    if np.isinf(array).any():
        raise ValueError(f"{name} must be finite, got an infinity")
    return array


def _checked(value, name: str, *, low: float | None = None, strictly: bool = False) -> np.ndarray:
    """``_real_array`` refusing values below ``low`` (or at it, when ``strictly``)."""
    array = _real_array(value, name)
    if low is not None:
        bad = array <= low if strictly else array < low
        if bad.any():
            relation = ">" if strictly else ">="
            raise ValueError(
                f"{name} must be {relation} {low:g}, got {array[bad].flat[0]:g}"
                + (f" at index {np.argwhere(bad)[0].tolist()}" if array.ndim else "")
            )
    return array


#: The paper's units, g = Lambda = 1.
_PAPER_UNITS = PhysicalUnits()


def _heights(value, name: str, units: PhysicalUnits = _PAPER_UNITS) -> np.ndarray:
    """``_checked`` heights in ``units``, in the paper's units: x = 0, or
    ``distribution.SMALLEST_POSITION`` <= x / L <= ``distribution.LARGEST_POSITION``
    (ValueError naming ``name`` and the bounds in ``units``)."""
    from ..distribution import LARGEST_POSITION, SMALLEST_POSITION

    x = _checked(value, name, low=0.0)
    paper = units.to_paper(x, "length")
    bad = ((x > 0.0) & (paper < SMALLEST_POSITION)) | (paper > LARGEST_POSITION)
    if bad.any():
        raise ValueError(
            f"{name} = {x[bad].flat[0]:g} is outside the heights computed: x = 0 or "
            f"{units.to_physical(SMALLEST_POSITION, 'length'):g} <= x <= "
            f"{units.to_physical(LARGEST_POSITION, 'length'):g} "
            "(distribution.SMALLEST_POSITION, LARGEST_POSITION" + _in_units(units, "length") + ")"
        )
    return paper


def _in_units(units: PhysicalUnits, dimension: str) -> str:
    """How a bound of the paper's units is shown in ``units`` (nothing in the paper's)."""
    return "" if units.is_paper else f", times the unit of {dimension}"


def _broadcast(first, second, names):
    """The two arrays broadcast together; ValueError naming both if their shapes do not."""
    try:
        return np.broadcast_arrays(first, second)
    except ValueError:
        raise ValueError(
            f"{names[0]} (shape {first.shape}) and {names[1]} (shape {second.shape}) do not "
            "broadcast to one shape"
        ) from None


def _out(array):
    """A numpy scalar for a 0-d result, the array otherwise."""
    return array[()] if array.ndim == 0 else array
