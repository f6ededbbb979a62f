"""The simulation held against the exact solutions and the solver: z-scores and residuals.

Pure functions on the tables the workflow writes; the figures (Figs. 5-7)
and results/tables/moments.{csv,md} are drawn from them.
"""

from fractions import Fraction

import numpy as np
import pandas as pd

from . import stages
from .fits import bin_averages_of_curve, usable_curve

SOURCES = stages.COMPARISON

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
    "reference",
    "z",
)


def moment_rows(label, restitution, simulation, solver, exact=None):
    """One row per time average of eq. (xandDeltax) for one r.

    ``simulation``, ``solver`` and ``exact`` are the one-row summaries of
    the merge, solve and exact stages (``exact`` None where r is not 1/2 or
    1/3).  z = (simulation - reference) / simulation_err, the reference
    being the exact value where there is one and the solver's otherwise.
    """
    paper = PAPER_VALUES.get(Fraction(restitution))
    rows = []
    for quantity in QUANTITIES:
        reference_name = "exact" if exact is not None else "solver"
        reference = float((exact if exact is not None else solver)[quantity])
        value = float(simulation[quantity])
        error = float(simulation[f"{quantity}_err"])
        z = (value - reference) / error if np.isfinite(reference) and error > 0 else np.nan
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
                "reference": reference_name,
                "z": z,
            }
        )
    return rows


def moments_table(rows) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=list(MOMENT_COLUMNS))


def _number(value, digits=6):
    return "" if not np.isfinite(value) else f"{value:.{digits}g}"


def value_with_error(value, error) -> str:
    """'3.4280 ± 0.0030': the value to the second significant digit of its error."""
    if not (np.isfinite(value) and np.isfinite(error) and error > 0):
        return _number(value)
    decimals = max(0, 1 - int(np.floor(np.log10(error))))
    return f"{value:.{decimals}f} ± {error:.{decimals}f}"


def moments_markdown(table: pd.DataFrame) -> str:
    """The moments table for a reader: value +- error, the paper's rounded numbers, z."""
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
            "z": [
                f"{z:+.2f} (vs {reference})" if np.isfinite(z) else ""
                for z, reference in zip(table.z, table.reference)
            ],
        }
    )
    return shown.to_markdown(index=False, disable_numparse=True) + "\n"


def outgoing_speed_residuals(simulated: pd.DataFrame, solver_curve: pd.DataFrame) -> pd.DataFrame:
    """(simulation - solver) / sigma for every bin of the simulated P(0, v), Fig. 7.

    ``simulated`` is a merged p0v table (bins ``v_lo``, ``v_hi``), ``solver_curve``
    the solver's ``v, p0v`` grid; the solver enters as its average over each
    bin (eq. (collrate)), like the data.  Bins without an error (no
    collisions, the under- and overflow bins) and bins beyond the solver's
    grid (or beyond where its P(0, v) underflows) are left out.
    """
    speeds, density = usable_curve(solver_curve.v.to_numpy(), solver_curve.p0v.to_numpy())
    inside = (
        (simulated.v_lo >= speeds[0])
        & (simulated.v_hi <= speeds[-1])
        & np.isfinite(simulated.p0v_err)
        & (simulated.p0v_err > 0)
    )
    bins = simulated[inside]
    reference = bin_averages_of_curve(speeds, density, bins.v_lo.to_numpy(), bins.v_hi.to_numpy())
    return pd.DataFrame(
        {
            "v": bins.v.to_numpy(),
            "v_lo": bins.v_lo.to_numpy(),
            "v_hi": bins.v_hi.to_numpy(),
            "residual": (bins.p0v.to_numpy() - reference) / bins.p0v_err.to_numpy(),
            "count": bins["count"].to_numpy(),
        }
    )
