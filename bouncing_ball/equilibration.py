"""A run's own evidence of equilibrium: the early part of each shard against the rest.

Every shard starts at rest one unit above the floor and discards ``equilibration_time``
before it records.  Where the process relaxes more slowly than that (near r -> 1 the ball
loses a fraction 1 - r^2 of its energy per bounce, and the collisions grow rare), every
shard records part of the same transient: <x>, Delta x and I are biased alike in every
shard, and the errors from their scatter (``histograms.jackknife``) do not see it.  Comparing
the shards with each other, or batches of shards with the jackknife, cannot catch it either,
since the shards are independent and share the bias.  What does see it is time within each
shard: in equilibrium the early part of a recording (its first ``tallies.EARLY_FRACTION``,
``tallies.EARLY_SUMS``) has the expectation of the rest, while a transient sits in it.

``early_check`` compares <x>, <x^2> and I, whose estimates over a window (a time average,
collisions per time) have the equilibrium value as expectation whatever the window's
length.  (Not Delta x: over a window shorter than the correlation time its estimate is
biased low, so the early part's would differ from the rest's in equilibrium too.)  For each
quantity and each shard it takes the difference d_k of the early part's estimate and the
rest's, and Student's t-test of mean d = 0 over the independent shards.  Its p-value says
how likely a difference this large is in equilibrium: below ``WARN_P`` the merge warns,
below ``REFUSE_P`` it refuses, since the errors cannot be trusted.
"""

import numpy as np
import pandas as pd
from scipy import special  # not scipy.stats, the slowest of scipy to import, in every merge

from .histograms import deviations_from_mean
from .tallies import EARLY_FRACTION, ShardTallies

__all__ = [
    "early_check",
    "early_check_record",
    "early_check_message",
    "window_estimates",
    "WARN_P",
    "REFUSE_P",
    "QUANTITIES",
]

#: The p-value of ``early_check`` below which the merge warns.
WARN_P = 1.0e-3
#: The p-value of ``early_check`` below which the merge refuses.
REFUSE_P = 1.0e-6
#: The quantities compared: <x>, <x^2> and the collision rate I of eq. (collrate).
QUANTITIES = ("mean_x", "mean_x2", "collision_rate")
_SUMS = ("time", "collisions", "int_x", "int_x2")


def _estimates(time, collisions, int_x, int_x2) -> dict:
    return {"mean_x": int_x / time, "mean_x2": int_x2 / time, "collision_rate": collisions / time}


def window_estimates(shards: list[ShardTallies]) -> pd.DataFrame:
    """<x>, <x^2> and I of each shard over the early part of its recording and over the rest.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards (anything with the sums time, collisions, int_x, int_x2 and their
        ``early_`` parts).

    Returns
    -------
    pandas.DataFrame
        One row per shard, in the order given: columns ``early_<quantity>`` and
        ``rest_<quantity>`` for each of ``QUANTITIES``, and ``complete``: whether both parts
        recorded time (not so in a shard that stopped early).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from bouncing_ball.equilibration import window_estimates
    >>> shard = SimpleNamespace(
    ...     time=10.0, collisions=5, int_x=20.0, int_x2=80.0,
    ...     early_time=2.0, early_collisions=1, early_int_x=4.0, early_int_x2=16.0,
    ... )
    >>> row = window_estimates([shard]).iloc[0]
    >>> print(row.complete, row.early_mean_x, row.rest_mean_x, row.rest_collision_rate)
    True 2.0 2.0 0.5
    """
    total = {name: np.array([float(getattr(s, name)) for s in shards]) for name in _SUMS}
    early = {name: np.array([float(getattr(s, f"early_{name}")) for s in shards]) for name in _SUMS}
    rest = {name: total[name] - early[name] for name in _SUMS}
    frame = {"complete": (early["time"] > 0.0) & (rest["time"] > 0.0)}
    with np.errstate(divide="ignore", invalid="ignore"):
        early_estimates, rest_estimates = _estimates(**early), _estimates(**rest)
    for quantity in QUANTITIES:
        frame[f"early_{quantity}"] = early_estimates[quantity]
        frame[f"rest_{quantity}"] = rest_estimates[quantity]
    return pd.DataFrame(frame)


