"""``SimulationResult``: a simulation's tables and scalars in the units it was run in, saved
to and loaded from a Parquet file (``load``)."""

from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property

import numpy as np

from ..restitution import parse_restitution, restitution_label
from ..settings import ShardSettings
from ..units import PhysicalUnits
from .seeds import _seed_from_record, _seed_record, _seed_text

__all__ = [
    "SimulationResult",
    "load",
    "SCALARS",
    "COLUMN_DIMENSIONS",
    "RESULT_KIND",
]

SCALARS = {
    "collision_rate": ("I", "collisions per unit time, eq. (collrate)"),
    "mean_x": ("<x>", "the mean height, eq. (xandDeltax)"),
    "delta_x": ("Delta x", "the height's standard deviation, eq. (xandDeltax)"),
    "mean_flight_time": ("<T>", "the mean time of flight between collisions"),
    "flight_time_second_moment": ("<T^2>", "the mean squared time of flight"),
}

#: The dimension (a key of ``units.DIMENSIONS``) of each column of the result's tables that has
#: one, by its name without ``_err``, ``_controlled``: the scalars of ``SCALARS``, the bins'
#: edges and centres, and the tables' values.  The other columns (counts, probabilities,
#: correlations, r) have none.
COLUMN_DIMENSIONS = {
    "collision_rate": "rate",
    "mean_x": "length",
    "delta_x": "length",
    "mean_flight_time": "time",
    "flight_time_second_moment": "time_squared",
    "total_time": "time",
    **dict.fromkeys(("x_lo", "x_hi", "x"), "length"),
    **dict.fromkeys(("v_lo", "v_hi", "v", "u_lo", "u_hi"), "speed"),
    **dict.fromkeys(("t_lo", "t_hi", "t"), "time"),
    "p0v": "phase_space_density",
    "pxv": "phase_space_density",
    "px": "per_length",
    "v2_given_x": "speed_squared",
    "density": "rate",  # rho(T) per flight
}


def _estimated_quantity(column: str) -> str:
    """The quantity a table's ``column`` estimates: the column without its estimator's suffix
    (``_martingale``, ``_controlled``) and its error's (``_err``)."""
    return column.removesuffix("_err").removesuffix("_controlled").removesuffix("_martingale")


def _column_dimension(column: str):
    """The dimension of a table's ``column`` (``COLUMN_DIMENSIONS``), None if it has none."""
    return COLUMN_DIMENSIONS.get(_estimated_quantity(column))


def _in_units(table, units):
    """A table of the paper's units in ``units``: each column with a dimension times its
    unit (``table`` itself in the paper's units)."""
    if units.is_paper:
        return table
    converted = table.copy()
    for column in converted.columns:
        dimension = _column_dimension(column)
        if dimension is not None:
            converted[column] = units.to_physical(converted[column].to_numpy(float), dimension)
    return converted


#: The names of the tables in other releases' spelling, and the table each is.
_TABLE_NAMES = {
    "p0v": "p0v_histogram",
    "px": "px_histogram",
    "v2_given_x": "v2_given_x_histogram",
    "pxv": "pxv_histogram",
    "position": "position_histogram",
    "flight_time_density": "flight_time_histogram",
    "return_speed": "return_speed_histogram",
    "summary": "summary_table",
}

#: What ``SimulationResult.save`` writes in its file's provenance under ``kind``.
RESULT_KIND = "SimulationResult"


