"""Rule solve's tables and checks (``results/solver/r{r}/``), built from an equilibrium object.

The tables take any ``bouncing_ball.EquilibriumBase``: an ``Equilibrium`` (what rule solve
writes) or an ``ExactEquilibrium`` (the paper's r = 1/2 and 1/3, for comparison).  The summary
row and its checks describe a solve (its residuals, the error of its interpolated w(F), the
exponents measured on it) and take an ``Equilibrium``.
"""

import math

import numpy as np

from ..restitution import DISTRIBUTION_RESTITUTION_RANGE, restitution_label

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
    "DISTRIBUTION_TABLES",
    "outside_fractions",
    "weight_frame",
    "position_frame",
    "distribution_frame",
    "EXPONENT_TOLERANCES",
    "solve_table_defects",
    "check_solve_tables",
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


def _in_paper_units(equilibrium):
    """``equilibrium`` if it is in the paper's units (g = Lambda = 1), those of rule solve's
    tables; else ValueError naming the argument and its units."""
    units = equilibrium.units
    if units.gravity != 1.0 or units.noise != 1.0:
        raise ValueError(
            f"equilibrium: rule solve's tables are in the paper's units (g = Lambda = 1), but "
            f"this {type(equilibrium).__name__} is in units of gravity = {units.gravity:g}, "
            f"noise = {units.noise:g}; build it with the defaults gravity=1.0, noise=1.0"
        )
    return equilibrium


def _solve(equilibrium, what: str):
    """``equilibrium`` if it is an ``Equilibrium`` (a solve), else TypeError naming ``what``."""
    from ..equilibrium import Equilibrium

    if not isinstance(equilibrium, Equilibrium):
        raise TypeError(
            f"{what} describes a solve of eq. (inteq) and takes an Equilibrium, got "
            f"{type(equilibrium).__name__}"
        )
    return _in_paper_units(equilibrium)


def _relaxation_columns(equilibrium) -> dict:
    """The summary's ``relaxation.RELAXATION_COLUMNS`` (the bounce chain) and
    ``time_relaxation.TIME_RELAXATION_COLUMNS`` (the process in time): NaN at r <= r_c."""
    from ..asymptotics import CRITICAL_RESTITUTION
    from ..relaxation import RELAXATION_COLUMNS
    from ..time_relaxation import TIME_RELAXATION_COLUMNS

    if equilibrium.r <= CRITICAL_RESTITUTION:
        return dict.fromkeys(RELAXATION_COLUMNS + TIME_RELAXATION_COLUMNS, math.nan)
    return {
        "relaxation_eigenvalue": equilibrium.relaxation_eigenvalue,
        "relaxation_eigenvalue_accuracy": equilibrium.relaxation_accuracy,
        "continuum_edge": equilibrium._relaxation.continuum_edge,
        "correlation_bounces": equilibrium.correlation_bounces,
        "bounce_chain_time": equilibrium.bounce_chain_time,
        "relaxation_rate": equilibrium.relaxation_rate,
        "relaxation_rate_accuracy": equilibrium.relaxation_rate_accuracy,
        "large_speed_edge": equilibrium._time_relaxation.large_speed_edge,
        "relaxation_time": equilibrium.relaxation_time,
    }


