"""The time averages of the simulation against the exact values and the solver:
results/tables/moments.{csv,md}."""

from fractions import Fraction

import numpy as np
import pandas as pd

__all__ = [
    "moment_rows",
    "moments_table",
    "moments_markdown",
    "value_with_error",
    "independent_estimate",
    "kernel3_estimate",
    "INDEPENDENT_ESTIMATOR",
    "MOMENT_COLUMNS",
    "PAPER_VALUES",
    "QUANTITIES",
    "SYMBOLS",
]

# exact, fits and histograms (scipy, numba) are imported by the functions that use them: the
# moments and position tables need none of them


# the time averages of eq. (xandDeltax)
QUANTITIES = ("mean_x", "delta_x", "collision_rate")
SYMBOLS = {"mean_x": "<x>", "delta_x": "Delta x", "collision_rate": "I"}

# the numbers as printed in eq. (xandDeltax) (rounded there); the exact stage
# recomputes them from eqs. (P(x)2), (collrate) and (constants)
PAPER_VALUES = {
    Fraction(1, 2): {"mean_x": 6.0, "delta_x": 10.4, "collision_rate": 1.0 / 3.0},
    Fraction(1, 3): {"mean_x": 3.89, "delta_x": 7.68, "collision_rate": 3.0 / 4.0},
}

MOMENT_COLUMNS = (
    "r_label",
    "r",
    "quantity",
    "paper",
    "exact",
    "solver",
    "simulation",
    "simulation_err",
    "estimator",
    "reference",
    "z",
    "kernel3_controlled",
    "kernel3_controlled_err",
    "kernel3_z",
)

#: The estimator of each quantity in the moments table's ``simulation`` column, fixed in
#: advance and the same at every r: the summary's ``{quantity}_martingale``, corrected by the
#: martingale control variates only (their mean is 0 for the simulated process whatever it
#: is, ``estimators.position_moments_summary``), and where the shards are too few for them
#: (NaN) the plain ``{quantity}``.  Never chosen by the smaller error: a choice by a noisy
#: error picks the estimates whose errors came out low.
INDEPENDENT_ESTIMATOR = "martingale"


def independent_estimate(summary, quantity):
    """The estimate of ``quantity`` that judges agreement: independent of the theory.

    By the fixed rule of ``INDEPENDENT_ESTIMATOR``: ``{quantity}_martingale`` where the summary
    has it (finite), else the plain ``{quantity}``; estimator is "martingale" or "plain".

    Parameters
    ----------
    summary : mapping
        The merge stage's summary row.
    quantity : str
        One of ``QUANTITIES``.

    Returns
    -------
    tuple
        (value, error, estimator).

    Examples
    --------
    >>> from bouncing_ball.validation import independent_estimate
    >>> summary = {"mean_x": 6.0, "mean_x_err": 0.2, "mean_x_martingale": 6.1,
    ...            "mean_x_martingale_err": 0.3}
    >>> independent_estimate(summary, "mean_x")
    (6.1, 0.3, 'martingale')
    """
    column = f"{quantity}_{INDEPENDENT_ESTIMATOR}"
    if column in summary and np.isfinite(float(summary[column])):
        return float(summary[column]), float(summary[f"{column}_err"]), INDEPENDENT_ESTIMATOR
    return float(summary[quantity]), float(summary[f"{quantity}_err"]), "plain"


def kernel3_estimate(summary, quantity):
    """The estimate of ``quantity`` corrected with the flight-law controls of eq. (kernel3).

    The summary's ``{quantity}_controlled`` where its ``kernel3_controls`` is true, else
    (NaN, NaN): an estimate that leans on the theory it is held against, shown beside the
    independent one, never instead of it.

    Parameters
    ----------
    summary : mapping
        The merge stage's summary row.
    quantity : str
        One of ``QUANTITIES``.

    Returns
    -------
    tuple of float
        (value, error).
    """
    column = f"{quantity}_controlled"
    if column in summary and bool(summary.get("kernel3_controls", False)):
        return float(summary[column]), float(summary[f"{column}_err"])
    return np.nan, np.nan


def _z(value, error, reference):
    if np.isfinite(value) and np.isfinite(reference) and error > 0:
        return (value - reference) / error
    return np.nan


