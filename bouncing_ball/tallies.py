"""What one simulation shard records, and merging shards (a sum).

A shard is stored as one long table, a row per tally entry::

    tally                   lo     hi     lo2    hi2    value
    outgoing_speed          v_lo   v_hi   NaN    NaN    collisions with v_out in [v_lo, v_hi)
    outgoing_speed_fine     v_lo   v_hi   NaN    NaN    the same on the fine bins (settings.return_law_speed_bins)
    position_time           x_lo   x_hi   NaN    NaN    time spent with x in [x_lo, x_hi)
    position_v2_time        x_lo   x_hi   NaN    NaN    int v^2 dt over that time
    flight_time             t_lo   t_hi   NaN    NaN    flights with duration in [t_lo, t_hi)
    position_velocity_time  x_lo   x_hi   v_lo   v_hi   time spent in that cell of (x, v)
    return_speed            u_lo   u_hi   v_lo   v_hi   flights leaving the floor at speed u
                                                        and returning at speed v in the cell
    lag_pairs, ...          k      k + 1  NaN    NaN    the bounce-chain sums at lag k
      (BOUNCE_LAG_SUMS)                                 (k = 0 .. BOUNCE_LAGS)
    time, collisions, steps, int_x, int_x2, budget_exhausted,
    flights, flight_time_sum, flight_time_squared_sum,
    noise_sum, noise_v_sum, noise_scaled_sum, normal_sum,
    early_time, early_collisions, early_int_x, early_int_x2,
    noise_x_sum, ..., position_noise_x_sum (MOMENT_CONTROL_SUMS)
                            NaN    NaN    NaN    NaN    the scalar

A 2-D tally's rows run over its second variable fastest (row-major, the first
variable's bins on the outer loop), each variable with its under- and
overflow bins.  Every entry is additive over shards, so merging is a sum.

``SCALARS`` is the one definition of the scalars' layout: their order in the table, in
the array a compiled shard loop fills (``SCALAR_INDEX``: the numba loop's indices, and
the C reference's, which ``benchmarks/reference_loop.py`` passes to the compiler, with
``EARLY_FRACTION``).  ``HISTOGRAMS`` and ``HISTOGRAMS_2D`` name the histograms and their
bins, ``BINS`` the four bins a shard is recorded on, ``CONTROL_VARIATE_SUMS`` the martingale
sums of mean 0 that correct the collision rate I, and ``EARLY_SUMS`` the sums over the first
``EARLY_FRACTION`` of the recording (the shard's own evidence of equilibration).

Examples
--------
A shard's tallies round-trip through its table; two shards merge to their sum:

>>> from bouncing_ball.bins import LinearBins, LogBins
>>> from bouncing_ball.settings import ShardSettings
>>> from bouncing_ball.tallies import ShardTallies, merge_shards, SCALAR_INDEX
>>> from bouncing_ball.tallies import tallies_from_frame, tallies_to_frame
>>> settings = ShardSettings(
...     shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
...     max_steps=100, speed_bins=LogBins(0.1, 10.0, 1), position_bins=LogBins(0.1, 10.0, 1),
...     velocity_bins=LinearBins(-1.0, 1.0, 1.0), flight_time_bins=LogBins(0.1, 10.0, 1),
... )
>>> arrays = ShardTallies.loop_arrays(settings)
>>> arrays["speed_counts"][1] = 3
>>> arrays["scalars"][SCALAR_INDEX["collisions"]] = 3
>>> shard = ShardTallies.from_loop(settings, arrays)
>>> total = merge_shards([shard, shard])
>>> print(total.collisions, total.speed_counts)
6 [0 6 0 0]
>>> back = tallies_from_frame(tallies_to_frame(total), settings)
>>> print(back.collisions, back.speed_counts)
6 [0 6 0 0]
"""

from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING

import numpy as np

from .bins import LinearBins, LogBins
from .settings import return_law_speed_bins

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "HISTOGRAMS",
    "HISTOGRAMS_2D",
    "CONTROL_VARIATE_SUMS",
    "MOMENT_CONTROL_SUMS",
    "MOMENT_CONTROLS",
    "RATE_CONTROLS",
    "SHARDS_PER_CONTROL",
    "EARLY_FRACTION",
    "EARLY_SUMS",
    "SCALARS",
    "SCALAR_INDEX",
    "BINS",
    "BOUNCE_LAGS",
    "BOUNCE_LAG_SUMS",
    "bounce_lag_pair_sums",
    "tally_seed_sequence",
    "ShardTallies",
    "merge_shards",
    "COLUMNS",
    "tallies_to_columns",
    "tallies_from_columns",
    "tallies_to_frame",
    "tallies_from_frame",
    "batch_schema",
    "batch_to_table",
    "batch_from_table",
    "batch_to_frame",
    "batch_from_frame",
]

