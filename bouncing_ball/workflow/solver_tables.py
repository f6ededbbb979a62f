"""Rule solve's tables and checks (``results/solver/r{r}/``), built from an equilibrium object.

The tables take any ``bouncing_ball.EquilibriumBase``: an ``Equilibrium`` (what rule solve
writes) or an ``ExactEquilibrium`` (the paper's r = 1/2 and 1/3, for comparison).  The summary
row and its checks describe a solve (its residuals, the error of its interpolated w(F), the
exponents measured on it) and take an ``Equilibrium``.
"""

import math

import numpy as np

from ..restitution import restitution_label

__all__ = [
    "label",
    "summary",
    "check",
    "p0v_table",
    "position_table",
    "distribution_table",
    "weight_table",
    "flight_time_table",
    "return_speed_table",
]


def label(equilibrium) -> str:
    """The label the workflow files r's outputs under (``restitution.restitution_label``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase

    Returns
    -------
    str

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> from bouncing_ball.workflow.solver_tables import label
    >>> label(ExactEquilibrium("1/3"))
    '0.333333'
    """
    return restitution_label(equilibrium.restitution)


def _solve(equilibrium, what: str):
    """``equilibrium`` if it is an ``Equilibrium`` (a solve), else TypeError naming ``what``."""
    from ..equilibrium import Equilibrium

    if not isinstance(equilibrium, Equilibrium):
        raise TypeError(
            f"{what} describes a solve of eq. (inteq) and takes an Equilibrium, got "
            f"{type(equilibrium).__name__}"
        )
    return equilibrium


def _relaxation_columns(equilibrium) -> dict:
    """The summary's ``relaxation.RELAXATION_COLUMNS``: NaN at r <= r_c."""
    from ..asymptotics import CRITICAL_RESTITUTION
    from ..relaxation import RELAXATION_COLUMNS

    if equilibrium.r <= CRITICAL_RESTITUTION:
        return dict.fromkeys(RELAXATION_COLUMNS, math.nan)
    return {
        "relaxation_eigenvalue": equilibrium.relaxation_eigenvalue,
        "relaxation_eigenvalue_accuracy": equilibrium.relaxation_accuracy,
        "continuum_edge": equilibrium._relaxation.continuum_edge,
        "correlation_bounces": equilibrium.correlation_bounces,
        "relaxation_time": equilibrium.relaxation_time,
    }


def summary(equilibrium) -> dict:
    """Rule solve's summary row of a solve.

    ``solver.solution_summary`` (with the accuracy estimate), the collision statistics
    (``flight_time.flight_time_summary``), <x>, Delta x and the normalisation from P(x)
    (eqs. (P(x)1), (xandDeltax)), the interpolation error of w(F)
    (``WeightFunction.interpolation_error``), the measured and predicted exponents of P(x)
    with the large-x fit window (``distribution.measured_exponents``), and the relaxation of
    the bounce-speed chain (``relaxation.RELAXATION_COLUMNS``; NaN below r_c).

    Parameters
    ----------
    equilibrium : bouncing_ball.Equilibrium
        The solve, r in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``.

    Returns
    -------
    dict
        One row of ``results/solver/r{r}/summary.parquet``.

    Raises
    ------
    TypeError
        For an equilibrium that is not an ``Equilibrium`` (it has no solve to describe).
    ValueError
        Above ``restitution.DISTRIBUTION_RESTITUTION_RANGE`` (no w(F) there).

    Examples
    --------
    >>> from bouncing_ball import Equilibrium
    >>> from bouncing_ball.workflow.solver_tables import summary
    >>> row = summary(Equilibrium("1/2"))  # doctest: +SKIP
    >>> print(f"{row['mean_x']:.8f} {row['mean_x_from_position']:.8f}")  # doctest: +SKIP
    6.00000000 6.00000000
    """
    from .. import distribution, flight_time, solver

    eq = _solve(equilibrium, "summary")
    eq._check_distribution("summary")
    row = solver.solution_summary(eq.solution, with_accuracy_estimate=False)
    row["accuracy_estimate"] = eq.accuracy
    collisions = flight_time.flight_time_summary(eq.solution)
    row.update({key: value for key, value in collisions.items() if key not in row})
    weight = eq.weight_function
    averages = eq._position_averages
    row["position_normalization"] = averages["normalization"]
    row["mean_x_from_position"] = averages["mean_x"]
    row["delta_x_from_position"] = averages["delta_x"]
    row["weight_interpolation_error"] = weight.interpolation_error
    measured = distribution.measured_exponents(weight)
    for key, value in distribution.predicted_exponents(eq.restitution).items():
        row[f"{key}_measured"], row[f"{key}_predicted"] = measured[key], value
    row["large_x_window_lo"], row["large_x_window_hi"] = measured["large_x_window"]
    row.update(_relaxation_columns(eq))
    return row