def summary(equilibrium) -> dict:
    """Rule solve's summary row of a solve.

    ``solver.solution_summary`` (with the accuracy estimate), the collision statistics
    (``flight_time.flight_time_summary``), <x>, Delta x and the normalisation from P(x)
    (eqs. (P(x)1), (xandDeltax)), the interpolation error of w(F)
    (``WeightFunction.interpolation_error``), the measured and predicted exponents of P(x)
    with the large-x fit window (``distribution.measured_exponents``), and the relaxation of
    the bounce-speed chain and of the process in time (``relaxation.RELAXATION_COLUMNS``,
    ``time_relaxation.TIME_RELAXATION_COLUMNS``; NaN below r_c).

    Parameters
    ----------
    equilibrium : bouncing_ball.Equilibrium
        The solve, r in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``, in the paper's units
        (gravity = noise = 1, the defaults).

    Returns
    -------
    dict
        One row of ``results/solver/r{r}/summary.parquet``.

    Raises
    ------
    TypeError
        For an equilibrium that is not an ``Equilibrium`` (it has no solve to describe).
    ValueError
        Above ``restitution.DISTRIBUTION_RESTITUTION_RANGE`` (no w(F) there), or for an
        equilibrium in other units than the paper's.

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
    ``check_solve_tables``: no NaN where a value is defined and no infinity
    anywhere, the moments from P(x) equal the Ito ones, the measured exponents within their
    tolerance of the predicted ones.

    Parameters
    ----------
    equilibrium : bouncing_ball.Equilibrium
        The solve, in the paper's units (gravity = noise = 1, the defaults).
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
        For an equilibrium in other units than the paper's; naming r and every check that fails: first ``accuracy`` and ``position_accuracy``
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
    from .. import solver

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
    check_solve_tables(label(eq), summary(eq) if row is None else row, tables, target)


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
        In the paper's units (gravity = noise = 1, the defaults): ValueError otherwise.
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
    equilibrium = _in_paper_units(equilibrium)
    import pandas as pd

    speeds = _positive(speeds, "speeds")
    return pd.DataFrame({"v": speeds, "p0v": equilibrium.p0v(speeds)})


def position_table(equilibrium, positions):
    """P(x) and <v^2>_x, eqs. (P(x)1), (moment2), as a table (``results/solver/r{r}/position``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
        In the paper's units (gravity = noise = 1, the defaults): ValueError otherwise.
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
    equilibrium = _in_paper_units(equilibrium)

    equilibrium._check_distribution("position_table")
    positions = _positive(positions, "positions")
    equilibrium.px(positions)  # the domain's checks
    return position_frame(equilibrium.weight_function, positions)


def distribution_table(equilibrium, positions, speeds):
    """P(x, v), eq. (fpsol), on the grid of ``positions`` and ``speeds``, with the largest
    relative error quad estimates for it (``results/solver/r{r}/distribution``;
    ``distribution_frame`` of the object's w(F) and P(0, v)).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
        In the paper's units (gravity = noise = 1, the defaults): ValueError otherwise.
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
    equilibrium = _in_paper_units(equilibrium)

    equilibrium._check_distribution("distribution_table")
    positions = np.asarray(positions, dtype=float)
    speeds = np.asarray(speeds, dtype=float)
    if not np.all(np.isfinite(positions) & (positions >= 0.0)):
        raise ValueError("positions must be finite and >= 0")
    if not np.all(np.isfinite(speeds)):
        raise ValueError("speeds must be finite")
    return distribution_frame(equilibrium.weight_function, equilibrium.solution, positions, speeds)


def weight_table(equilibrium, forces):
    """w(F) of eq. (weightfunc) as a table (``results/solver/r{r}/weight``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
        In the paper's units (gravity = noise = 1, the defaults): ValueError otherwise.
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
    equilibrium = _in_paper_units(equilibrium)

    equilibrium._check_distribution("weight_table")
    return weight_frame(equilibrium.weight_function, _positive(forces, "forces"))


def flight_time_table(equilibrium, times):
    """The flight-time densities of eq. (rate) and their short- and long-time forms,
    eqs. (short), (long1), (long2) (``flight_time.flight_time_table``;
    ``results/solver/r{r}/flight_time``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
        In the paper's units (gravity = noise = 1, the defaults): ValueError otherwise.
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
    equilibrium = _in_paper_units(equilibrium)
    from .. import flight_time

    times = _positive(times, "times")
    for per_collision in (False, True):  # nu(T) and rho(T) finite
        equilibrium._flight_times(times, "times", per_collision=per_collision)
    return flight_time.flight_time_table(equilibrium.solution, times)


#: The solver's tables that hold a distribution: {table: (its variable, the column of the
#: distribution's density over that variable, what it counts)}; ``outside_fractions``.
DISTRIBUTION_TABLES = {
    "p0v": ("v", None, "collisions"),  # v P(0, v): the collisions' outgoing speeds
    "position": ("x", "px", "time"),
    "flight_time": ("t", "density", "flights"),
}


def outside_fractions(tables: dict) -> dict:
    """How much of each distribution a solve's tables leave outside their ranges
    (``scales.tail_fractions``: each end continued by the power law of its last two points).

    Parameters
    ----------
    tables : dict
        Rule solve's tables by name; those of ``DISTRIBUTION_TABLES`` are read (the
        collisions of P(0, v) are v P(0, v)).

    Returns
    -------
    dict
        {table: {"below", "above", "outside", "counts", "lo", "hi"}}, the fractions of the
        whole and the table's range; None
        where the end's slope cannot bound its tail (below r_c, v P(0, v) ~ v^(1 - beta) is
        not integrable at 0: the collision rate is infinite, eq. (collrate)).
    """
    from ..scales import tail_fractions

    fractions = {}
    for name, (variable, column, counted) in DISTRIBUTION_TABLES.items():
        if name not in tables:
            continue
        table = tables[name]
        z = table[variable].to_numpy()
        density = z * table["p0v"].to_numpy() if column is None else table[column].to_numpy()
        below, above = tail_fractions(z, density)
        finite = [value if np.isfinite(value) else None for value in (below, above)]
        fractions[name] = {
            "below": finite[0],
            "above": finite[1],
            "outside": below + above if None not in finite else None,
            "counts": counted,
            "lo": float(z[0]),
            "hi": float(z[-1]),
        }
    return fractions


def return_speed_table(equilibrium, speed_bins):
    """The return-speed law v G_g(v, u) of eq. (kernel3) averaged over a simulation's speed
    bins, with u weighted by the collision rate u P(0, u) in its bin
    (``flight_time.return_speed_table``; ``results/solver/r{r}/return_speed``).

    Parameters
    ----------
    equilibrium : bouncing_ball.EquilibriumBase
        In the paper's units (gravity = noise = 1, the defaults): ValueError otherwise.
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
    equilibrium = _in_paper_units(equilibrium)
    from .. import flight_time

    return flight_time.return_speed_table(equilibrium.solution, speed_bins)


