"""``compare``: an equilibrium object against a simulation's result, for a notebook."""

from fractions import Fraction

import numpy as np
import pandas as pd

from .checks import POSITION_RANGE, _shard_deviations
from .sign_flip import order_free_mean, shard_ratios, sign_flip_test

__all__ = [
    "compare",
    "COMPARED_SCALARS",
    "COMPARE_COLUMNS",
]

# exact, fits and histograms (scipy, numba) are imported by the functions that use them: the
# moments and position tables need none of them


# ---------------------------------------------------------------------------------------------
# an equilibrium object against a simulation's result, for a notebook

#: The scalars ``compare`` holds against the equilibrium, with their symbols.
COMPARED_SCALARS = {
    "mean_x": "<x>",
    "delta_x": "Delta x",
    "collision_rate": "I",
    "mean_flight_time": "<T>",
    "flight_time_second_moment": "<T^2>",
}
#: The columns of ``compare``'s table.
COMPARE_COLUMNS = (
    "quantity",
    "estimator",
    "equilibrium",
    "simulation",
    "simulation_err",
    "z",
    "dof",
    "bins",
    "chi2_per_bin",
    "p_sign_flip",
)


def _scalar_rows(equilibrium, summary, dof):
    """The rows of ``compare`` of the scalars: plain, martingale-controlled (independent of the
    theory: the estimate that judges agreement) and controlled (with eq. (kernel3) where the
    summary's ``kernel3_controls`` says so), each where finite."""
    rows = []
    for quantity in COMPARED_SCALARS:
        reference = float(getattr(equilibrium, quantity))
        for estimator, column in (
            ("plain", quantity),
            ("martingale", f"{quantity}_martingale"),
            ("controlled", f"{quantity}_controlled"),
        ):
            if column not in summary:
                continue
            value, error = float(summary[column]), float(summary[f"{column}_err"])
            if not (np.isfinite(value) and np.isfinite(error) and error > 0.0):
                continue
            rows.append(
                {
                    "quantity": quantity,
                    "estimator": estimator,
                    "equilibrium": reference,
                    "simulation": value,
                    "simulation_err": error,
                    "z": (value - reference) / error if np.isfinite(reference) else np.nan,
                    "dof": dof,
                }
            )
    return rows


def _table_row(quantity, simulated, errors, reference, deviations):
    """The row of ``compare`` of one table: chi^2 per bin of z = (simulation - reference) /
    error (``order_free_mean``) and the sign-flip p of the shards' ``deviations``."""
    z = (simulated - reference) / errors
    return {
        "quantity": quantity,
        "estimator": "plain",
        "bins": len(z),
        "chi2_per_bin": float(order_free_mean(np.square(z))) if len(z) else np.nan,
        "p_sign_flip": sign_flip_test(deviations)[1] if len(z) else np.nan,
    }