#: The 1-D histograms, name in the table: (the bins' attribute, the values' attribute,
#: integer counts?).  ``return_law_speed_bins`` is ``settings.return_law_speed_bins`` of the speed bins, the same
#: for every shard.
HISTOGRAMS = {
    "outgoing_speed": ("speed_bins", "speed_counts", True),
    "outgoing_speed_fine": ("return_law_speed_bins", "return_law_speed_counts", True),
    "position_time": ("position_bins", "position_time", False),
    "position_v2_time": ("position_bins", "position_v2_time", False),
    "flight_time": ("flight_time_bins", "flight_time_counts", True),
}
#: The 2-D histograms, name in the table: ((the bins of the first and of the second variable),
#: values, integer?).
HISTOGRAMS_2D = {
    "position_velocity_time": (("position_bins", "velocity_bins"), "position_velocity_time", False),
    "return_speed": (("speed_bins", "speed_bins"), "return_speed_counts", True),
}
#: The martingale sums of mean 0 in the velocity noise xi_n = sqrt(2 dt_n) normal_r of
#: eq. (vstep): of xi_n, v_n xi_n, v_n xi_n / (x_n + v_n^2 / 2 + 4 dt_n) and normal_r, at the
#: step's start state; in every set of control variates (``RATE_CONTROLS``, ``MOMENT_CONTROLS``).
CONTROL_VARIATE_SUMS = ("noise_sum", "noise_v_sum", "noise_scaled_sum", "normal_sum")
#: More such sums, with weights polynomial in the step's start state, that correct the moments
#: of x and the flights (``estimators.position_moments_summary``); xi_n = sqrt(2 dt_n) normal_r,
#: q_n = xi_n^2 - 2 dt_n and eta_n = dt_n^(3/2) normal_s, the noises of eqs. (xstep), (vstep).
MOMENT_CONTROL_SUMS = (
    "noise_x_sum",
    "noise_xv_sum",
    "noise_x2_sum",
    "noise_v2_sum",
    "noise_v3_sum",
    "noise_v4_sum",
    "noise_xv2_sum",
    "noise_squared_sum",
    "noise_squared_v_sum",
    "noise_squared_x_sum",
    "noise_squared_v2_sum",
    "position_noise_sum",
    "position_noise_v_sum",
    "position_noise_x_sum",
)
#: The control variates of the summary's moments (I, <x>, Delta x, the flights' moments):
#: all the sums of mean 0 (``estimators.moment_controls``).
MOMENT_CONTROLS = (*CONTROL_VARIATE_SUMS, *MOMENT_CONTROL_SUMS)
#: The fewer control variates of the summary's moments with few shards, and those of the bins
#: of P(0, v), P(x) and <v^2>_x.
RATE_CONTROLS = (*CONTROL_VARIATE_SUMS, "noise_squared_sum")
#: The shards per control variate that a correction needs: with fewer, the jackknife error
#: of the corrected estimate scatters so much that z has heavy tails (``estimators.shard_controls``).
SHARDS_PER_CONTROL = 3
#: The fraction of the recording whose steps ``EARLY_SUMS`` sum over: those that start before
#: ``EARLY_FRACTION`` x shard_time.
EARLY_FRACTION = 0.125
#: The time, collisions, int x dt and int x^2 dt over the early part of the recording
#: (``EARLY_FRACTION``): the shard's own evidence of equilibration (``simulation.equilibration``).
EARLY_SUMS = ("early_time", "early_collisions", "early_int_x", "early_int_x2")
#: The scalars of a shard, in their order in its table and in the array a compiled shard loop
#: fills: the totals, then ``CONTROL_VARIATE_SUMS``, ``EARLY_SUMS`` and ``MOMENT_CONTROL_SUMS``.
SCALARS = (
    "time",
    "collisions",
    "steps",
    "int_x",
    "int_x2",
    "budget_exhausted",
    "flights",
    "flight_time_sum",
    "flight_time_squared_sum",
    *CONTROL_VARIATE_SUMS,
    *EARLY_SUMS,
    *MOMENT_CONTROL_SUMS,
)
#: Where each scalar of ``SCALARS`` sits in the array a compiled shard loop fills.
SCALAR_INDEX = {name: index for index, name in enumerate(SCALARS)}
_INTEGER = ("collisions", "steps", "budget_exhausted", "flights", "early_collisions")
#: The four bins a shard is recorded on, fields of ``ShardTallies`` and of
#: ``settings.ShardSettings``.
BINS = ("speed_bins", "position_bins", "velocity_bins", "flight_time_bins")
#: The largest lag K, in bounces, of the bounce chain's sums (``BOUNCE_LAG_SUMS``).  At
#: r = 0.99 (n_c ~ 100 bounces) the correlation falls by 1 - lambda_2^16 ~ 15 % over the
#: lags, far above its statistical error, so the decay rate is resolved; at r <= 0.75
#: (n_c < 4) it falls below its error well before lag 16, so longer lags add noise only.
#: The cost is per collision (a few hundred flops), not per step.
BOUNCE_LAGS = 16
#: The sums over pairs of bounces (n - k, n), for each lag k = 0 .. BOUNCE_LAGS, of the
#: functions f = (ln u, u) of the outgoing speeds u_{n-k}, u_n: the pairs, the sums of
#: f(u_{n-k}) ("leading") and of f(u_n) ("trailing"), and of the products
#: f_a(u_{n-k}) f_b(u_n).  A pair is counted at its later bounce n, a recorded one; the
#: earlier may lie in the equilibration (as a flight is counted at the collision that ends it),
#: so in a stationary shard every sum has expectation (recorded collisions) x its
#: equilibrium average, with no edge effect.  Lag 0 holds the sums of f and of f_a f_b.
BOUNCE_LAG_SUMS = (
    "lag_pairs",
    "lag_log_speed_leading",
    "lag_speed_leading",
    "lag_log_speed_trailing",
    "lag_speed_trailing",
    "lag_log_log",
    "lag_log_speed",
    "lag_speed_log",
    "lag_speed_speed",
)


