"""The time averages from the shards' sums: I, <x>, Delta x, <T>, <T^2>, plain and controlled."""

import numpy as np
import pandas as pd

from ..tallies import (
    ShardTallies,
    merge_shards,
)
from .control_variates import (
    _FLIGHT_LAW_SHARDS,
    _controlled,
    _restitution_float,
    flight_law_prediction,
    moment_controls,
)
from .jackknife import jackknife

__all__ = [
    "CONTROLLED_MOMENTS",
    "position_moments_summary",
]


def _mean_x(int_x, time):
    return int_x / time


def _delta_x(int_x, int_x2, time):
    return np.sqrt(int_x2 / time - (int_x / time) ** 2)


#: The moments ``position_moments_summary`` also gives corrected by the control variates of
#: ``moment_controls`` (its columns ``{name}_controlled``).
CONTROLLED_MOMENTS = ("mean_x", "delta_x", "mean_flight_time", "flight_time_second_moment")


# each moment as a function of the sums of the collisions, int x dt, int x^2 dt, the
# flights, sum T and sum T^2, and of the times
_MOMENT_ESTIMATORS = {
    "collision_rate": lambda c, ix, ix2, n, f, f2, t: c / t,
    "mean_x": lambda c, ix, ix2, n, f, f2, t: _mean_x(ix, t),
    "delta_x": lambda c, ix, ix2, n, f, f2, t: _delta_x(ix, ix2, t),
    "mean_flight_time": lambda c, ix, ix2, n, f, f2, t: f / n,
    "flight_time_second_moment": lambda c, ix, ix2, n, f, f2, t: f2 / n,
}


def _controlled_moments(controls, time, sums, suffix):
    """The columns ``{moment}_{suffix}`` and ``{moment}_{suffix}_err`` of every moment of
    ``_MOMENT_ESTIMATORS``, its sums ``sums`` adjusted by ``controls`` (NaN where None)."""
    columns = {}
    for name, estimator in _MOMENT_ESTIMATORS.items():
        value, error = _controlled(estimator, controls, time, sums, [time])
        columns[f"{name}_{suffix}"] = [float(value)]
        columns[f"{name}_{suffix}_err"] = [float(error)]
    return columns


def position_moments_summary(
    shards: list[ShardTallies], restitution, outgoing_density=None
) -> pd.DataFrame:
    """One row of moments: <x>, Delta x, the collision rate I and the flight time's moments.

    <x> and Delta x are eq. (xandDeltax), I eq. (collrate); the flight time T has its mean and
    second moment per flight.  Each is given three times:

    - plain: the time averages, collisions per time, the flights' averages;
    - ``*_martingale``: the same with each sum (the collisions, int x dt, int x^2 dt, the
      flights, sum T, sum T^2) corrected before the ratio by the martingale control
      variates of ``moment_controls`` without a flight law (``tallies.MOMENT_CONTROLS`` or
      the fewer ``tallies.RATE_CONTROLS``, as many as the shards can fit,
      ``shard_controls``; NaN with too few shards).  Their mean is 0 for the simulated
      process whatever it is, so the estimate has the plain one's expectation
      (``control_variate_adjusted``) with less variance: with the plain one, it is
      independent of the theory it is held against;
    - ``*_controlled``: corrected by the same controls and, where r is in the solver's
      range and the shards suffice, the flight-law controls of ``flight_law_prediction``
      (``kernel3_controls`` True).  Those are built from E[T | u] and E[T^2 | u] of
      eq. (kernel3), the theory under test: their mean is 0 only if the simulated process
      follows it, so a simulation that departs from eq. (kernel3) shifts this estimate by
      more or less than its own departure.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards.
    restitution : fractions.Fraction or float
        The shards' r as parsed (``restitution.parse_restitution``), 0 < r < 1, written in
        column ``r``.
    outgoing_density : callable, optional
        P(0, u) of the theory the ``*_controlled`` columns lean on, given by the caller (the
        solver's, ``solver.solved_outgoing_density``): it weighs the fine bins of the
        flight-law controls.  Without it those controls are left out (``kernel3_controls``
        False).  The estimators never solve eq. (inteq) themselves.

    Returns
    -------
    pandas.DataFrame
        One row: ``r``; ``mean_x``, ``delta_x``, ``collision_rate``, ``mean_flight_time``,
        ``flight_time_second_moment``, each with ``_err``, ``_martingale``,
        ``_martingale_err``, ``_controlled`` and ``_controlled_err``; ``kernel3_controls``
        (whether ``_controlled`` uses the flight-law controls of eq. (kernel3)); the totals
        ``flights``, ``total_time``, ``collisions``, ``steps``, ``shards`` and
        ``shards_out_of_budget``; ``control_variates``, the number of controls fitted to the
        shards for the ``_controlled`` values (0: none, and those are NaN).

    Raises
    ------
    TypeError
        If ``restitution`` is not parsed (a string).
    ValueError
        If r is outside (0, 1).

    Examples
    --------
    See the module's example.
    """
    time = np.array([s.time for s in shards])
    int_x = np.array([s.int_x for s in shards])
    int_x2 = np.array([s.int_x2 for s in shards])
    collisions = np.array([s.collisions for s in shards], dtype=float)
    mean_x, mean_x_err = jackknife(_mean_x, int_x, time)
    delta_x, delta_x_err = jackknife(_delta_x, int_x, int_x2, time)
    rate, rate_err = jackknife(lambda c, t: c / t, collisions, time)
    flight_law = None
    r = _restitution_float(restitution)
    if outgoing_density is not None and len(shards) >= _FLIGHT_LAW_SHARDS:  # else too few
        flight_law = flight_law_prediction(shards, outgoing_density)
    flights = np.array([s.flights for s in shards], dtype=float)
    flight_time = np.array([s.flight_time_sum for s in shards])
    flight_time_squared = np.array([s.flight_time_squared_sum for s in shards])
    mean_t, mean_t_err = jackknife(lambda f, n: f / n, flight_time, flights)
    second_t, second_t_err = jackknife(lambda f, n: f / n, flight_time_squared, flights)
    sums = (collisions, int_x, int_x2, flights, flight_time, flight_time_squared)
    martingale = moment_controls(shards)
    controls = moment_controls(shards, flight_law)
    # the flight-law controls in use: the *_controlled columns lean on eq. (kernel3)
    kernel3 = controls is not None and martingale is not None
    kernel3 = kernel3 and controls.shape[1] > martingale.shape[1]
    estimates = {
        **_controlled_moments(martingale, time, sums, "martingale"),
        **_controlled_moments(controls, time, sums, "controlled"),
    }
    total = merge_shards(shards)
    return pd.DataFrame(
        {
            "r": [r],
            "mean_x": [float(mean_x)],
            "mean_x_err": [float(mean_x_err)],
            "delta_x": [float(delta_x)],
            "delta_x_err": [float(delta_x_err)],
            "collision_rate": [float(rate)],
            "collision_rate_err": [float(rate_err)],
            "mean_flight_time": [float(mean_t)],
            "mean_flight_time_err": [float(mean_t_err)],
            "flight_time_second_moment": [float(second_t)],
            "flight_time_second_moment_err": [float(second_t_err)],
            **estimates,
            "kernel3_controls": [bool(kernel3)],
            "flights": [int(total.flights)],
            "total_time": [float(total.time)],
            "collisions": [int(total.collisions)],
            "steps": [int(total.steps)],
            "shards": [len(shards)],
            "shards_out_of_budget": [int(total.budget_exhausted)],
            "control_variates": [0 if controls is None else int(np.shape(controls)[1])],
        }
    )