def compare(equilibrium, result) -> pd.DataFrame:
    """A simulation held against an equilibrium object, as the validation table holds it.

    The z of every scalar, and the chi^2 per bin and sign-flip p of each table.

    The two must be in the same units (``units``, of ``Equilibrium(r, gravity=, noise=)`` and
    ``simulate(..., gravity=, noise=)``); the scalars' columns are in them.

    The scalars <x>, Delta x, I, <T>, <T^2> (eqs. (xandDeltax), (collrate), (meanT),
    (meanT2)), plain, martingale-controlled (``independent_estimate``: the one that judges
    agreement) and controlled with eq. (kernel3), each where the result has a finite estimate:
    z = (simulation - equilibrium) / simulation_err, the error the delete-one jackknife's
    over the shards, so z has a Student t law with at most ``dof`` = shards - 1 degrees of
    freedom (fewer after the control fits).

    The tables P(0, v), P(x) and <v^2>_x, each bin against the equilibrium's average over it
    (``EquilibriumBase.p0v_bin_average``, ``px_bin_average``, ``v2_given_x_bin_average``),
    over the bins the validation table uses: those with a finite error > 0, for P(0, v) not
    the under- and overflow bins, for P(x) and <v^2>_x inside ``POSITION_RANGE``.  chi^2 per
    bin is the mean of z^2 (the bins are correlated, so it need not be near 1); p_sign_flip is
    ``sign_flip_test`` of the shards' shares of the deviation (``ratio_deviations`` of
    ``shard_ratios``), which carries those correlations.  P(x) and <v^2>_x only where the
    equilibrium computes them (``distribution_available``).

    Parameters
    ----------
    equilibrium : EquilibriumBase
        ``Equilibrium(r)`` or ``ExactEquilibrium(r)``, of the result's r.
    result : SimulationResult
        ``simulate``'s result, with at least 2 shards.

    Returns
    -------
    pandas.DataFrame
        Columns ``COMPARE_COLUMNS``: one row per scalar and estimator (quantity, estimator,
        equilibrium, simulation, simulation_err, z, dof) and one per table (quantity p0v, px,
        v2_given_x; bins, chi2_per_bin, p_sign_flip); NaN where a column does not apply.

    Raises
    ------
    ValueError
        If the two are of different r or units, or the result has fewer than 2 shards.

    Examples
    --------
    >>> import bouncing_ball as bb
    >>> sim = bb.simulate(0.5, shards=4, shard_time=500.0, seed=2, progress=False)
    >>> table = bb.compare(bb.ExactEquilibrium("1/2"), sim)
    >>> table.loc[table.estimator == "plain", "quantity"].tolist()
    ['mean_x', 'delta_x', 'collision_rate', 'mean_flight_time', 'flight_time_second_moment', 'p0v', 'px', 'v2_given_x']
    >>> print(table.dof.max())
    3
    """
    if Fraction(equilibrium.restitution) != Fraction(result.restitution):
        raise ValueError(
            f"result: simulated at r = {result.restitution}, the equilibrium is at "
            f"r = {equilibrium.restitution}"
        )
    if equilibrium.units != result.units:
        raise ValueError(
            f"result: simulated in {result.units}, the equilibrium is in {equilibrium.units}; "
            "give both the same gravity and noise"
        )
    if result.shards < 2:
        raise ValueError(f"result: needs at least 2 shards for errors, got {result.shards}")
    shards = list(result.tallies)
    per_shard = shard_ratios(shards)
    rows = _scalar_rows(equilibrium, result.summary_table.iloc[0], result.shards - 1)

    # the tables in the paper's units, as the shards' tallies are (their rows have no dimension)
    equilibrium = equilibrium._paper_twin()
    p0v = result._p0v_paper
    usable = (
        (p0v.v_lo >= max(equilibrium.smallest_speed, np.finfo(float).tiny))
        & np.isfinite(p0v.v_hi)
        & np.isfinite(p0v.p0v_err)
        & (p0v.p0v_err > 0.0)
    ).to_numpy()
    bins = p0v[usable]
    reference = np.atleast_1d(
        equilibrium.p0v_bin_average(bins.v_lo.to_numpy(), bins.v_hi.to_numpy())
    )
    deviations = _shard_deviations(
        per_shard, "p0v", np.flatnonzero(usable), reference, result.shards
    )
    rows.append(
        _table_row("p0v", bins.p0v.to_numpy(), bins.p0v_err.to_numpy(), reference, deviations)
    )

    if equilibrium.distribution_available:
        position = result._position_paper
        low, high = POSITION_RANGE
        inside = (
            (position.x_lo >= low * (1.0 - 1e-9))
            & (position.x_hi <= high * (1.0 + 1e-9))
            & np.isfinite(position.x_hi)
        )
        for quantity, bin_average in (
            ("px", equilibrium.px_bin_average),
            ("v2_given_x", equilibrium.v2_given_x_bin_average),
        ):
            error = position[f"{quantity}_err"]
            compared = (inside & np.isfinite(error) & (error > 0.0)).to_numpy()
            bins = position[compared]
            reference = np.atleast_1d(bin_average(bins.x_lo.to_numpy(), bins.x_hi.to_numpy()))
            deviations = _shard_deviations(
                per_shard, quantity, np.flatnonzero(compared), reference, result.shards
            )
            rows.append(
                _table_row(
                    quantity,
                    bins[quantity].to_numpy(),
                    bins[f"{quantity}_err"].to_numpy(),
                    reference,
                    deviations,
                )
            )
    return pd.DataFrame(rows, columns=list(COMPARE_COLUMNS)).astype(
        {"dof": "Int64", "bins": "Int64"}
    )