# ---------------------------------------------------------------------------------------------
# the tables of a weight function w(F)


def weight_frame(weight, forces):
    """w(F) of eq. (weightfunc) at ``forces``, as a table.

    Parameters
    ----------
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).
    forces : array_like
        Values of F > 0.

    Returns
    -------
    pandas.DataFrame
        Columns F, w and log_w (w over- or underflows where log_w does not).

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.workflow.solver_tables import weight_frame
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(weight_frame(weight, [0.1, 1.0]).round(6).to_string(index=False))
      F        w     log_w
    0.1 0.229053 -1.473800
    1.0 0.153341 -1.875093
    """
    import pandas as pd

    forces = np.asarray(forces, dtype=float)
    log_w = weight.log(forces)
    return pd.DataFrame({"F": forces, "w": np.exp(log_w), "log_w": log_w})


def position_frame(weight, positions):
    """P(x) of eq. (P(x)1) and <v^2>_x of eq. (moment2) at ``positions``, as a table.

    Parameters
    ----------
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).
    positions : array_like
        Heights x >= 0.

    Returns
    -------
    pandas.DataFrame
        Columns x, px and v2_given_x.

    Examples
    --------
    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.workflow.solver_tables import position_frame
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> print(position_frame(weight, [0.1, 1.0]).round(6).to_string(index=False))
      x       px  v2_given_x
    0.1 0.503776    1.853157
    1.0 0.183784    3.710784
    """
    import pandas as pd

    from ..distribution import mean_speed_squared_given_position, position_density

    x = np.asarray(positions, dtype=float)
    px = position_density(x, weight)
    return pd.DataFrame(
        {"x": x, "px": px, "v2_given_x": mean_speed_squared_given_position(x, weight)}
    )