def _summary_scalar(column):
    """A read-only attribute: ``column`` of ``summary_table``'s one row, as a float; its
    docstring says which scalar of ``SCALARS`` it is and which estimate."""
    name = _estimated_quantity(column)
    symbol, what = SCALARS[name]
    if column == name:
        doc = f"{symbol}, {what}: the shards' estimate."
    elif column == f"{name}_err":
        doc = f"The delete-one jackknife error of ``{name}`` over the shards."
    elif column == f"{name}_martingale":
        doc = (
            f"{symbol} corrected by the martingale (noise-sum) control variates: the same "
            "expectation for the simulated process, less variance, independent of the theory "
            "(the estimate that judges agreement); NaN with too few shards to fit them "
            "(``tallies.SHARDS_PER_CONTROL`` per control)."
        )
    elif column == f"{name}_controlled":
        doc = (
            f"{symbol} corrected by every control variate, the flight-law controls of "
            "eq. (kernel3) included where r is in the solver's range (the summary's "
            "``kernel3_controls``): built from the theory under test; NaN with too few shards."
        )
    else:
        doc = (
            f"The delete-one jackknife error of ``{column.removesuffix('_err')}``; NaN where it is."
        )

    def value(self) -> float:
        return float(self.summary_table[column].iloc[0])

    value.__doc__ = doc
    return property(value)


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """What ``simulate`` returns: the shards' tallies, their merged tables and the observables
    with their delete-one jackknife errors over the shards (``estimators``).

    The raw data are the shards' tallies with the settings, the seed and r: ``save`` writes
    them to a Parquet file and ``bouncing_ball.load`` reads them back to an equal result.
    Every table is a ``pandas.DataFrame`` over bins or lags, named ``*_histogram`` or
    ``*_table`` (``Equilibrium``'s ``p0v``, ``px``, ... are functions; these are the
    simulation's bin averages of them).

    Attributes
    ----------
    restitution : fractions.Fraction
        r exactly.
    r : float
        r as a float.
    label : str
        The workflow's label of r (``restitution.restitution_label``).
    seed : int or numpy.random.SeedSequence
        The root seed: pass it to ``simulate`` again, with the same r, shard_time and
        settings, for the same numbers.
    settings : settings.ShardSettings
        The shard settings of the run.
    tallies : tuple of tallies.ShardTallies
        Each shard's tallies, in the order of the shards (the raw data).
    shard_indices : tuple of int
        The index of each shard of ``tallies`` (its random stream); 0 .. shards - 1 unless
        the run was interrupted.
    requested_shards : int
        The shards asked for; ``partial`` (shown in the repr and the summary) when fewer
        finished: a run stopped by Ctrl-C (``SimulationInterrupted``).
    units : units.PhysicalUnits
        The gravity and noise of ``simulate`` (the paper's g = Lambda = 1 by default): the
        scalars, ``total_time``, ``observables()`` and every table are in these units, each
        column times its unit (``COLUMN_DIMENSIONS``).  ``settings`` and ``tallies`` are
        the shards' own, in the paper's units.
    shards : int
        The shards of ``tallies``.
    partial : bool
        True when fewer shards finished than were asked for.
    merged : tallies.ShardTallies
        The shards' tallies summed.
    total_time : float
        The simulated time recorded, summed over the shards.
    collision_rate, mean_x, delta_x, mean_flight_time, flight_time_second_moment : float
        I (eq. (collrate)), <x>, Delta x (eq. (xandDeltax)), and <T>, <T^2> per flight.
    collision_rate_err, mean_x_err, delta_x_err, mean_flight_time_err, flight_time_second_moment_err : float
        Their delete-one jackknife errors over the shards.
    collision_rate_martingale, mean_x_martingale, delta_x_martingale, mean_flight_time_martingale, flight_time_second_moment_martingale : float
        The same corrected by the martingale (noise-sum) control variates: the same
        expectation for the simulated process, less variance, independent of the theory (the
        estimates that judge agreement); NaN with too few shards to fit the controls
        (``tallies.SHARDS_PER_CONTROL`` per control); each with ``*_err``.
    collision_rate_controlled, mean_x_controlled, delta_x_controlled, mean_flight_time_controlled, flight_time_second_moment_controlled : float
        The same corrected by every control, the flight-law controls of eq. (kernel3)
        included where r is in the solver's range: built from the theory under test, shown
        beside the independent estimates, never instead of them.
    collision_rate_controlled_err, mean_x_controlled_err, delta_x_controlled_err, mean_flight_time_controlled_err, flight_time_second_moment_controlled_err : float
        Their jackknife errors; NaN as they are.
    relaxation_eigenvalue, relaxation_eigenvalue_err : float
        lambda of ``bounce_chain_decay`` and its jackknife error (NaN where fewer than 2
        lags are resolved); against ``Equilibrium.relaxation_eigenvalue``.
    p0v_histogram : pandas.DataFrame
        P(0, v) on the speed bins (v_lo, v_hi, v, p0v, p0v_err, count).
    px_histogram, v2_given_x_histogram : pandas.DataFrame
        P(x) and <v^2>_x (eq. (moment2)) on the position bins (x_lo, x_hi, x, and the value
        with its ``_err``); ``position_histogram`` has both.
    pxv_histogram : pandas.DataFrame
        P(x, v) cell averages (x_lo, x_hi, v_lo, v_hi, pxv, pxv_err).
    flight_time_histogram : pandas.DataFrame
        rho(T) per flight on the flight-time bins (t_lo, t_hi, t, density, density_err).
    return_speed_histogram : pandas.DataFrame
        The return speed's bin probabilities given the outgoing speed's bin.
    bounce_autocorrelation : pandas.DataFrame
        The bounce chain's autocorrelation over lags 1 .. ``tallies.BOUNCE_LAGS`` (lag,
        autocorrelation of ln u_n, principal_correlation of (ln u_n, u_n), each with its
        ``_err``; ``estimators.bounce_autocorrelation``).
    bounce_chain_decay : dict
        The fitted decay rate -ln lambda of the bounce chain's correlations, lambda
        (``relaxation_eigenvalue``), n_c = 1 / rate (``correlation_bounces``), each with its
        ``_err``, and the lags of the fit (``estimators.bounce_chain_decay``).
    outside_fractions : dict
        The fraction of each table's distribution outside its finite bins: {table: {below,
        above, outside, counts}} (``estimators.outside_fractions``).
    summary_table : pandas.DataFrame
        One row: the scalars, their errors, the counts (as the workflow's summary table);
        ``observables()`` is the same scalars as a tidy table.

    Examples
    --------
    >>> from bouncing_ball import simulate
    >>> result = simulate(0.6, shards=2, shard_time=200.0, seed=3, progress=False)
    >>> list(result.px_histogram.columns)
    ['x_lo', 'x_hi', 'x', 'px', 'px_err']
    """

    restitution: Fraction
    seed: object
    settings: object
    tallies: tuple = field(repr=False)
    shard_indices: tuple = field(default=None, repr=False)
    requested_shards: int = None
    units: PhysicalUnits = field(default_factory=PhysicalUnits)

    def __post_init__(self):
        if not isinstance(self.units, PhysicalUnits):
            raise TypeError(f"units must be a units.PhysicalUnits, got {self.units!r}")
        if self.shard_indices is None:
            object.__setattr__(self, "shard_indices", tuple(range(len(self.tallies))))
        if self.requested_shards is None:
            object.__setattr__(self, "requested_shards", len(self.tallies))
        if len(self.shard_indices) != len(self.tallies):
            raise ValueError(
                f"shard_indices: {len(self.shard_indices)} indices for {len(self.tallies)} shards"
            )

    def __getattr__(self, name):
        # only for names not found otherwise: a table under another spelling
        if name in _TABLE_NAMES:
            raise AttributeError(
                f"'SimulationResult' object has no attribute {name!r}: the table is "
                f"{_TABLE_NAMES[name]!r} (Equilibrium.{name} is the function)"
            )
        raise AttributeError(f"'SimulationResult' object has no attribute {name!r}")

    collision_rate = _summary_scalar("collision_rate")
    collision_rate_err = _summary_scalar("collision_rate_err")
    collision_rate_martingale = _summary_scalar("collision_rate_martingale")
    collision_rate_martingale_err = _summary_scalar("collision_rate_martingale_err")
    collision_rate_controlled = _summary_scalar("collision_rate_controlled")
    collision_rate_controlled_err = _summary_scalar("collision_rate_controlled_err")
    mean_x = _summary_scalar("mean_x")
    mean_x_err = _summary_scalar("mean_x_err")
    mean_x_martingale = _summary_scalar("mean_x_martingale")
    mean_x_martingale_err = _summary_scalar("mean_x_martingale_err")
    mean_x_controlled = _summary_scalar("mean_x_controlled")
    mean_x_controlled_err = _summary_scalar("mean_x_controlled_err")
    delta_x = _summary_scalar("delta_x")
    delta_x_err = _summary_scalar("delta_x_err")
    delta_x_martingale = _summary_scalar("delta_x_martingale")
    delta_x_martingale_err = _summary_scalar("delta_x_martingale_err")
    delta_x_controlled = _summary_scalar("delta_x_controlled")
    delta_x_controlled_err = _summary_scalar("delta_x_controlled_err")
    mean_flight_time = _summary_scalar("mean_flight_time")
    mean_flight_time_err = _summary_scalar("mean_flight_time_err")
    mean_flight_time_martingale = _summary_scalar("mean_flight_time_martingale")
    mean_flight_time_martingale_err = _summary_scalar("mean_flight_time_martingale_err")
    mean_flight_time_controlled = _summary_scalar("mean_flight_time_controlled")
    mean_flight_time_controlled_err = _summary_scalar("mean_flight_time_controlled_err")
    flight_time_second_moment = _summary_scalar("flight_time_second_moment")
    flight_time_second_moment_err = _summary_scalar("flight_time_second_moment_err")
    flight_time_second_moment_martingale = _summary_scalar("flight_time_second_moment_martingale")
    flight_time_second_moment_martingale_err = _summary_scalar(
        "flight_time_second_moment_martingale_err"
    )
    flight_time_second_moment_controlled = _summary_scalar("flight_time_second_moment_controlled")
    flight_time_second_moment_controlled_err = _summary_scalar(
        "flight_time_second_moment_controlled_err"
    )

    @property
    def partial(self) -> bool:
        """True when fewer shards finished than were asked for (an interrupted run)."""
        return self.shards < self.requested_shards

    @property
    def r(self) -> float:
        """r as a float."""
        return float(self.restitution)

    @property
    def label(self) -> str:
        """The workflow's label of r (``restitution.restitution_label``)."""
        return restitution_label(self.restitution)

    @property
    def shards(self) -> int:
        """The shards of ``tallies``."""
        return len(self.tallies)

    @cached_property
    def merged(self):
        """The shards' tallies summed (``tallies.merge_shards``)."""
        from ..tallies import merge_shards

        return merge_shards(self.tallies)

    @property
    def total_time(self) -> float:
        """The simulated time recorded, summed over the shards, in ``units``."""
        return float(self.units.to_physical(float(self.merged.time), "time"))

    @cached_property
    def _theory_outgoing_density(self):
        """The solver's P(0, u) at r, which the ``*_controlled`` estimates lean on (None outside
        the solver's range of r)."""
        from ..solver import solved_outgoing_density

        return solved_outgoing_density(self.restitution)

    @cached_property
    def _summary_paper(self):
        """``summary_table`` in the paper's units."""
        from ..estimators import position_moments_summary

        summary = position_moments_summary(
            list(self.tallies), self.restitution, self._theory_outgoing_density
        )
        return summary.assign(requested_shards=self.requested_shards, partial=self.partial)

    @cached_property
    def summary_table(self):
        """One row: the scalars, their errors and the counts
        (``estimators.position_moments_summary``), with ``requested_shards`` and
        ``partial``; in ``units``."""
        return _in_units(self._summary_paper, self.units)

    def observables(self):
        """Every scalar with its error, as a tidy table: a row per (observable, estimator).

        The plain estimates and their delete-one jackknife errors over the shards, with
        ``dof`` = shards - 1; the estimates corrected by the martingale (noise-sum) controls
        (``*_martingale``, independent of the theory: the ones that judge agreement,
        ``validation.independent_estimate``) and by every control, those of eq. (kernel3)
        included where r is in the solver's range (``*_controlled``), each with ``dof`` =
        shards - 1 - the controls fitted (``estimators.moment_controls``, at most); and the
        bounce chain's relaxation eigenvalue lambda (``bounce_chain_decay``), dof =
        shards - 1.  Only the estimates that exist are rows: a controlled one needs
        ``tallies.SHARDS_PER_CONTROL`` shards per control and a finite error, lambda two
        resolved lags.  A z-score against a prediction is (value - prediction) / error,
        Student-t with ``dof`` degrees of freedom.

        Returns
        -------
        pandas.DataFrame
            Columns ``observable`` (the attribute's name: ``collision_rate``, ``mean_x``,
            ``delta_x``, ``mean_flight_time``, ``flight_time_second_moment``,
            ``relaxation_eigenvalue``), ``symbol``, ``estimator`` (``"plain"``,
            ``"martingale"``, ``"controlled"``, or ``"bounce-chain fit"`` for lambda),
            ``value``, ``error``
            (finite and positive), ``shards`` and ``dof``.

        Examples
        --------
        >>> from bouncing_ball import simulate
        >>> result = simulate("1/2", shards=4, shard_time=200.0, seed=1, progress=False)
        >>> table = result.observables()
        >>> int(table.set_index(["observable", "estimator"]).loc["mean_x", "plain"].dof)
        3
        """
        import pandas as pd

        row = self.summary_table.iloc[0]
        shards = self.shards
        rows = []
        for name, (symbol, _) in SCALARS.items():
            rows.append((name, symbol, "plain", row[name], row[f"{name}_err"], shards - 1))
            for estimator in ("martingale", "controlled"):
                column = f"{name}_{estimator}"
                dof = shards - 1 - int(row["control_variates"])
                rows.append((name, symbol, estimator, row[column], row[f"{column}_err"], dof))
        decay = self.bounce_chain_decay
        rows.append(
            (
                "relaxation_eigenvalue",
                "lambda",
                "bounce-chain fit",
                decay["relaxation_eigenvalue"],
                decay["relaxation_eigenvalue_err"],
                shards - 1,
            )
        )
        table = pd.DataFrame(
            rows, columns=["observable", "symbol", "estimator", "value", "error", "dof"]
        )
        table.insert(5, "shards", shards)
        value, error = table["value"].to_numpy(float), table["error"].to_numpy(float)
        present = np.isfinite(value) & np.isfinite(error) & (error > 0.0)
        return table[present].reset_index(drop=True)

    @cached_property
    def _p0v_paper(self):
        """``p0v_histogram`` in the paper's units."""
        from ..estimators import outgoing_speed_histogram

        return outgoing_speed_histogram(
            list(self.tallies), self.restitution, self._theory_outgoing_density
        )

    @cached_property
    def p0v_histogram(self):
        """P(0, v) averaged over the speed bins (``estimators.outgoing_speed_histogram``):
        v_lo, v_hi, v, p0v, p0v_err, count; in ``units``."""
        return _in_units(self._p0v_paper, self.units)

    @cached_property
    def _position_paper(self):
        """``position_histogram`` in the paper's units."""
        from ..estimators import position_histogram

        return position_histogram(list(self.tallies))

    @cached_property
    def position_histogram(self):
        """P(x) and <v^2>_x averaged over the position bins (``estimators.position_histogram``),
        in ``units``."""
        return _in_units(self._position_paper, self.units)

    @property
    def px_histogram(self):
        """P(x) averaged over the position bins: x_lo, x_hi, x, px, px_err."""
        return self.position_histogram[["x_lo", "x_hi", "x", "px", "px_err"]]

    @property
    def v2_given_x_histogram(self):
        """<v^2>_x (eq. (moment2)) over the position bins: x_lo, x_hi, x, v2_given_x,
        v2_given_x_err."""
        return self.position_histogram[["x_lo", "x_hi", "x", "v2_given_x", "v2_given_x_err"]]

    @cached_property
    def pxv_histogram(self):
        """P(x, v) averaged over the cells (``estimators.distribution_histogram``): x_lo, x_hi,
        v_lo, v_hi, pxv, pxv_err; in ``units``."""
        from ..estimators import distribution_histogram

        return _in_units(distribution_histogram(list(self.tallies)), self.units)

    @cached_property
    def flight_time_histogram(self):
        """rho(T) per flight averaged over the flight-time bins
        (``estimators.flight_time_histogram``): t_lo, t_hi, t, density, density_err; in
        ``units``."""
        from ..estimators import flight_time_histogram

        return _in_units(flight_time_histogram(list(self.tallies)), self.units)

    @cached_property
    def return_speed_histogram(self):
        """The return speed's bin probabilities given the outgoing speed's bin
        (``estimators.return_speed_table``), the bins' edges in ``units``."""
        from ..estimators import return_speed_table

        return _in_units(return_speed_table(list(self.tallies)), self.units)

    @cached_property
    def bounce_autocorrelation(self):
        """The bounce chain's autocorrelations by lag (``estimators.bounce_autocorrelation``)."""
        from ..estimators import bounce_autocorrelation

        return bounce_autocorrelation(list(self.tallies))

    @cached_property
    def bounce_chain_decay(self):
        """The fitted decay of the bounce chain's correlations
        (``estimators.bounce_chain_decay``)."""
        from ..estimators import bounce_chain_decay

        return bounce_chain_decay(list(self.tallies))

    @cached_property
    def outside_fractions(self) -> dict:
        """How much of each table's distribution lies outside its finite bins
        (``estimators.outside_fractions``): {table: {below, above, outside, counts}} for
        ``p0v`` (collisions), ``position`` (time), ``flight_time`` (flights) and
        ``distribution`` (time)."""
        from ..estimators import outside_fractions

        return outside_fractions(list(self.tallies))

    @property
    def relaxation_eigenvalue(self) -> float:
        """lambda, the bounce chain's relaxation eigenvalue fitted to its correlations
        (``bounce_chain_decay``); NaN where fewer than 2 lags are resolved."""
        return float(self.bounce_chain_decay["relaxation_eigenvalue"])

    @property
    def relaxation_eigenvalue_err(self) -> float:
        """The jackknife error of ``relaxation_eigenvalue``."""
        return float(self.bounce_chain_decay["relaxation_eigenvalue_err"])

    def batch_frame(self):
        """The shards as one table in the workflow's batch format (``tallies.batch_to_frame``;
        ``results/simulation/r{r}/shards{first}-{last}.parquet``)."""
        from ..tallies import batch_to_frame

        return batch_to_frame(dict(zip(self.shard_indices, self.tallies)))

    def provenance(self) -> dict:
        """What ``save`` records with the shards: the kind, r, the seed (an int, or a
        SeedSequence's entropy, spawn key and pool size), the settings, the shard indices,
        the shards asked for and the units (gravity and noise) (JSON-ready)."""
        from ..restitution import exact_string

        return {
            "kind": RESULT_KIND,
            "r": exact_string(self.restitution),
            "r_label": self.label,
            "seed": _seed_record(self.seed),
            "settings": self.settings.as_mapping(),
            "shard_indices": [int(index) for index in self.shard_indices],
            "requested_shards": int(self.requested_shards),
            "units": {"gravity": self.units.gravity, "noise": self.units.noise},
        }

    def save(self, path):
        """Write the result to a Parquet file: its shards' tallies in the workflow's batch
        table (``tallies.batch_to_table``), with ``provenance()`` and the package version in
        the file's metadata (``parquet.write_table``: atomic, a reader never sees half a
        file).  ``bouncing_ball.load(path)`` gives it back, every observable bit-identical.

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (conventionally ``*.parquet``; ``~`` is the user's home); its
            folder is made if missing, an existing file replaced.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from bouncing_ball import load, simulate
        >>> result = simulate("1/2", shards=2, shard_time=200.0, seed=1, progress=False)
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "half.parquet"
        >>> result.save(path)
        >>> load(path).mean_x == result.mean_x
        True
        """
        from pathlib import Path

        from ..parquet import write_table
        from ..tallies import batch_to_table

        write_table(
            batch_to_table(dict(zip(self.shard_indices, self.tallies))),
            Path(path).expanduser(),
            self.provenance(),
        )

    def __repr__(self):
        row = self.summary_table.iloc[0]

        def shown(name, symbol):
            return f"{symbol} = {row[name]:.6g} +- {row[name + '_err']:.2g}"

        units = self.units
        given = "" if units.is_paper else f"gravity={units.gravity!r}, noise={units.noise!r}, "
        return (
            f"SimulationResult(r={self.restitution}, {given}"
            + (
                f"PARTIAL: shards={self.shards} of {self.requested_shards} (interrupted), "
                if self.partial
                else f"shards={self.shards}, "
            )
            + f"seed={_seed_text(self.seed)}, "
            f"total time {row.total_time:.6g}, {int(row.collisions)} collisions, "
            f"{int(row.steps)} steps): "
            + ", ".join(shown(name, symbol) for name, (symbol, _) in SCALARS.items())
            + (
                f"; {int(row.shards_out_of_budget)} shards stopped early (max_steps)"
                if row.shards_out_of_budget
                else ""
            )
        )


