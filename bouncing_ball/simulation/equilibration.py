"""Equilibration: how long a shard discards, and a coarse check of the early part of each
shard's recording against the rest.

Every shard starts at rest one unit above the floor and discards ``equilibration_time``
before it records.  Where the process relaxes more slowly than that (near r -> 1 the ball
loses a fraction 1 - r^2 of its energy per bounce, and the collisions grow rare), every
shard records part of the same transient: <x>, Delta x and I are biased alike in every
shard, and the errors from their scatter (``estimators.jackknife``) do not see it.  Comparing
the shards with each other, or batches of shards with the jackknife, cannot catch it either,
since the shards are independent and share the bias.  What can see it is time within each
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

The check is weak, and a pass is no proof of equilibrium (``early_check_power``,
docs/validation.md, "What the equilibration check can see").  The early part holds f = 1/8
of the recording, so the mean difference has a standard error 1 / sqrt(f (1 - f)) = 3.02
times that of the full run's estimate.  At 64 shards a transient over within the early
part is caught half the time only once it biases the final estimate by 1.3 of its standard
errors (warn) or 2.0 (refuse).  One that decays as e^(-t/tau) over a good part of the
recording T shifts both parts and must be larger: 2.2 standard errors at tau = T/8, 4.1 at
T/4 (warn); one as slow as the recording (18.7 at tau = T: the difference falls as
T / (2 tau)) it hardly sees, and a bias constant in time (of the step rule, of the model)
not at all (``early_check_power_table``).  What keeps the transient out is the discarded
time, ``default_equilibration_time``; the check catches gross shortfalls of it, such as an
``equilibration_time`` set far below the relaxation time.

How long to discard, and how long a shard must be, follow from the relaxation time of the
process (``equilibration_relaxation_time``: ``Equilibrium(r).relaxation_time``, the slowest
decay time 1 / gamma of correlations in time, ``time_relaxation``, docs/methods.md):

* ``default_equilibration_time``: ``EQUILIBRATION_RELAXATION_TIMES`` relaxation times, never
  less than ``MIN_EQUILIBRATION_TIME``: what is left of the start, at most e^-20 = 2e-9 of it
  in the slowest mode, is far below any statistical error.
* ``SHARD_RELAXATION_TIMES``: the shortest shard whose errors are trusted, so that the early
  part of its recording (``EARLY_FRACTION``) spans at least one relaxation time: a transient
  shorter than the shard but longer than its early part would straddle the two and escape
  ``early_check``.
* ``equilibration_problems`` says what in a shard's settings falls short of these, naming r,
  the relaxation time and the setting; the workflow's config check refuses it before any job
  runs, ``simulate`` warns (``EquilibrationWarning``), and the merge records the settings in
  relaxation times beside its check (``relaxation_record``).
"""

import warnings

import numpy as np
import pandas as pd
from scipy import special  # not scipy.stats, the slowest of scipy to import, in every merge

from ..estimators import deviations_from_mean
from ..tallies import EARLY_FRACTION, ShardTallies

__all__ = [
    "early_check",
    "early_check_record",
    "early_check_message",
    "window_estimates",
    "WARN_P",
    "REFUSE_P",
    "QUANTITIES",
    "EQUILIBRATION_RELAXATION_TIMES",
    "MIN_EQUILIBRATION_TIME",
    "SHARD_RELAXATION_TIMES",
    "EquilibrationWarning",
    "equilibration_relaxation_time",
    "default_equilibration_time",
    "relaxation_time_bound",
    "equilibration_problems",
    "warn_equilibration_problems",
    "relaxation_record",
    "early_check_power",
    "early_check_power_table",
]

#: The p-value of ``early_check`` below which the merge warns.
WARN_P = 1.0e-3
#: The p-value of ``early_check`` below which the merge refuses.
REFUSE_P = 1.0e-6
#: The quantities compared: <x>, <x^2> and the collision rate I of eq. (collrate).
QUANTITIES = ("mean_x", "mean_x2", "collision_rate")
_SUMS = ("time", "collisions", "int_x", "int_x2")