def bounce_lag_pair_sums(sums):
    """The bounce-lag sums of ``BOUNCE_LAG_SUMS`` by name: views of rows of ``sums``.

    Parameters
    ----------
    sums : numpy.ndarray
        A shard's ``bounce_lag_sums``, shape (..., len(BOUNCE_LAG_SUMS), lags), e.g.
        stacked over shards.

    Returns
    -------
    dict of str to numpy.ndarray
        Each name of ``BOUNCE_LAG_SUMS`` -> its row, shape (..., lags).
    """
    sums = np.asarray(sums)
    return {name: sums[..., row, :] for row, name in enumerate(BOUNCE_LAG_SUMS)}


def _bins(holder, attribute):
    """The bins ``attribute`` of a shard's settings or tallies (``HISTOGRAMS``)."""
    if attribute == "return_law_speed_bins":
        return return_law_speed_bins(holder.speed_bins)
    return getattr(holder, attribute)


def tally_seed_sequence(seed_sequence: np.random.SeedSequence) -> np.random.SeedSequence:
    """The stream of a shard's bridge points, the first child of the shard's stream.

    The bridge points (``simulation.simulate_shard``) sample P(x, v) and correct P(x) and
    <v^2>_x.  The child is made without ``spawn`` (which would change the parent's state).

    Parameters
    ----------
    seed_sequence : numpy.random.SeedSequence
        The shard's stream.

    Returns
    -------
    numpy.random.SeedSequence
        Its child with spawn key ``(*seed_sequence.spawn_key, 0)``, as ``spawn`` would make
        first.

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.tallies import tally_seed_sequence
    >>> shard = np.random.SeedSequence(12345, spawn_key=(7,))
    >>> child = tally_seed_sequence(shard)
    >>> child.spawn_key, child.entropy
    ((7, 0), 12345)
    >>> bool((child.generate_state(2) == shard.spawn(1)[0].generate_state(2)).all())
    True
    """
    return np.random.SeedSequence(
        entropy=seed_sequence.entropy,
        spawn_key=(*seed_sequence.spawn_key, 0),
        pool_size=seed_sequence.pool_size,
    )


