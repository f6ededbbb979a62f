"""The asymptotics of P(x): the exponents predicted from beta, S and gamma, and those measured on P(x).

x -> 0: P(x) ~ x^((1 - beta)/3), P(x, 0) ~ x^(-beta/3).  x -> inf: P(x) ~ x^c exp(-b x^(1/2))
with b = 2 (S + 1/12)^(1/2) and c = -(gamma + 1)/2 (S and gamma of the small-F law of w(F),
``small_force_decay``, ``small_force_power``), from the saddle point F ~ ((S + 1/12)/x)^(1/2)
of eq. (P(x)1) (derivation: docs/distribution_notes.md).  ``measured_exponents`` reads the local
slopes of the computed P(x) and P(x, 0) at both ends.
"""

import numpy as np
import pandas as pd

from ..asymptotics import small_speed_exponent
from ..restitution import restitution_value as restitution_float
from .phase_space import distribution_by_force_integral
from .position import _total_decay, position_density
from .weight_function import small_force_decay, small_force_power

__all__ = [
    "predicted_exponents",
    "measured_exponents",
    "exponents_table",
]


def predicted_exponents(restitution) -> dict:
    """The asymptotic exponents of P(x) (derivation: docs/distribution_notes.md).

    x -> 0: P(x) ~ x^((1 - beta)/3) (for beta < 1: P(0) - P(x) ~ x^((1 - beta)/3)),
    P(x, 0) ~ x^(-beta/3).  x -> inf: P(x) ~ x^c exp(-b x^(1/2)) with b = 2 (S + 1/12)^(1/2)
    (S of ``small_force_decay``: b = (2/3)^(1/2) for r <= 1/2, q (2 (3 - 2q) / 3)^(1/2) above)
    and c = -(gamma + 1)/2 (gamma of ``small_force_power``: -1/2 for r < 1/2, -1/4 at r = 1/2,
    1/4 - m/2 above), from the saddle point F ~ ((S + 1/12)/x)^(1/2) of eq. (P(x)1).

    Parameters
    ----------
    restitution : float or str
        r, 0 < r < 1, a float or a fraction string ("1/3").

    Returns
    -------
    dict
        small_x_power ((1 - beta)/3), small_x_power_at_zero_speed (-beta/3), large_x_rate (b)
        and large_x_power (c).

    Examples
    --------
    At r = 1/3 P(x) ~ x^(-1/6) at small x (eq. (P(x)2)):

    >>> from bouncing_ball.distribution import predicted_exponents
    >>> print({key: round(float(value), 6) for key, value in predicted_exponents("1/3").items()})
    {'small_x_power': -0.166667, 'small_x_power_at_zero_speed': -0.5, 'large_x_rate': 0.816497,
    'large_x_power': -0.5}
    """
    restitution = restitution_float(restitution)
    beta = small_speed_exponent(restitution)
    total = small_force_decay(restitution) + 1.0 / 12.0
    return {
        "small_x_power": (1.0 - beta) / 3.0,
        "small_x_power_at_zero_speed": -beta / 3.0,
        "large_x_rate": 2.0 * np.sqrt(total),
        "large_x_power": -(small_force_power(restitution) + 1.0) / 2.0,
    }


def _local_slope(x, y):
    """d ln y / d ln x at the geometric centre of x, from a quadratic fit in ln x."""
    lx = np.log(x)
    centre = 0.5 * (lx[0] + lx[-1])
    coefficients = np.polyfit(lx - centre, np.log(y), 2)
    return float(coefficients[1])