def check(equilibrium, tables, row=None) -> None:
    """Rule solve's checks of its tables and summary row, held to ``solver.ACCURACY_TARGET``.

    ``accuracy`` (P(0, v) against a finer solve) and ``position_accuracy`` (int P dx = 1, and
    <x>, Delta x from P(x) of eq. (P(x)1) against the Ito identities) within the target; then
    ``distribution.check_solve_tables``: no NaN where a value is defined and no infinity
    anywhere, the moments from P(x) equal the Ito ones, the measured exponents within their
    tolerance of the predicted ones.

    Parameters
    ----------
    equilibrium : bouncing_ball.Equilibrium
        The solve.
    tables : dict of str to pandas.DataFrame
        Any of p0v, flight_time, return_speed, position, distribution, weight, as the table
        functions here give them.
    row : dict, optional
        The solve's ``summary`` (None: computed).

    Returns
    -------
    None

    Raises
    ------
    TypeError
        For an equilibrium that is not an ``Equilibrium``.
    ValueError
        Naming r and every check that fails: first ``accuracy`` and ``position_accuracy``
        beyond the target (with the settings), then the tables' (naming the table and column).

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball import Equilibrium
    >>> from bouncing_ball.workflow import solver_tables
    >>> eq = Equilibrium("1/2")
    >>> table = solver_tables.flight_time_table(eq, [1.0, 2.0])
    >>> table.loc[1, "rate_density"] = np.inf
    >>> solver_tables.check(eq, {"flight_time": table})  # doctest: +SKIP
    Traceback (most recent call last):
    ...
    ValueError: r = 0.5: the solver's tables fail their checks: flight_time: 1 of 2 rate_density are infinite ...
    """
    from .. import distribution, solver

    eq = _solve(equilibrium, "check")
    target = solver.ACCURACY_TARGET
    misses = [
        f"{name} = {value:.1e}"
        for name, value in (
            ("accuracy", eq.accuracy),
            ("position_accuracy", eq.position_accuracy),
        )
        if not value <= target
    ]
    if misses:
        raise ValueError(
            f"r = {label(eq)}: the solve misses the {target:.0e} accuracy target: "
            + ", ".join(misses)
            + f" (quadrature_step = {eq.quadrature_step:g}, weight_panel_nodes = "
            f"{eq.weight_panel_nodes}; docs/distribution.md#where-it-degrades)"
        )
    distribution.check_solve_tables(label(eq), summary(eq) if row is None else row, tables, target)


def _positive(values, name):
    """``values`` as a float array, each > 0 and finite (ValueError naming ``name``)."""
    values = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(values) & (values > 0.0)):
        raise ValueError(f"{name} must be finite and > 0")
    return values


def p0v_table(equilibrium, speeds):
    """P(0, v) of eq. (inteq) (eq. (P(0,v)) for the exact solutions) as a table
    (``results/solver/r{r}/p0v``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
    speeds : array_like
        Outgoing speeds, v >= ``equilibrium.smallest_speed`` and v > 0.

    Returns
    -------
    pandas.DataFrame
        Columns v, p0v.

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> from bouncing_ball.workflow.solver_tables import p0v_table
    >>> p0v_table(ExactEquilibrium("1/2"), [1.0, 2.0]).round(6)
         v       p0v
    0  1.0  0.122626
    1  2.0  0.022556
    """
    import pandas as pd

    speeds = _positive(speeds, "speeds")
    return pd.DataFrame({"v": speeds, "p0v": equilibrium.p0v(speeds)})


def position_table(equilibrium, positions):
    """P(x) and <v^2>_x, eqs. (P(x)1), (moment2), as a table (``results/solver/r{r}/position``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
    positions : array_like
        Heights, x > 0, within the domain of ``px``.

    Returns
    -------
    pandas.DataFrame
        Columns x, px, v2_given_x.

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> from bouncing_ball.workflow.solver_tables import position_table
    >>> position_table(ExactEquilibrium("1/2"), [0.1, 1.0]).round(6)
         x        px  v2_given_x
    0  0.1  0.503776    1.853157
    1  1.0  0.183784    3.710784
    """
    from .. import distribution

    equilibrium._check_distribution("position_table")
    positions = _positive(positions, "positions")
    equilibrium.px(positions)  # the domain's checks
    return distribution.position_table(equilibrium.weight_function, positions)