@dataclass(frozen=True)
class ShardTallies:
    """The tallies of one shard, or of several merged (``+``, ``merge_shards``).

    Every field but the bins is additive over shards.

    Parameters
    ----------
    speed_bins, position_bins, flight_time_bins : LogBins
        The bins of outgoing speeds, heights and flight times (``BINS``).
    velocity_bins : LinearBins
        The velocity bins of P(x, v).
    speed_counts, flight_time_counts : numpy.ndarray of int64
        Collisions by outgoing speed (P(0, v)), flights by duration; each with its under- and
        overflow bins.
    return_law_speed_counts : numpy.ndarray of int64
        Collisions by outgoing speed on the fine ``settings.return_law_speed_bins``, for the
        return-law control of P(0, v) (``estimators.return_law_prediction``).
    bounce_lag_sums : numpy.ndarray
        Shape (len(BOUNCE_LAG_SUMS), BOUNCE_LAGS + 1): for each sum of ``BOUNCE_LAG_SUMS``
        (a row) and lag k = 0 .. BOUNCE_LAGS (a column), the sum over the pairs of bounces k
        apart; the autocorrelations of the bounce chain (``estimators.bounce_autocorrelation``).
    position_time, position_v2_time : numpy.ndarray
        Time spent in each height bin (P(x)) and int v^2 dt over it (<v^2>_x, eq. (moment2)).
    position_velocity_time : numpy.ndarray
        Time spent in each (x, v) cell, shape (x bins, v bins): P(x, v).
    return_speed_counts : numpy.ndarray of int64
        Flights by outgoing speed u and return speed v, shape (u bins, v bins).
    time, collisions, steps, int_x, int_x2 : float or int
        Scalars of ``SCALARS``: recorded time, collisions, steps, int x dt and int x^2 dt.
    budget_exhausted, flights, flight_time_sum, flight_time_squared_sum : int or float
        Scalars of ``SCALARS``: shards that ran out of their step budget, flights recorded (one
        per recorded collision with an earlier collision) and the sums of their T and T^2.
    **control_variates : float
        One field per name of ``CONTROL_VARIATE_SUMS`` (the velocity noise of eq. (vstep))
        and of ``MOMENT_CONTROL_SUMS`` (the noises of eqs. (xstep), (vstep) with weights
        polynomial in the step's start state): sums of mean 0 over the recorded steps, the
        martingale control variates, all of them ``MOMENT_CONTROLS``, the fewer
        ``RATE_CONTROLS``.
    early_time, early_collisions, early_int_x, early_int_x2 : float or int
        ``EARLY_SUMS``: time, collisions, int x dt and int x^2 dt over the first
        ``EARLY_FRACTION`` of the recording.

    Raises
    ------
    ValueError
        On ``+`` of shards recorded on different bins.

    Examples
    --------
    See the module's example.
    """

    speed_bins: LogBins
    position_bins: LogBins
    velocity_bins: LinearBins
    flight_time_bins: LogBins
    speed_counts: np.ndarray  # outgoing speeds of the recorded collisions
    position_time: np.ndarray  # time per x bin (the mean path, bridge-corrected)
    position_v2_time: np.ndarray  # int v^2 dt per x bin
    flight_time_counts: np.ndarray  # durations of the recorded flights
    position_velocity_time: np.ndarray  # (x bins, v bins): time per cell (sampled on the bridge)
    return_speed_counts: np.ndarray  # (u bins, v bins): outgoing speed u, return speed v
    return_law_speed_counts: np.ndarray  # outgoing speeds again, on the fine return_law_speed_bins
    bounce_lag_sums: np.ndarray  # (BOUNCE_LAG_SUMS, lags 0 .. BOUNCE_LAGS): bounce-chain sums
    time: float
    collisions: int
    steps: int
    int_x: float
    int_x2: float
    budget_exhausted: int  # number of shards that ran out of their step budget
    flights: int  # flights recorded: one per recorded collision with an earlier collision
    flight_time_sum: float  # sum of their durations T
    flight_time_squared_sum: float  # sum of T^2
    # control variates: sums over the recorded steps n (state x_n, v_n and step dt_n at the
    # step's start, velocity noise xi_n = sqrt(2 dt_n) normal_n of eq. (vstep)), each of mean 0
    noise_sum: float  # sum xi_n
    noise_v_sum: float  # sum v_n xi_n
    noise_scaled_sum: float  # sum v_n xi_n / (x_n + v_n^2 / 2 + 4 dt_n)
    normal_sum: float  # sum normal_n
    # the steps that start in the early part of the recording (t < EARLY_FRACTION shard_time):
    # their time, collisions, int x dt and int x^2 dt (all 0 if the shard stopped before)
    early_time: float
    early_collisions: int
    early_int_x: float
    early_int_x2: float
    # sums over the recorded steps of mean 0 (MOMENT_CONTROL_SUMS)
    noise_x_sum: float  # sum x xi
    noise_xv_sum: float  # sum x v xi
    noise_x2_sum: float  # sum x^2 xi
    noise_v2_sum: float  # sum v^2 xi
    noise_v3_sum: float  # sum v^3 xi
    noise_v4_sum: float  # sum v^4 xi
    noise_xv2_sum: float  # sum x v^2 xi
    noise_squared_sum: float  # sum q
    noise_squared_v_sum: float  # sum v q
    noise_squared_x_sum: float  # sum x q
    noise_squared_v2_sum: float  # sum v^2 q
    position_noise_sum: float  # sum eta
    position_noise_v_sum: float  # sum v eta
    position_noise_x_sum: float  # sum x eta

    @staticmethod
    def loop_arrays(settings) -> dict:
        """Zeroed arrays a compiled shard loop fills.

        Parameters
        ----------
        settings : settings.ShardSettings
            Anything with the four bins of ``BINS``.

        Returns
        -------
        dict of str to numpy.ndarray
            By field name, each histogram with under- and overflow bins, ``bounce_lag_sums``
            and ``scalars`` in the order of ``SCALARS``.
        """
        arrays = {}
        for bins_attr, values_attr, integer in HISTOGRAMS.values():
            arrays[values_attr] = np.zeros(
                _bins(settings, bins_attr).n + 2, dtype=np.int64 if integer else np.float64
            )
        for (first, second), values_attr, integer in HISTOGRAMS_2D.values():
            shape = (getattr(settings, first).n + 2, getattr(settings, second).n + 2)
            arrays[values_attr] = np.zeros(shape, dtype=np.int64 if integer else np.float64)
        arrays["bounce_lag_sums"] = np.zeros((len(BOUNCE_LAG_SUMS), BOUNCE_LAGS + 1))
        arrays["scalars"] = np.zeros(len(SCALARS))
        return arrays

    @classmethod
    def from_loop(cls, settings, arrays: dict) -> "ShardTallies":
        """The tallies of a compiled shard loop.

        Parameters
        ----------
        settings : settings.ShardSettings
            Anything with the four bins of ``BINS``: the bins the loop recorded on.
        arrays : dict of str to numpy.ndarray
            The arrays of ``loop_arrays`` after the loop (the numba loop and its C reference
            both fill them so).

        Returns
        -------
        ShardTallies
        """
        values = {
            name: int(value) if name in _INTEGER else float(value)
            for name, value in zip(SCALARS, arrays["scalars"])
        }
        histograms = {name: array for name, array in arrays.items() if name != "scalars"}
        return cls(
            **{name: getattr(settings, name) for name in BINS},
            **histograms,
            **values,
        )

    def __add__(self, other: "ShardTallies") -> "ShardTallies":
        if any(getattr(self, name) != getattr(other, name) for name in BINS):
            raise ValueError("cannot merge shards recorded on different bins")
        summed = {
            f.name: getattr(self, f.name) + getattr(other, f.name)
            for f in fields(self)
            if f.name not in BINS
        }
        return replace(self, **summed)