#: The least ratio of ``relaxation_time_bound`` to the relaxation time over r_c < r < 1.
RELAXATION_BOUND_MARGIN = 1.05
#: The default ``equilibration_time`` in relaxation times (``default_equilibration_time``).
EQUILIBRATION_RELAXATION_TIMES = 20
#: The least default ``equilibration_time``, where the relaxation time is short or undefined.
MIN_EQUILIBRATION_TIME = 1.0e3
#: The shortest ``shard_time`` in relaxation times whose errors are trusted: the early part of
#: the recording (``EARLY_FRACTION`` of it) spans one relaxation time.
SHARD_RELAXATION_TIMES = round(1.0 / EARLY_FRACTION)


class EquilibrationWarning(RuntimeWarning):
    """A ``simulate`` run whose times fall short of the relaxation time at r.

    See ``equilibration_problems``: its estimates may carry the start's transient, or errors
    that cannot be trusted.
    """


def equilibration_relaxation_time(restitution) -> float | None:
    """The relaxation time that sets the equilibration of the simulation at r.

    ``Equilibrium(r).relaxation_time``, the slowest relaxation time of the process in time
    (1 / gamma, ``time_relaxation.time_relaxation``) where the solver answers it,
    r_c < r <= 0.9999; above 0.9999 its quasi-elastic form, (64/9) (1 - r)^-2 (1 - (1 - r))
    (``quasi_elastic.quasi_elastic_form("relaxation_time", r)``).  None at or below r_c
    (eq. (rc)), where the outgoing speeds collapse and there is no stationary state.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    float or None
        In the paper's time units.

    Examples
    --------
    >>> from bouncing_ball.simulation.equilibration import equilibration_relaxation_time
    >>> print(round(equilibration_relaxation_time("1/2"), 4))
    19.3446
    >>> print(equilibration_relaxation_time(0.1))
    None
    >>> print(f"{equilibration_relaxation_time(0.99999):.4g}")
    7.111e+10
    """
    from ..asymptotics import CRITICAL_RESTITUTION
    from ..restitution import SOLVER_RESTITUTION_RANGE, parse_restitution

    exact = parse_restitution(restitution, "r")
    if exact <= CRITICAL_RESTITUTION:
        return None
    if exact > SOLVER_RESTITUTION_RANGE[1]:
        from ..quasi_elastic import quasi_elastic_form

        return quasi_elastic_form("relaxation_time", exact)
    from ..equilibrium import Equilibrium

    return float(Equilibrium(exact).relaxation_time)


def relaxation_time_bound(restitution) -> float:
    """An upper bound of the relaxation time at r that needs no solve: 7.5 / (1 - r)^2.

    The relaxation time (``equilibration_relaxation_time``, 1 / gamma) stays finite at r_c
    (6.9 there) and grows as (64/9) (1 - r)^-2 (1 - (1 - r)) at r -> 1 (docs/quasi_elastic.md);
    (1 - r)^2 / gamma lies between 4.6 and 64/9 = 7.11 over r_c < r < 1, so the bound lies above
    it by a factor of at least ``RELAXATION_BOUND_MARGIN`` (``tests/numerical/test_whole_range.py``
    holds it against the solver on a grid from r_c + 1e-5 to 0.9999, and the quasi-elastic
    form beyond), and keeps 20 of it below 1e3 up to r = 0.6.  ``default_equilibration_time``
    and ``equilibration_problems`` solve eq. (inteq) only where the bound leaves the answer
    open.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, r_c < r < 1.

    Returns
    -------
    float
        In the paper's time units.

    Raises
    ------
    ValueError
        If r is not above r_c, where there is no relaxation time.

    Examples
    --------
    >>> from bouncing_ball.simulation.equilibration import relaxation_time_bound
    >>> print(round(relaxation_time_bound("1/2"), 3))
    30.0
    """
    from ..asymptotics import CRITICAL_RESTITUTION
    from ..restitution import parse_restitution

    r = float(parse_restitution(restitution, "r"))
    if not r > CRITICAL_RESTITUTION:
        raise ValueError(f"r = {restitution}: at or below r_c there is no relaxation time")
    return 7.5 / (1.0 - r) ** 2