def measured_exponents(weight, large_window=None) -> dict:
    """The exponents of ``predicted_exponents``, measured from this module's P(x) and P(x, 0).

    Small x: local slopes of ln P (of ln(P(0) - P(x)) where beta < 1) and of ln P(x, 0) against
    ln x at x ~ 1e-7.  Large x: a least-squares fit of ln P = a - b x^(1/2) + c ln x + d x^(-1/2)
    on ``large_window`` = (x_lo, x_hi) (default: where the saddle point F_s = ((S + 1/12)/x)^(1/2)
    lies between 2 F_min and (S + 1/12)/8, so that w(F) there is computed, not continued, and
    x_hi at most 75^2 / (S + 1/12)).

    Parameters
    ----------
    weight : WeightFunction
        The interpolated w(F) of eq. (weightfunc) (its beta and F_min are used).
    large_window : tuple of float, optional
        (x_lo, x_hi) of the large-x fit; the default as above.

    Returns
    -------
    dict
        The keys of ``predicted_exponents``, measured, and large_x_window, the (x_lo, x_hi)
        used.

    Examples
    --------
    A ``WeightFunction`` takes seconds to build, after the solve (which compiles the kernel on
    its first call), so not run as a doctest; at r = 1/2 the small-x slope carries the log
    correction (predicted 0):

    >>> from bouncing_ball.distribution import measured_exponents
    >>> from bouncing_ball.distribution import interpolated_weight_function
    >>> from bouncing_ball.distribution import outgoing_speed_solution
    >>> weight = interpolated_weight_function(outgoing_speed_solution("1/2"))  # doctest: +SKIP
    >>> measured = measured_exponents(weight)  # doctest: +SKIP
    >>> del measured["large_x_window"]  # doctest: +SKIP
    >>> print({key: round(value, 3) for key, value in measured.items()})  # doctest: +SKIP
    {'small_x_power': -0.06, 'small_x_power_at_zero_speed': -0.337, 'large_x_rate': 0.816,
    'large_x_power': -0.25}
    """
    beta = weight.small_speed_exponent
    x_small = np.geomspace(1e-8, 1e-6, 9)
    p_small = position_density(x_small, weight)
    if beta < 1.0:
        p_small = position_density(np.array([0.0]), weight)[0] - p_small
    at_zero_speed = np.array(
        [distribution_by_force_integral(x, 0.0, weight)[0] for x in np.geomspace(1e-7, 1e-5, 5)]
    )
    total = _total_decay(weight)
    if large_window is None:
        smallest = getattr(weight, "smallest_force", total / 150.0)
        # up to where the exponent 2 ((S + 1/12) x)^(1/2) reaches 150 (P still a normal double)
        # (at r = 0.9 the two bounds cross: the window is then the x between them)
        large_window = tuple(
            sorted((64.0 / total, min(total / (2.0 * smallest) ** 2, 75.0**2 / total)))
        )
    x_large = np.geomspace(large_window[0], large_window[1], 40)
    p_large = position_density(x_large, weight)
    design = np.column_stack(
        [np.ones_like(x_large), -np.sqrt(x_large), np.log(x_large), 1.0 / np.sqrt(x_large)]
    )
    (_, rate, power, _), *_ = np.linalg.lstsq(design, np.log(p_large), rcond=None)
    return {
        "small_x_power": _local_slope(x_small, p_small),
        "small_x_power_at_zero_speed": _local_slope(np.geomspace(1e-7, 1e-5, 5), at_zero_speed),
        "large_x_rate": float(rate),
        "large_x_power": float(power),
        "large_x_window": tuple(float(x) for x in large_window),
    }


def exponents_table(weights) -> pd.DataFrame:
    """Measured and predicted exponents of P(x) for each weight function: one row per r.

    Parameters
    ----------
    weights : iterable of WeightFunction
        Interpolated w(F) of eq. (weightfunc), one per r.

    Returns
    -------
    pandas.DataFrame
        Columns r, <key>_measured and <key>_predicted for each key of ``predicted_exponents``
        (``measured_exponents``), and large_x_window_lo, large_x_window_hi.

    Examples
    --------
    Not run as a doctest (as ``measured_exponents``):

    >>> from bouncing_ball.distribution import exponents_table
    >>> from bouncing_ball.distribution import interpolated_weight_function
    >>> from bouncing_ball.distribution import outgoing_speed_solution
    >>> weight = interpolated_weight_function(outgoing_speed_solution("1/2"))  # doctest: +SKIP
    >>> table = exponents_table([weight])  # doctest: +SKIP
    >>> columns = ["r", "large_x_rate_measured", "large_x_rate_predicted"]
    >>> print(table[columns].round(4))  # doctest: +SKIP
         r  large_x_rate_measured  large_x_rate_predicted
    0  0.5                 0.8165                  0.8165
    """
    rows = []
    for weight in weights:
        measured = measured_exponents(weight)
        predicted = predicted_exponents(weight.restitution)
        row = {"r": weight.restitution}
        for key, value in predicted.items():
            row[f"{key}_measured"] = measured[key]
            row[f"{key}_predicted"] = value
        row["large_x_window_lo"], row["large_x_window_hi"] = measured["large_x_window"]
        rows.append(row)
    return pd.DataFrame(rows)