def merge_shards(shards) -> ShardTallies:
    """Sum the tallies of several shards (order does not matter).

    Parameters
    ----------
    shards : iterable of ShardTallies
        At least one, all recorded on the same bins.

    Returns
    -------
    ShardTallies
        Their sum.

    Raises
    ------
    ValueError
        If there are no shards, or their bins differ.

    Examples
    --------
    See the module's example.
    """
    shards = list(shards)
    if not shards:
        raise ValueError("no shards to merge")
    total = shards[0]
    for shard in shards[1:]:
        total = total + shard
    return total


#: The columns of a shard's long table, in order (the module's docstring).
COLUMNS = ("tally", "lo", "hi", "lo2", "hi2", "value")


def tallies_to_columns(tallies: ShardTallies) -> dict:
    """A shard's tallies as the columns of its long table, without pandas.

    The layout of the module's docstring; a simulation job writes the columns as they are.

    Parameters
    ----------
    tallies : ShardTallies

    Returns
    -------
    dict
        ``COLUMNS`` -> 1-d numpy.ndarray: ``tally`` the names (object), the rest float64; a
        row per bin of each histogram (a 2-D one's second variable fastest), a row per lag
        of each of ``BOUNCE_LAG_SUMS``, then a row per scalar of ``SCALARS``.
    """
    names, lo, hi, lo2, hi2, value = [], [], [], [], [], []
    for name, (bins_attr, values_attr, _) in HISTOGRAMS.items():
        bins = _bins(tallies, bins_attr)
        names.append(np.full(bins.n + 2, name, dtype=object))
        lo.append(bins.lower)
        hi.append(bins.upper)
        lo2.append(np.full(bins.n + 2, np.nan))
        hi2.append(np.full(bins.n + 2, np.nan))
        value.append(np.asarray(getattr(tallies, values_attr), dtype=float))
    for name, ((first, second), values_attr, _) in HISTOGRAMS_2D.items():
        outer, inner = getattr(tallies, first), getattr(tallies, second)
        n_inner = inner.n + 2
        names.append(np.full((outer.n + 2) * n_inner, name, dtype=object))
        lo.append(np.repeat(outer.lower, n_inner))
        hi.append(np.repeat(outer.upper, n_inner))
        lo2.append(np.tile(inner.lower, outer.n + 2))
        hi2.append(np.tile(inner.upper, outer.n + 2))
        value.append(np.asarray(getattr(tallies, values_attr), dtype=float).ravel())
    lags = np.arange(BOUNCE_LAGS + 1, dtype=float)
    for name, row in zip(BOUNCE_LAG_SUMS, tallies.bounce_lag_sums, strict=True):
        names.append(np.full(lags.size, name, dtype=object))
        lo.append(lags)
        hi.append(lags + 1.0)
        lo2.append(np.full(lags.size, np.nan))
        hi2.append(np.full(lags.size, np.nan))
        value.append(np.asarray(row, dtype=float))
    names.append(np.array(SCALARS, dtype=object))
    for column in (lo, hi, lo2, hi2):
        column.append(np.full(len(SCALARS), np.nan))
    value.append(np.array([float(getattr(tallies, s)) for s in SCALARS]))
    columns = (names, lo, hi, lo2, hi2, value)
    return {key: np.concatenate(parts) for key, parts in zip(COLUMNS, columns, strict=True)}