def _above_critical(restitution) -> bool:
    from ..asymptotics import CRITICAL_RESTITUTION
    from ..restitution import parse_restitution

    return parse_restitution(restitution, "r") > CRITICAL_RESTITUTION


def default_equilibration_time(restitution) -> float:
    """The simulated time a shard discards before it records, unless told otherwise.

    ``EQUILIBRATION_RELAXATION_TIMES`` relaxation times (``equilibration_relaxation_time``)
    rounded up to two significant digits, and at least ``MIN_EQUILIBRATION_TIME``.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    float
        In the paper's time units.

    Examples
    --------
    >>> from bouncing_ball.simulation.equilibration import default_equilibration_time
    >>> default_equilibration_time("1/2"), default_equilibration_time(0.1)
    (1000.0, 1000.0)
    >>> default_equilibration_time(0.95), default_equilibration_time(0.99)
    (55000.0, 1500000.0)
    """
    if not _above_critical(restitution):
        return MIN_EQUILIBRATION_TIME
    if (
        EQUILIBRATION_RELAXATION_TIMES * relaxation_time_bound(restitution)
        <= MIN_EQUILIBRATION_TIME
    ):
        return MIN_EQUILIBRATION_TIME  # the same answer, without solving eq. (inteq)
    relaxation = equilibration_relaxation_time(restitution)
    return max(MIN_EQUILIBRATION_TIME, _two_digits_up(EQUILIBRATION_RELAXATION_TIMES * relaxation))


def _two_digits_up(time: float) -> float:
    """``time`` rounded up to two significant digits: a setting that does not move with the
    last bits of the eigenvalue it comes from (they differ between LAPACK builds)."""
    unit = 10.0 ** (int(np.floor(np.log10(time))) - 1)
    return float(np.ceil(time / unit * (1.0 - 1e-9)) * unit)