def load(path) -> SimulationResult:
    """The ``SimulationResult`` a file of ``SimulationResult.save`` holds: its shards'
    tallies, settings, seed, r and units, so every table and observable is bit-identical to
    the saved result's.

    Parameters
    ----------
    path : str or os.PathLike
        A Parquet file written by ``SimulationResult.save`` (``~`` is the user's home).

    Returns
    -------
    SimulationResult

    Raises
    ------
    parquet.UnreadableFileError
        Naming the file: a folder (naming the saved results it holds), missing, not a
        readable Parquet file (truncated, corrupt), without
        bouncing_ball's provenance, of another kind (e.g. a table of the workflow), or whose
        shards are not on its settings' bins.

    Examples
    --------
    See ``SimulationResult.save``.
    """
    from pathlib import Path

    import pyarrow.parquet as pq

    from ..parquet import UnreadableFileError, provenance_of, read_parquet
    from ..tallies import batch_from_table

    path = Path(path).expanduser()
    if path.is_dir():
        raise UnreadableFileError(_folder_message(path))
    table = read_parquet(pq.read_table, path)
    provenance = provenance_of(path, table.schema)
    if provenance.get("kind") != RESULT_KIND:
        written_by = provenance.get("rule") or provenance.get("kind") or "unknown"
        raise UnreadableFileError(
            f"{path}: not a saved SimulationResult (written by {written_by}); "
            "bouncing_ball.load reads the files of SimulationResult.save"
        )
    try:
        settings = ShardSettings.from_mapping(provenance["settings"])
        restitution = parse_restitution(provenance["r"], "r")
        seed = _seed_from_record(provenance["seed"])
        shards = batch_from_table(table, settings, source=str(path))
        indices = tuple(int(index) for index in provenance["shard_indices"])
        if sorted(shards) != sorted(indices):
            raise ValueError(
                f"its shards {sorted(shards)} are not its provenance's {sorted(indices)}"
            )
        return SimulationResult(
            restitution=restitution,
            seed=seed,
            settings=settings,
            tallies=tuple(shards[index] for index in indices),
            shard_indices=indices,
            requested_shards=int(provenance["requested_shards"]),
            units=PhysicalUnits(**provenance.get("units", {})),
        )
    except (KeyError, TypeError, ValueError) as error:
        raise UnreadableFileError(f"{path}: not a readable SimulationResult ({error})") from None


def _folder_message(folder) -> str:
    """Why ``load`` refuses a folder, naming the saved results in it."""
    from ..parquet import UnreadableFileError, read_provenance

    results = []
    for candidate in sorted(folder.glob("*.parquet")):
        try:
            if read_provenance(candidate).get("kind") == RESULT_KIND:
                results.append(candidate.name)
        except UnreadableFileError:
            continue
    if not results:
        return f"{folder}: a folder, not a file; it holds no saved SimulationResult"
    named = ", ".join(results)
    return (
        f"{folder}: a folder, not a file; it holds {len(results)} saved "
        f"result{'s' if len(results) > 1 else ''} ({named}): load one, e.g. "
        f"bouncing_ball.load({str(folder / results[0])!r})"
    )