def tallies_to_frame(tallies: ShardTallies) -> "pd.DataFrame":
    """A shard's tallies as its long table, the layout of the module's docstring.

    Parameters
    ----------
    tallies : ShardTallies

    Returns
    -------
    pandas.DataFrame
        The columns of ``tallies_to_columns``.

    Examples
    --------
    See the module's example.
    """
    import pandas as pd  # here: a simulation job writes its tallies without pandas

    return pd.DataFrame(tallies_to_columns(tallies))


def _on_bins(values, expected):
    return len(values) == len(expected) and np.allclose(values, expected, equal_nan=True)


def tallies_from_columns(columns, settings, source: str = "shard") -> ShardTallies:
    """A shard's tallies from the columns of its table: the inverse of ``tallies_to_columns``.

    Parameters
    ----------
    columns : mapping
        ``COLUMNS`` -> 1-d arrays (a dict of arrays, a pandas.DataFrame), the table's rows in
        their order.
    settings : settings.ShardSettings
        Anything with the four bins of ``BINS``; the table's bins must be these.
    source : str, optional
        Where the table comes from (a file), named in errors.

    Returns
    -------
    ShardTallies

    Raises
    ------
    ValueError
        Naming ``source``, if a column is missing, a tally is not on the bins of ``settings``
        (or a bounce-lag sum not on the lags 0 .. ``BOUNCE_LAGS``: a table of a layout
        without them), or a scalar is missing or repeated.
    """
    missing = set(COLUMNS) - set(columns)
    if missing:
        raise ValueError(f"{source}: missing columns {sorted(missing)}")
    lo, lo2, value = (np.asarray(columns[key]) for key in ("lo", "lo2", "value"))
    # each row's tally as an index of the names: one pass over the strings, then integer masks
    names = [*HISTOGRAMS, *HISTOGRAMS_2D, *BOUNCE_LAG_SUMS, *SCALARS]
    index = {name: k for k, name in enumerate(names)}
    codes = np.fromiter(
        (index.get(name, -1) for name in np.asarray(columns["tally"], dtype=object)),
        dtype=np.int64,
        count=len(lo),
    )
    rows = {name: np.flatnonzero(codes == k) for k, name in enumerate(names)}
    values = {name: getattr(settings, name) for name in BINS}
    for name, (bins_attr, values_attr, integer) in HISTOGRAMS.items():
        selected = rows[name]
        bins = _bins(settings, bins_attr)
        if not _on_bins(lo[selected], bins.lower):
            raise ValueError(
                f"{source}: tally '{name}' is not on the configured bins "
                f"({len(selected)} rows, expected {bins.n + 2}); re-run the shard"
            )
        column = value[selected]
        values[values_attr] = column.astype(np.int64) if integer else column
    for name, ((first, second), values_attr, integer) in HISTOGRAMS_2D.items():
        selected = rows[name]
        outer, inner = getattr(settings, first), getattr(settings, second)
        shape = (outer.n + 2, inner.n + 2)
        if not (
            _on_bins(lo[selected], np.repeat(outer.lower, shape[1]))
            and _on_bins(lo2[selected], np.tile(inner.lower, shape[0]))
        ):
            raise ValueError(
                f"{source}: tally '{name}' is not on the configured bins "
                f"({len(selected)} rows, expected {shape[0] * shape[1]}); re-run the shard"
            )
        column = value[selected].reshape(shape)
        values[values_attr] = column.astype(np.int64) if integer else column
    lags = np.arange(BOUNCE_LAGS + 1, dtype=float)
    lag_sums = []
    for name in BOUNCE_LAG_SUMS:
        selected = rows[name]
        if not _on_bins(lo[selected], lags):
            raise ValueError(
                f"{source}: tally '{name}' is not on the lags 0 .. {BOUNCE_LAGS} "
                f"({len(selected)} rows, expected {lags.size}); re-run the shard"
            )
        lag_sums.append(value[selected])
    values["bounce_lag_sums"] = np.array(lag_sums)
    for name in SCALARS:
        selected = rows[name]
        if len(selected) != 1:
            raise ValueError(f"{source}: expected one '{name}' row, found {len(selected)}")
        scalar = float(value[selected[0]])
        values[name] = int(scalar) if name in _INTEGER else scalar
    return ShardTallies(**values)