def distribution_frame(weight, solution, positions, speeds):
    """P(x, v) of eq. (fpsol) for every x in ``positions`` and v in ``speeds``, as a table.

    Parameters
    ----------
    weight : WeightFunction or ClosedFormWeight
        w(F) of eq. (weightfunc) (``interpolated_weight_function``, or
        ``closed_form_weight_function``).
    solution : solver.OutgoingSpeedSolution
        P(0, v) of eq. (inteq), used at x = 0 and next to the floor at large v, where the F
        integral oscillates too fast (``distribution_with_error``).
    positions : array_like
        Heights x >= 0.
    speeds : array_like
        Velocities v: any, at every x (the near-wall series of eq. (fp) where x < 1.7e-8 v^3).

    Returns
    -------
    table : pandas.DataFrame
        Long format: columns x, v and pxv, x varying slowest.
    worst : float
        The largest estimated error of the table's P(x, v) (``distribution_by_force_rule``,
        ``near_wall.distribution_near_wall``) relative to the largest finite P(x, v) at its x:
        the measure of the stated accuracy, ``distribution.DISTRIBUTION_NOISE`` (the table
        spans r's scales, and a far-tail value far below the peak has a large relative error
        of no consequence).

    Raises
    ------
    ValueError
        As ``distribution_with_error``.

    Examples
    --------
    At x > 0 (``solution``, the exact P(0, v) of r = 1/2 on the solver's nodes, is not used):

    >>> from bouncing_ball.distribution import closed_form_weight_function
    >>> from bouncing_ball.workflow.solver_tables import distribution_frame
    >>> import numpy as np
    >>> from bouncing_ball import exact
    >>> weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    >>> from bouncing_ball.solver import OutgoingSpeedSolution
    >>> from bouncing_ball.solver import coordinate_of_speed, speed_of_coordinate
    >>> s = np.arange(coordinate_of_speed(1e-12), coordinate_of_speed(65.0), 0.25)
    >>> nodes = speed_of_coordinate(s)
    >>> density = exact.outgoing_speed_density(nodes, "1/2")
    >>> solution = OutgoingSpeedSolution(0.5, 1.0, 0.25, nodes, density, 1.0)
    >>> table, worst = distribution_frame(weight, solution, [0.5, 1.0], [-1.0, 1.0])
    >>> print(table.round(6).to_string(index=False), worst < 1e-9)
      x    v      pxv
    0.5 -1.0 0.042010
    0.5  1.0 0.075690
    1.0 -1.0 0.027950
    1.0  1.0 0.045491 True
    """
    import pandas as pd

    from ..distribution import distribution_with_error

    x, v = np.meshgrid(np.asarray(positions, dtype=float), speeds, indexing="ij")
    pxv, error = distribution_with_error(x, v, weight, solution)
    finite = np.isfinite(pxv) & (pxv > 0.0)
    peak = np.max(np.where(finite, pxv, 0.0), axis=1, keepdims=True)  # at each x
    relative = np.where(finite, error / np.where(peak > 0.0, peak, 1.0), 0.0)
    worst = float(np.max(relative)) if finite.any() else 0.0
    return pd.DataFrame({"x": x.ravel(), "v": v.ravel(), "pxv": pxv.ravel()}), worst


# ---------------------------------------------------------------------------------------------
# the checks of rule solve's tables

#: How far the measured exponents of P(x) (``measured_exponents``) may lie from the predicted
#: ones (``predicted_exponents``) over DISTRIBUTION_RESTITUTION_RANGE: the small-x slopes at
#: x ~ 1e-7 carry corrections of relative order x^((beta - 1)/3) (the log at r = 1/2: -0.06),
#: absolute tolerances; the large-x rate relative, its power absolute, the power checked only
#: where the fit window starts beyond 100 (1 - q)^-4 / 6, where the power law has set in (close
#: to r = 1/2 it sets in much further out than any window; there the rate is held to 10 times
#: its tolerance: 7e-4 off at r = 0.48).
EXPONENT_TOLERANCES = {
    "small_x_power": 0.1,
    "small_x_power_at_zero_speed": 0.02,
    "large_x_rate": 1e-3,
    "large_x_power": 0.01,
}