def equilibration_problems(
    restitution, shard_time: float, equilibration_time: float, where: str = "", units=None
) -> list[str]:
    """What in a shard's times falls short of the relaxation time at r, one sentence each.

    ``equilibration_time`` below ``default_equilibration_time`` (r above r_c, where it is
    ``EQUILIBRATION_RELAXATION_TIMES`` relaxation times and more than the least; a shorter
    time chosen below that is the user's), and ``shard_time`` below
    ``SHARD_RELAXATION_TIMES`` relaxation times.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.
    shard_time, equilibration_time : float
        The shard's settings, in the paper's time units.
    where : str, optional
        The prefix of the settings' names in the messages (e.g. ``"simulation."``).
    units : units.PhysicalUnits, optional
        The units the messages quote every time in (those the user gave ``simulate``); None:
        the paper's.

    Returns
    -------
    list of str
        Empty where both are long enough, and at or below r_c.

    Examples
    --------
    >>> from bouncing_ball.simulation.equilibration import equilibration_problems
    >>> equilibration_problems("1/2", 2e3, 1e3)
    []
    >>> for problem in equilibration_problems(0.95, 2e3, 50.0):
    ...     print(problem)  # doctest: +ELLIPSIS
    r = 0.95: equilibration_time = 50 is shorter than 20 relaxation times (2707.26 each): ...
    r = 0.95: shard_time = 2000 is shorter than 8 relaxation times (2707.26 each): ...

    The same in seconds, for a ball under g = 9.81 and a noise strength Lambda = 0.05, whose
    unit of time is Lambda / g^2 = 5.2e-4 s:

    >>> from bouncing_ball.units import PhysicalUnits
    >>> units = PhysicalUnits(gravity=9.81, noise=0.05)
    >>> print(equilibration_problems(0.95, 2e3, 50.0, units=units)[0])  # doctest: +ELLIPSIS
    r = 0.95: equilibration_time = 0.0259778 is shorter than 20 relaxation times (1.40657 each): ...
    """
    from ..restitution import parse_restitution, restitution_label

    if not _above_critical(restitution):
        return []
    bound = relaxation_time_bound(restitution)
    needed_bound = EQUILIBRATION_RELAXATION_TIMES * bound
    equilibrated = equilibration_time >= needed_bound or needed_bound <= MIN_EQUILIBRATION_TIME
    if equilibrated and shard_time >= SHARD_RELAXATION_TIMES * bound:
        return []  # the same answer, without solving eq. (inteq)
    relaxation = equilibration_relaxation_time(restitution)
    label = restitution_label(parse_restitution(restitution, "r"))

    def shown(time):  # a time of the paper's units in those of the messages
        return time if units is None else float(units.to_physical(time, "time"))

    problems = []
    needed = EQUILIBRATION_RELAXATION_TIMES * relaxation
    if equilibration_time < needed and needed > MIN_EQUILIBRATION_TIME:
        problems.append(
            f"r = {label}: {where}equilibration_time = {shown(equilibration_time):g} is "
            f"shorter than {EQUILIBRATION_RELAXATION_TIMES} relaxation times "
            f"({shown(relaxation):.6g} each): the shards may record the start's transient; use "
            f"the default (the workflow's equilibration_time: auto), {shown(needed):.3g}"
        )
    shortest = SHARD_RELAXATION_TIMES * relaxation
    if shard_time < shortest:
        problems.append(
            f"r = {label}: {where}shard_time = {shown(shard_time):g} is shorter than "
            f"{SHARD_RELAXATION_TIMES} relaxation times ({shown(relaxation):.6g} each): the "
            "early part of a recording, which the equilibration check compares with the rest, "
            "spans less than one, and the errors cannot be trusted; use at least "
            f"{shown(shortest):.3g}"
        )
    return problems


def warn_equilibration_problems(restitution, shard_time, equilibration_time, units=None) -> None:
    """Warn of each of ``equilibration_problems`` (``simulate``).

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.
    shard_time, equilibration_time : float
        The shard's settings, in the paper's time units.
    units : units.PhysicalUnits, optional
        The units the warnings quote every time in (None: the paper's).

    Returns
    -------
    None
        Each problem is an ``EquilibrationWarning``, attributed to the caller's caller.
    """
    for problem in equilibration_problems(restitution, shard_time, equilibration_time, units=units):
        warnings.warn(problem, EquilibrationWarning, stacklevel=3)


def relaxation_record(restitution, shard_time: float, equilibration_time: float) -> dict:
    """The shards' times in relaxation times, as a JSON-ready record for a merge's provenance.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.
    shard_time, equilibration_time : float
        The shards' settings.

    Returns
    -------
    dict
        ``relaxation_time`` (None at or below r_c), ``equilibration_relaxation_times`` and
        ``shard_relaxation_times`` (the settings divided by it; None likewise), and
        ``problems`` (``equilibration_problems``).

    Examples
    --------
    >>> from bouncing_ball.simulation.equilibration import relaxation_record
    >>> record = relaxation_record("1/2", 2e3, 1e3)
    >>> round(record["shard_relaxation_times"], 1), record["problems"]
    (103.4, [])
    """
    relaxation = equilibration_relaxation_time(restitution)
    ratio = (lambda time: None) if relaxation is None else (lambda time: time / relaxation)
    return {
        "relaxation_time": relaxation,
        "equilibration_relaxation_times": ratio(equilibration_time),
        "shard_relaxation_times": ratio(shard_time),
        "problems": equilibration_problems(restitution, shard_time, equilibration_time),
    }


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
    >>> from bouncing_ball.simulation.equilibration import window_estimates
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
    >>> from bouncing_ball.simulation.equilibration import early_check
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