def tallies_from_frame(frame: "pd.DataFrame", settings, source: str = "shard") -> ShardTallies:
    """A shard's tallies from its table: the inverse of ``tallies_to_frame``.

    ``tallies_from_columns`` of the frame's columns: the same checks and errors.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table of ``tallies_to_frame``.
    settings, source
        As for ``tallies_from_columns``.

    Returns
    -------
    ShardTallies

    Examples
    --------
    See the module's example.
    """
    return tallies_from_columns(frame, settings, source)


def _arrow_array(values: np.ndarray, kind):
    """``values`` as an Arrow array of ``kind`` (int64, float64 or large_string) made from its
    buffers: ``pyarrow.array`` would import pandas to look at its argument."""
    import pyarrow as pa

    if kind == pa.large_string():
        encoded = [str(value).encode() for value in values]
        offsets = np.zeros(len(encoded) + 1, dtype=np.int64)
        np.cumsum([len(value) for value in encoded], out=offsets[1:])
        buffers = [None, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))]
    else:
        buffers = [None, pa.py_buffer(np.ascontiguousarray(values, dtype=kind.to_pandas_dtype()))]
    return pa.Array.from_buffers(kind, len(values), buffers)


def batch_schema():
    """The Arrow schema of a batch's table.

    Returns
    -------
    pyarrow.Schema
        ``shard`` (int64), then ``COLUMNS`` (``tally`` a large_string, as pandas writes str
        columns, the rest float64).
    """
    import pyarrow as pa

    return pa.schema(
        [
            ("shard", pa.int64()),
            ("tally", pa.large_string()),
            *((column, pa.float64()) for column in COLUMNS[1:]),
        ]
    )