def _non_finite_defects(name, table, allowed=None) -> list:
    """'name: n of m c are NaN' for every column with NaN outside the rows ``allowed`` marks,
    and 'name: n of m c are infinite' for every column but a bin's edges (``*_lo``, ``*_hi``:
    an overflow bin ends at inf) holding +-inf (no value of rule solve's tables is infinite:
    P(0, 0) and P(x = 0, v = 0) are NaN, and every flight time is > 0)."""
    import pandas as pd

    defects = []
    for column in table.columns:
        values = pd.to_numeric(table[column], errors="coerce").to_numpy(dtype=float)
        missing = np.isnan(values) & ~(False if allowed is None else allowed(table, column))
        if missing.any():
            defects.append(f"{name}: {int(missing.sum())} of {values.size} {column} are NaN")
        if str(column).endswith(("_lo", "_hi")):
            continue
        infinite = np.isinf(values)
        if infinite.any():
            defects.append(f"{name}: {int(infinite.sum())} of {values.size} {column} are infinite")
    return defects


def solve_table_defects(summary, tables, target=1e-8) -> list:
    """What fails among the checks every table of rule solve passes before it is written.

    The checks: no infinity, and no NaN where a value is defined (P(0, 0) is not, nor rho(T)
    where I is infinite, below r_c, nor the return-speed law given a u-bin above the highest
    node, where P(0, u) underflows); no P(x, v) below -DISTRIBUTION_NOISE (or the weight_interpolation_error, where
    larger) of its largest value at that x; int P dx = 1, and <x>, Delta x from P(x) equal the
    Ito values from P(0, v), within the tolerance; every measured exponent within
    ``EXPONENT_TOLERANCES`` of its prediction.

    Parameters
    ----------
    summary : dict
        The summary row: ``solver.solution_summary`` with the averages from P(x)
        (position_normalization, mean_x_from_position, delta_x_from_position), the measured and
        predicted exponents and the large-x fit window (large_x_window_lo, large_x_window_hi).
    tables : dict of str to pandas.DataFrame
        p0v, flight_time, return_speed, position, distribution, weight.
    target : float
        The accuracy asked for (``solver.ACCURACY_TARGET``): int P dx - 1 and the moments from
        P(x) against the Ito ones are held to it.

    Returns
    -------
    list of str
        One message per failing check, naming the table or summary key and the values; empty
        if all pass.

    Examples
    --------
    The values of r = 1/2 (eq. (xandDeltax)), with int P dx off by 2e-7:

    >>> from bouncing_ball.distribution import predicted_exponents
    >>> from bouncing_ball.workflow.solver_tables import solve_table_defects
    >>> summary = {
    ...     "r": 0.5, "collision_rate": 1 / 3, "mean_x": 6.0, "delta_x": 108**0.5,
    ...     "position_normalization": 1.0 + 2e-7, "mean_x_from_position": 6.0,
    ...     "delta_x_from_position": 108**0.5, "large_x_window_lo": 384.0,
    ...     "large_x_window_hi": 33750.0,
    ... }
    >>> for key, value in predicted_exponents(0.5).items():
    ...     summary[f"{key}_measured"] = summary[f"{key}_predicted"] = value
    >>> solve_table_defects(summary, {})
    ['int P dx - 1 = 2.00e-07, beyond the tolerance 1e-08']
    """
    from ..asymptotics import large_speed_decay_rate
    from ..distribution import DISTRIBUTION_NOISE
    from ..relaxation import RELAXATION_COLUMNS
    from ..time_relaxation import TIME_RELAXATION_COLUMNS

    infinite_rate = not np.isfinite(summary["collision_rate"])
    # the relaxations of the bounce chain and of the process in time are not defined below r_c
    undefined = RELAXATION_COLUMNS + TIME_RELAXATION_COLUMNS if infinite_rate else ()
    defects = [
        f"summary: {key} is NaN"
        for key, value in summary.items()
        if isinstance(value, float) and math.isnan(value) and key not in undefined
    ]
    allowed = {
        "flight_time": lambda table, column: column == "density" and infinite_rate,
        "distribution": lambda table, column: (table.x == 0.0) & (table.v == 0.0),
        # a u-bin above the highest node, where P(0, u) is below the smallest double: the
        # probabilities given u are 0/0 there
        "return_speed": lambda table, column: table.u_lo >= summary["highest_speed"],
    }
    for name, table in tables.items():
        defects += _non_finite_defects(name, table, allowed.get(name))
    if "distribution" in tables:
        joint = tables["distribution"]
        largest = joint.pxv.abs().groupby(joint.x).transform("max").to_numpy(dtype=float)
        pxv = joint.pxv.to_numpy(dtype=float)
        # (fewer interpolation nodes of w, weight_panel_nodes, make a coarser w and more noise)
        noise = max(DISTRIBUTION_NOISE, summary.get("weight_interpolation_error", 0.0))
        negative = pxv < -noise * largest
        if negative.any():
            defects.append(
                f"distribution: {int(negative.sum())} of {pxv.size} pxv are negative beyond "
                f"{noise:.1g} of the largest at their x (down to {np.nanmin(pxv):.3g})"
            )
    tolerance = target
    for what, value in (
        ("int P dx", summary["position_normalization"]),
        ("<x> from P(x) / <x> from P(0, v)", summary["mean_x_from_position"] / summary["mean_x"]),
        (
            "Delta x from P(x) / Delta x from P(0, v)",
            summary["delta_x_from_position"] / summary["delta_x"],
        ),
    ):
        if not abs(value - 1.0) <= tolerance:
            defects.append(f"{what} - 1 = {value - 1.0:.2e}, beyond the tolerance {tolerance:.0e}")
    q = large_speed_decay_rate(summary["r"])
    # the power law holds to 1e-2 from 100 times (1 - q)^-4 / 6 on (0.011 off at r = 0.4, where
    # the window starts 9 times beyond it); at r = 1/2 itself, q = 1, from the start
    onset = 0.0 if abs(q - 1.0) < 1e-12 else 100.0 * (1.0 - q) ** -4 / 6.0
    before_onset = summary["large_x_window_lo"] < onset
    for key, allowance in EXPONENT_TOLERANCES.items():
        measured, predicted = summary[f"{key}_measured"], summary[f"{key}_predicted"]
        if key == "large_x_power" and before_onset:
            continue
        if key == "large_x_rate" and before_onset:
            allowance *= 10.0  # the fit's power is off, and the rate it fits with it
        scale = abs(predicted) if key == "large_x_rate" else 1.0
        if not abs(measured - predicted) <= allowance * scale:
            defects.append(
                f"{key} measured {measured:.6g}, predicted {predicted:.6g}: beyond the "
                f"tolerance {allowance:g}" + (" (relative)" if key == "large_x_rate" else "")
            )
    return defects