def early_check(
    shards: list[ShardTallies], warn_p: float = WARN_P, refuse_p: float = REFUSE_P
) -> pd.DataFrame:
    """Does the early part of the shards' recordings agree with the rest?

    One row per quantity of ``QUANTITIES``: the mean over the shards of (early - rest) and its
    standard error, their ratio ``z`` (Student's t with shards - 1 degrees of freedom), the
    two-sided ``p``, and the ``verdict``: "ok", "warn" (p < ``warn_p``) or "refuse"
    (p < ``refuse_p``); "not checked" with fewer than two shards whose two parts both
    recorded time.  See the module's account of why.

    Parameters
    ----------
    shards : list of ShardTallies
        The shards of one r.
    warn_p, refuse_p : float
        The p-values below which the disagreement is reported, and refused.

    Returns
    -------
    pandas.DataFrame
        Columns quantity, shards, early, rest (the means over the shards), difference,
        difference_err, z, p, verdict.

    Examples
    --------
    Three shards whose early parts agree with the rest within their scatter:

    >>> from types import SimpleNamespace
    >>> from bouncing_ball.equilibration import early_check
    >>> def shard(early_x, rest_x):
    ...     return SimpleNamespace(
    ...         time=10.0, collisions=5, int_x=2.0 * early_x + 8.0 * rest_x, int_x2=80.0,
    ...         early_time=2.0, early_collisions=1, early_int_x=2.0 * early_x,
    ...         early_int_x2=16.0,
    ...     )
    >>> check = early_check([shard(2.1, 2.0), shard(1.9, 2.0), shard(2.0, 2.1)])
    >>> print(check.quantity[0], check.shards[0], check.verdict[0])
    mean_x 3 ok
    >>> print(round(check.loc[0, "z"], 6), round(check.loc[0, "p"], 6))
    -0.5 0.666667
    """
    windows = window_estimates(shards)
    used = windows[windows["complete"]]
    n = len(used)
    rows = []
    for quantity in QUANTITIES:
        early = used[f"early_{quantity}"].to_numpy()
        rest = used[f"rest_{quantity}"].to_numpy()
        row = {
            "quantity": quantity,
            "shards": n,
            "early": float(early.mean()) if n else np.nan,
            "rest": float(rest.mean()) if n else np.nan,
            "difference": np.nan,
            "difference_err": np.nan,
            "z": np.nan,
            "p": np.nan,
            "verdict": "not checked",
        }
        if n >= 2:
            difference = early - rest
            # 0 exactly where every shard's difference is the same
            error = np.sqrt(np.sum(deviations_from_mean(difference) ** 2) / (n - 1) / n)
            z = difference.mean() / error if error > 0.0 else 0.0
            p = float(2.0 * special.stdtr(n - 1, -abs(z)))  # Student's t: 2 P(T > |z|)
            row.update(
                difference=float(difference.mean()),
                difference_err=float(error),
                z=float(z),
                p=p,
                verdict="refuse" if p < refuse_p else "warn" if p < warn_p else "ok",
            )
        rows.append(row)
    return pd.DataFrame(rows)


VERDICTS = ("not checked", "ok", "warn", "refuse")


def early_check_record(check: pd.DataFrame) -> dict:
    """The check as a JSON-ready record for a file's provenance.

    Parameters
    ----------
    check : pandas.DataFrame
        The table of ``early_check``.

    Returns
    -------
    dict
        ``verdict`` (the worst of the quantities'), ``early_fraction``, ``shards`` (those
        compared) and, per quantity, ``{"z": z, "p": p}`` (None where not finite).
    """
    return {
        "verdict": max(check["verdict"], key=VERDICTS.index),
        "early_fraction": EARLY_FRACTION,
        "shards": int(check["shards"].iloc[0]),
        **{row.quantity: {"z": _finite(row.z), "p": _finite(row.p)} for row in check.itertuples()},
    }


def _finite(value):
    return float(value) if np.isfinite(value) else None


SYMBOLS = {"mean_x": "<x>", "mean_x2": "<x^2>", "collision_rate": "I"}


def early_check_message(check: pd.DataFrame, label: str) -> str:
    """What a log says about the check of one r: each quantity's two parts, z and p.

    Parameters
    ----------
    check : pandas.DataFrame
        The table of ``early_check``.
    label : str
        The r label, as in the workflow's file names.

    Returns
    -------
    str
        One line.
    """
    parts = [
        f"{SYMBOLS[row.quantity]} {row.early:.5g} early vs {row.rest:.5g} later "
        f"(z = {row.z:+.1f}, p = {row.p:.1e})"
        for row in check.itertuples()
        if row.verdict != "not checked"
    ]
    if not parts:
        return f"r={label}: equilibration not checked (fewer than 2 shards recorded both parts)"
    return (
        f"r={label}: the first {EARLY_FRACTION:g} of each shard's recording against the rest: "
        + "; ".join(parts)
    )