def batch_to_table(batch: dict[int, ShardTallies]):
    """The table of a batch of shards, made without pandas.

    Parameters
    ----------
    batch : dict
        ``{shard index: ShardTallies}``, at least one shard.

    Returns
    -------
    pyarrow.Table
        The shards' long tables (``tallies_to_columns``) one after the other, in the order
        of the shards, with a first column ``shard`` (``batch_schema``).

    Examples
    --------
    >>> from bouncing_ball.bins import LinearBins, LogBins
    >>> from bouncing_ball.settings import ShardSettings
    >>> from bouncing_ball.tallies import ShardTallies, batch_from_table, batch_to_table
    >>> settings = ShardSettings(
    ...     shard_time=1.0, equilibration_time=0.0, criterion_c=5, min_step_divisor=10,
    ...     max_steps=100, speed_bins=LogBins(0.1, 10.0, 1),
    ...     position_bins=LogBins(0.1, 10.0, 1), velocity_bins=LinearBins(-1.0, 1.0, 1.0),
    ...     flight_time_bins=LogBins(0.1, 10.0, 1),
    ... )
    >>> shard = ShardTallies.from_loop(settings, ShardTallies.loop_arrays(settings))
    >>> sorted(batch_from_table(batch_to_table({3: shard, 1: shard}), settings))
    [1, 3]
    """
    import pyarrow as pa

    if not batch:
        raise ValueError("a batch needs at least one shard")
    schema = batch_schema()
    parts = {shard: tallies_to_columns(batch[shard]) for shard in sorted(batch)}
    columns = {
        "shard": np.concatenate(
            [np.full(len(part["value"]), shard, dtype=np.int64) for shard, part in parts.items()]
        ),
        **{key: np.concatenate([part[key] for part in parts.values()]) for key in COLUMNS},
    }
    return pa.Table.from_arrays(
        [_arrow_array(columns[field.name], field.type) for field in schema],
        schema=schema,
    )


def batch_to_frame(batch: dict[int, ShardTallies]) -> "pd.DataFrame":
    """The table of a batch (``batch_to_table``) as a pandas frame.

    Parameters
    ----------
    batch : dict
        ``{shard index: ShardTallies}``.

    Returns
    -------
    pandas.DataFrame
    """
    return batch_to_table(batch).to_pandas()


def batch_from_table(table, settings, source: str = "batch") -> dict[int, ShardTallies]:
    """The shards of a batch's table: the inverse of ``batch_to_table``.

    Parameters
    ----------
    table : pyarrow.Table
        A table of ``batch_to_table``.
    settings : ShardSettings
        The settings whose bins every shard must be on.
    source : str, optional
        The table's name in errors.

    Returns
    -------
    dict
        ``{shard: tallies}``, each checked to be on the bins of ``settings``
        (``tallies_from_columns``): a ValueError naming ``source`` otherwise.

    Examples
    --------
    See ``batch_to_table``.
    """
    if "shard" not in table.column_names:
        raise ValueError(f"{source}: missing column 'shard'")
    missing = set(COLUMNS) - set(table.column_names)
    if missing:
        raise ValueError(f"{source}: missing columns {sorted(missing)}")
    if table.num_rows == 0:
        return {}
    shard = table.column("shard").to_numpy()
    columns = {key: table.column(key).to_numpy() for key in COLUMNS}
    # each shard's rows in their order (a stable sort: the table's order within a shard)
    order = np.argsort(shard, kind="stable")
    shards, starts = np.unique(shard[order], return_index=True)
    batch = {}
    for number, rows in zip(shards, np.split(order, starts[1:]), strict=True):
        batch[int(number)] = tallies_from_columns(
            {key: column[rows] for key, column in columns.items()},
            settings,
            source=f"{source}, shard {int(number)}",
        )
    return batch


def batch_from_frame(
    frame: "pd.DataFrame", settings, source: str = "batch"
) -> dict[int, ShardTallies]:
    """``batch_from_table`` of a pandas frame (``batch_to_frame``).

    Parameters
    ----------
    frame : pandas.DataFrame
    settings, source
        As for ``batch_from_table``.

    Returns
    -------
    dict
        ``{shard: tallies}``.
    """
    if "shard" not in frame.columns:
        raise ValueError(f"{source}: missing column 'shard'")
    import pyarrow as pa

    return batch_from_table(pa.Table.from_pandas(frame, preserve_index=False), settings, source)