def check_solve_tables(label, summary, tables, target=1e-8) -> None:
    """Refuse the tables of rule solve if any check of ``solve_table_defects`` fails.

    Parameters
    ----------
    label : str
        r as the pipeline names it, named in the error.
    summary, tables, target
        As ``solve_table_defects``.

    Returns
    -------
    None

    Raises
    ------
    ValueError
        Naming r and every failing check.

    Examples
    --------
    The values of r = 1/2 (eq. (xandDeltax)), with int P dx off by 2e-7:

    >>> from bouncing_ball.distribution import predicted_exponents
    >>> from bouncing_ball.workflow.solver_tables import check_solve_tables
    >>> summary = {
    ...     "r": 0.5, "collision_rate": 1 / 3, "mean_x": 6.0, "delta_x": 108**0.5,
    ...     "position_normalization": 1.0 + 2e-7, "mean_x_from_position": 6.0,
    ...     "delta_x_from_position": 108**0.5, "large_x_window_lo": 384.0,
    ...     "large_x_window_hi": 33750.0,
    ... }
    >>> for key, value in predicted_exponents(0.5).items():
    ...     summary[f"{key}_measured"] = summary[f"{key}_predicted"] = value
    >>> check_solve_tables("0.5", summary, {})
    Traceback (most recent call last):
    ...
    ValueError: r = 0.5: the solver's tables fail their checks: int P dx - 1 = 2.00e-07, ...
    """
    defects = solve_table_defects(summary, tables, target)
    if defects:
        low, high = DISTRIBUTION_RESTITUTION_RANGE
        raise ValueError(
            f"r = {label}: the solver's tables fail their checks: "
            + "; ".join(defects)
            + f" (the solver is held to its accuracy for {low} <= r <= {high} at the default "
            "settings: docs/distribution.md#where-it-degrades)"
        )