def distribution_table(equilibrium, positions, speeds):
    """P(x, v), eq. (fpsol), on the grid of ``positions`` and ``speeds``, with the largest
    relative error quad estimates for it (``results/solver/r{r}/distribution``;
    ``distribution.distribution_table`` of the object's w(F) and P(0, v)).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
    positions : array_like
        Heights, x >= 0.
    speeds : array_like
        Velocities (either sign), finite.

    Returns
    -------
    table : pandas.DataFrame
        Columns x, v, pxv, one row per (x, v), v fastest (NaN at x = v = 0).
    worst : float
        The largest relative error estimate of the F integrals.

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> from bouncing_ball.workflow.solver_tables import distribution_table
    >>> table, worst = distribution_table(ExactEquilibrium("1/2"), [0.1], [-1.0, 1.0])
    >>> print(table["pxv"].to_numpy().round(6), worst < 1e-8)
    [0.074292 0.146809] True
    """
    from .. import distribution

    equilibrium._check_distribution("distribution_table")
    positions = np.asarray(positions, dtype=float)
    speeds = np.asarray(speeds, dtype=float)
    if not np.all(np.isfinite(positions) & (positions >= 0.0)):
        raise ValueError("positions must be finite and >= 0")
    if not np.all(np.isfinite(speeds)):
        raise ValueError("speeds must be finite")
    return distribution.distribution_table(
        equilibrium.weight_function, equilibrium.solution, positions, speeds
    )


def weight_table(equilibrium, forces):
    """w(F) of eq. (weightfunc) as a table (``results/solver/r{r}/weight``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
    forces : array_like
        F > 0, finite.

    Returns
    -------
    pandas.DataFrame
        Columns F, w, log_w (log_w stays finite where w over- or underflows).

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> from bouncing_ball.workflow.solver_tables import weight_table
    >>> weight_table(ExactEquilibrium("1/2"), [1.0]).round(6)
         F         w     log_w
    0  1.0  0.153341 -1.875093
    """
    from .. import distribution

    equilibrium._check_distribution("weight_table")
    return distribution.weight_table(equilibrium.weight_function, _positive(forces, "forces"))


def flight_time_table(equilibrium, times):
    """The flight-time densities of eq. (rate) and their short- and long-time forms,
    eqs. (short), (long1), (long2) (``flight_time.flight_time_table``;
    ``results/solver/r{r}/flight_time``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
    times : array_like
        Flight times, T > 0 and at least the bounds of ``flight_rate_density`` and
        ``flight_time_density`` (every value of the table is finite).  The pipeline writes
        ``flight_time.FLIGHT_TIME_TABLE_RANGE`` (config ``solver.flight_times``).

    Returns
    -------
    pandas.DataFrame
        Columns t, density, rate_density, time_weighted_density, short_time_form,
        long_time_form.

    Raises
    ------
    ValueError
        If a T is not positive, or below a bound.

    Examples
    --------
    >>> from bouncing_ball import Equilibrium
    >>> from bouncing_ball.workflow.solver_tables import flight_time_table
    >>> flight_time_table(Equilibrium("1/2"), [1.0])["density"].round(6).tolist()
    [0.196832]
    """
    from .. import flight_time

    times = _positive(times, "times")
    for per_collision in (False, True):  # nu(T) and rho(T) finite
        equilibrium._flight_times(times, "times", per_collision=per_collision)
    return flight_time.flight_time_table(equilibrium.solution, times)


def return_speed_table(equilibrium, speed_bins):
    """The return-speed law v G_g(v, u) of eq. (kernel3) averaged over a simulation's speed
    bins, with u weighted by the collision rate u P(0, u) in its bin
    (``flight_time.return_speed_table``; ``results/solver/r{r}/return_speed``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
    speed_bins : bins.LogBins
        The bins of the outgoing and return speeds (``settings.ShardSettings.speed_bins``).

    Returns
    -------
    pandas.DataFrame
        Columns u_lo, u_hi, v_lo, v_hi, probability.

    Examples
    --------
    >>> from bouncing_ball import Equilibrium
    >>> from bouncing_ball.bins import LogBins
    >>> from bouncing_ball.workflow.solver_tables import return_speed_table
    >>> table = return_speed_table(Equilibrium("1/2"), LogBins(0.1, 10.0, 1))
    >>> table.groupby("u_lo")["probability"].sum().round(12).tolist()
    [1.0, 1.0]
    """
    from .. import flight_time

    return flight_time.return_speed_table(equilibrium.solution, speed_bins)