def _transient_contrast(decay: float) -> float:
    """(early part's shift - rest's shift) / the whole recording's shift of a transient
    a e^(-t / tau) from the start of the recording, tau = ``decay`` x the recording time
    (0: a transient over before the early part ends, whatever its shape)."""
    f = EARLY_FRACTION
    if decay == 0.0:
        return 1.0 / f
    # in units of a tau / T: the early part's shift (1 - e^(-f/s)) / f, the rest's
    # (e^(-f/s) - e^(-1/s)) / (1 - f), the whole recording's 1 - e^(-1/s)
    early = -np.expm1(-f / decay) / f
    rest = np.exp(-f / decay) * -np.expm1(-(1.0 - f) / decay) / (1.0 - f)
    return float((early - rest) / -np.expm1(-1.0 / decay))


def _noncentral_t_two_sided_tail(dof: float, noncentrality: float, critical: float) -> float:
    """P(|t| > critical) of a noncentral Student's t, t = (Z + lambda) / (V / dof)^(1/2)
    with Z standard normal and V chi^2 with ``dof`` degrees of freedom: the normal tails
    given V averaged over V's density by quadrature in ln V (``scipy.special.nctdtr``
    gives NaN in parts of the lower tail)."""
    from scipy import integrate

    half = 0.5 * dof

    def integrand(log_v):
        v = np.exp(log_v)
        scale = critical * np.sqrt(v / dof)
        # V's density times v (d ln V), from its logarithm
        weight = np.exp(half * log_v - 0.5 * v - half * np.log(2.0) - special.gammaln(half))
        return weight * (special.ndtr(noncentrality - scale) + special.ndtr(-noncentrality - scale))

    # ln V from -80 (below, V's mass is under e^(-40)) to 20 standard deviations and 60 above
    # its mean; breaks at the peak and where the tails given V turn over
    lower, upper = -80.0, np.log(dof + 20.0 * np.sqrt(2.0 * dof) + 60.0)
    breaks = {np.log(dof)}
    if noncentrality > 0.0:
        breaks.add(np.log(dof) + 2.0 * np.log(noncentrality / critical))
    edges = [lower, *sorted(b for b in breaks if lower < b < upper), upper]
    return float(
        sum(
            integrate.quad(integrand, a, b, epsabs=1e-14, epsrel=1e-11, limit=200)[0]
            for a, b in zip(edges[:-1], edges[1:])
        )
    )