def moment_rows(label, restitution, simulation, solver, exact=None):
    """The time averages <x>, Delta x and I of eq. (xandDeltax) of one r, with their z.

    The simulation's value is the independent estimate (``independent_estimate``: the
    martingale-controlled one, or the plain one with too few shards; ``estimator`` says
    which), z = (simulation - reference) / simulation_err, the reference being the exact
    value where there is one and the solver's otherwise.  Beside it, ``kernel3_controlled``
    with its error and ``kernel3_z`` against the same reference: the estimate corrected with
    the flight-law controls of eq. (kernel3) (``kernel3_estimate``; NaN where the summary
    has none).  It leans on the theory under test, so agreement is judged on ``z``.

    Parameters
    ----------
    label : str
        The r label.
    restitution : float or fractions.Fraction
        r.
    simulation : mapping
        The merge stage's summary: each quantity and its ``<quantity>_err``, and where the
        shards allowed them ``<quantity>_martingale``, ``<quantity>_controlled`` (with
        ``_err``) and ``kernel3_controls``.
    solver : mapping
        The solve stage's summary.
    exact : mapping, optional
        The exact stage's summary (None where r is not 1/2 or 1/3).

    Returns
    -------
    list of dict
        One row per quantity, keys ``MOMENT_COLUMNS`` (with the paper's rounded numbers at
        r = 1/2 and 1/3).

    Examples
    --------
    >>> from bouncing_ball.validation import moment_rows
    >>> simulation = {"mean_x": 6.01, "mean_x_err": 0.01, "delta_x": 10.4,
    ...               "delta_x_err": 0.1, "collision_rate": 0.333, "collision_rate_err": 0.001}
    >>> exact = {"mean_x": 6.0, "delta_x": 10.39, "collision_rate": 1 / 3}
    >>> row = moment_rows("0.5", 0.5, simulation, exact, exact)[0]
    >>> print(row["quantity"], row["paper"], row["reference"], row["estimator"], round(row["z"], 6))
    mean_x 6.0 exact plain 1.0
    """
    paper = PAPER_VALUES.get(Fraction(restitution))
    rows = []
    for quantity in QUANTITIES:
        reference_name = "exact" if exact is not None else "solver"
        reference = float((exact if exact is not None else solver)[quantity])
        value, error, estimator = independent_estimate(simulation, quantity)
        kernel3, kernel3_err = kernel3_estimate(simulation, quantity)
        rows.append(
            {
                "r_label": label,
                "r": float(restitution),
                "quantity": quantity,
                "paper": paper[quantity] if paper else np.nan,
                "exact": float(exact[quantity]) if exact is not None else np.nan,
                "solver": float(solver[quantity]),
                "simulation": value,
                "simulation_err": error,
                "estimator": estimator,
                "reference": reference_name,
                "z": _z(value, error, reference),
                "kernel3_controlled": kernel3,
                "kernel3_controlled_err": kernel3_err,
                "kernel3_z": _z(kernel3, kernel3_err, reference),
            }
        )
    return rows


def moments_table(rows) -> pd.DataFrame:
    """The rows of ``moment_rows`` (of every r) as results/tables/moments.csv.

    Parameters
    ----------
    rows : list of dict
        Rows of ``moment_rows``.

    Returns
    -------
    pandas.DataFrame
        Columns ``MOMENT_COLUMNS``.
    """
    return pd.DataFrame(rows, columns=list(MOMENT_COLUMNS))


def _number(value, digits=6):
    return "" if not np.isfinite(value) else f"{value:.{digits}g}"


def value_with_error(value, error) -> str:
    """A value with its error, to the second significant digit of the error.

    Parameters
    ----------
    value, error : float
        The value and its standard error.

    Returns
    -------
    str
        "value ± error"; the value alone (6 significant digits) where the error is not
        finite and positive, "" where the value is not finite.

    Examples
    --------
    >>> from bouncing_ball.validation import value_with_error
    >>> value_with_error(3.42803, 0.003)
    '3.4280 ± 0.0030'
    >>> value_with_error(1234.5, 25.0)
    '1234 ± 25'
    """
    if not (np.isfinite(value) and np.isfinite(error) and error > 0):
        return _number(value)
    decimals = max(0, 1 - int(np.floor(np.log10(error))))
    return f"{value:.{decimals}f} ± {error:.{decimals}f}"


def moments_markdown(table: pd.DataFrame) -> str:
    """The moments table for a reader, as results/tables/moments.md.

    Parameters
    ----------
    table : pandas.DataFrame
        The table of ``moments_table``.

    Returns
    -------
    str
        A Markdown table: the paper's rounded numbers, the exact and the solver's values,
        the simulation's independent estimate (value ± error, its estimator, z), and the
        estimate controlled with eq. (kernel3) with its z.
    """
    shown = pd.DataFrame(
        {
            "r": table.r_label,
            "quantity": table.quantity.map(SYMBOLS),
            "paper, eq. (xandDeltax)": table.paper.map(lambda value: _number(value, 4)),
            "exact": table.exact.map(lambda value: _number(value, 10)),
            "solver, eq. (inteq)": table.solver.map(lambda value: _number(value, 10)),
            "simulation": [
                value_with_error(value, error)
                for value, error in zip(table.simulation, table.simulation_err)
            ],
            "estimator": table.estimator,
            "z": [
                f"{z:+.2f} (vs {reference})" if np.isfinite(z) else ""
                for z, reference in zip(table.z, table.reference)
            ],
            "controlled with eq. (kernel3)": [
                value_with_error(value, error)
                for value, error in zip(table.kernel3_controlled, table.kernel3_controlled_err)
            ],
            "z, eq. (kernel3)": [f"{z:+.2f}" if np.isfinite(z) else "" for z in table.kernel3_z],
        }
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n"