def early_check_power(
    shards: int = 64, detection: float = 0.5, p: float = WARN_P, decay: float = 0.0
) -> dict:
    """The smallest transient ``early_check`` catches with probability ``detection``.

    The model: each of n independent shards records time T; the estimate of a quantity over a
    window of length w scatters normally with variance sigma^2 T / w about its expectation
    (windows much longer than the correlation time, so the early part, ``EARLY_FRACTION``
    f of T, and the rest are independent), and a transient a e^(-t / tau) from the start
    of the recording shifts each window's expectation by its average there.  The full
    run's mean over n shards has the standard error SE = sigma / sqrt(n); the mean
    difference early - rest has SE / sqrt(f (1 - f)), 3.02 SE at f = 1/8.  The check's
    statistic is then a noncentral Student's t with n - 1 degrees of freedom, and the transient is caught (p below ``p``) with
    probability ``detection`` at one noncentrality, solved for (``scipy.optimize.brentq``).

    Parameters
    ----------
    shards : int, optional
        n, at least 2.
    detection : float, optional
        The probability of catching the transient, strictly between ``p`` (the false-alarm
        rate, what the check gives without a transient) and 1.
    p : float, optional
        The check's threshold: ``WARN_P`` (warn) or ``REFUSE_P`` (refuse); 0 < p < 1.
    decay : float, optional
        tau / T, at least 0 and finite: 0 for a transient over within the early part,
        whatever its shape (only its integral counts); a slower one straddles both parts.

    Returns
    -------
    dict
        ``difference_error``: the mean difference's standard error in units of SE,
        1 / sqrt(f (1 - f)); ``noncentrality``: the t statistic's, at the probability asked;
        ``early_shift``: the early part's shift minus the rest's (the early part's alone
        where ``decay`` is 0), and ``bias``: the shift the transient leaves in the estimate
        from the whole recording, both in units of SE.

    Examples
    --------
    At 64 shards the check warns half the time of a transient within the early part once
    it shifts that part by 10.4 standard errors, which biases the final estimate by 1.3,
    and refuses at 2.04:

    >>> from bouncing_ball.simulation.equilibration import REFUSE_P, early_check_power
    >>> warn, refuse = early_check_power(64), early_check_power(64, p=REFUSE_P)
    >>> print(round(warn["difference_error"], 3), round(warn["early_shift"], 1))
    3.024 10.4
    >>> print(round(warn["bias"], 2), round(refuse["bias"], 2))
    1.3 2.04
    """
    from scipy import optimize

    if isinstance(shards, bool) or not isinstance(shards, (int, np.integer)) or shards < 2:
        raise ValueError(f"shards = {shards!r}: a whole number of at least 2")
    if not 0.0 < p < 1.0:
        raise ValueError(f"p = {p!r}: must lie strictly between 0 and 1")
    if not p < detection < 1.0:
        raise ValueError(
            f"detection = {detection!r}: must lie strictly between p = {p:g} (the false-alarm "
            "rate) and 1"
        )
    if not (np.isfinite(decay) and decay >= 0.0):
        raise ValueError(f"decay = {decay!r}: tau / T must be at least 0 and finite")
    dof = float(shards - 1)
    critical = float(special.stdtrit(dof, 1.0 - p / 2.0))  # two-sided: |t| > critical

    def caught(noncentrality):
        return _noncentral_t_two_sided_tail(dof, noncentrality, critical)

    # caught(0) = p < detection; caught grows to 1 with lambda: double until past detection
    upper = critical + 10.0
    while caught(upper) <= detection:
        upper *= 2.0
    noncentrality = optimize.brentq(
        lambda lam: caught(lam) - detection, 0.0, upper, xtol=1e-10 * upper
    )
    difference_error = 1.0 / np.sqrt(EARLY_FRACTION * (1.0 - EARLY_FRACTION))
    early_shift = noncentrality * difference_error
    return {
        "difference_error": float(difference_error),
        "noncentrality": float(noncentrality),
        "early_shift": float(early_shift),
        "bias": float(early_shift / _transient_contrast(float(decay))),
    }


def early_check_power_table(
    shards: int = 64, detection: float = 0.5, decays=(0.0, 1 / 64, 1 / 16, 1 / 8, 1 / 4, 1.0)
) -> pd.DataFrame:
    """``early_check_power`` at ``WARN_P`` and ``REFUSE_P`` for each tau / T of ``decays``.

    Parameters
    ----------
    shards : int, optional
        n, at least 2.
    detection : float, optional
        The probability of catching the transient, strictly between ``WARN_P`` and 1.
    decays : sequence of float, optional
        tau / T of the transients (``early_check_power``'s ``decay``).

    Returns
    -------
    pandas.DataFrame
        One row per decay: ``decay`` (tau / T), ``warn_bias`` and ``refuse_bias``: the bias
        of the final estimate, in its standard errors, of the transient the check warns of,
        or refuses, with probability ``detection``.

    Examples
    --------
    >>> from bouncing_ball.simulation.equilibration import early_check_power_table
    >>> print(early_check_power_table(decays=(0.0, 1.0)).round(2).to_string(index=False))
     decay  warn_bias  refuse_bias
       0.0       1.30         2.04
       1.0      18.67        29.32
    """
    rows = []
    for decay in decays:
        warn = early_check_power(shards, detection, WARN_P, decay)
        refuse = early_check_power(shards, detection, REFUSE_P, decay)
        rows.append(
            {"decay": float(decay), "warn_bias": warn["bias"], "refuse_bias": refuse["bias"]}
        )
    return pd.DataFrame(rows)
