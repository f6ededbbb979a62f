"""What one simulation shard is run with: the one home of the shard settings.

The config's ``simulation`` section (with its per-r overrides, see
``config.shard_settings``), the workflow's rule parameters, a shard's
provenance, the compiled loop (``simulation.simulate_shard``), its C reference
(``benchmarks/reference_loop.py``) and the studies all use ``ShardSettings``.
The number of shards is not a shard setting: adding shards leaves the
existing ones alone.
"""

import math
import numbers
from dataclasses import asdict, dataclass, fields, replace

from .bins import LinearBins, LogBins, linear_bins, log_bins

__all__ = [
    "ShardSettings",
    "MAX_STEPS_LIMIT",
    "MIN_CRITERION_C",
    "MAX_MIN_STEP_FLOOR",
    "MAX_SHARDS",
    "real_number",
    "whole_number",
    "DEFAULT_SPEED_BINS",
    "DEFAULT_POSITION_BINS",
    "DEFAULT_VELOCITY_BINS",
    "DEFAULT_FLIGHT_TIME_BINS",
    "RETURN_LAW_BINS_PER_DECADE",
    "return_law_speed_bins",
]

#: The largest step budget: far beyond any shard (10^15 steps are years of CPU), far inside
#: the compiled loop's 64-bit step counter (9.2e18); the config schema repeats it.
MAX_STEPS_LIMIT = 10**15

#: The smallest c of eq. (criterion): below about 2 a step overshoots excursions below the
#: floor that it cannot see, and the results are biased (docs/validation.md, the criterion-bias
#: study; the default 3 keeps a margin above it).  The config schema repeats it.
MIN_CRITERION_C = 2.0

#: The largest min_step_floor: it regularises the collapse below r_c at speeds of order
#: (2 floor)^(1/2) (docs/methods.md, below r_c); a larger floor moves the speeds the
#: simulation resolves into the range it reports.  The config schema repeats it.
MAX_MIN_STEP_FLOOR = 1.0e-6

#: The most shards of one r (``simulate``'s ``shards``, the config's ``simulation.shards``):
#: the merge holds every shard's tallies.  The config schema repeats it.
MAX_SHARDS = 10**6

# the bins of the tallies, when a config or a caller does not name them (the default config
# names them; config/README.md says why these)
#: Outgoing speeds, P(0, v): 1e-4 to 100, 10 bins per decade.
DEFAULT_SPEED_BINS = LogBins(1.0e-4, 1.0e2, 10)
#: Heights, P(x) and <v^2>_x: 1e-3 to 1000, 5 bins per decade.
DEFAULT_POSITION_BINS = LogBins(1.0e-3, 1.0e3, 5)
#: Velocities of the 2-D P(x, v): -24 to 20 in steps of 0.25.
DEFAULT_VELOCITY_BINS = LinearBins(-24.0, 20.0, 0.25)
#: Times between collisions: 1e-12 to 1000, 5 bins per decade.
DEFAULT_FLIGHT_TIME_BINS = LogBins(1.0e-12, 1.0e3, 5)
#: Bins per decade of the fine outgoing speeds (``return_law_speed_bins``).
RETURN_LAW_BINS_PER_DECADE = 100


def return_law_speed_bins(speed_bins: LogBins) -> LogBins:
    """The fine bins of outgoing speeds every shard records beside ``speed_bins``.

    The same range at ``RETURN_LAW_BINS_PER_DECADE`` bins per decade: fine enough that the
    return-speed law of eq. (kernel3) hardly varies within a bin, for the return-law control of
    P(0, v) (``estimators.return_law_prediction``); the range is the speed bins', which follow
    r's scales (``scales``).  Not a setting of its own.

    Parameters
    ----------
    speed_bins : LogBins
        The shard's bins of outgoing speeds.

    Returns
    -------
    LogBins

    Examples
    --------
    >>> from bouncing_ball.bins import LogBins
    >>> from bouncing_ball.settings import return_law_speed_bins
    >>> return_law_speed_bins(LogBins(1e-4, 100.0, 10)).n
    600
    """
    return LogBins(speed_bins.lo, speed_bins.hi, RETURN_LAW_BINS_PER_DECADE)


@dataclass(frozen=True)
class ShardSettings:
    """The parameters that decide a shard's numbers (with its r, seed and index).

    Parameters
    ----------
    shard_time : float
        Simulated time recorded, after equilibration, > 0.
    equilibration_time : float
        Simulated time run and discarded first, >= 0.
    criterion_c : float
        The constant c of the step criterion, eq. (criterion), at least ``MIN_CRITERION_C``
        (below it the results are biased).
    min_step_divisor : float
        After each collision the step is sqrt(2 Delta) = v_out / min_step_divisor, > 0.
    max_steps : int
        The step budget, equilibration included, 1 to ``MAX_STEPS_LIMIT``.
    speed_bins : LogBins or dict
        Bins of outgoing speeds, P(0, v) (a dict: ``{lo, hi, per_decade}``).
    position_bins : LogBins or dict
        Bins of heights, P(x) and <v^2>_x.
    min_step_floor : float
        Lower bound on the step Delta, 0 (the paper's rule alone) to ``MAX_MIN_STEP_FLOOR``.
    velocity_bins : LinearBins or dict
        Bins of v of the 2-D P(x, v), its x-bins being ``position_bins`` (a dict:
        ``{lo, hi, width}``).
    flight_time_bins : LogBins or dict
        Bins of the times between collisions.

    Every number may be a Python or a numpy scalar; the times, c, the divisor and the floor
    must be finite.

    Raises
    ------
    TypeError
        Naming a setting that is not a real number (a string, a bool).
    ValueError
        Naming every setting out of its range, or a max_steps that is not a whole number.

    Examples
    --------
    >>> from bouncing_ball.settings import ShardSettings
    >>> settings = ShardSettings(
    ...     shard_time=1e4, equilibration_time=100, criterion_c=5, min_step_divisor=10,
    ...     max_steps=1e9,
    ... )
    >>> settings.max_steps, settings.speed_bins.per_decade
    (1000000000, 10)
    >>> ShardSettings.from_mapping(settings.as_mapping()) == settings
    True
    >>> settings.replace(shard_time=-1.0)
    Traceback (most recent call last):
    ...
    ValueError: shard settings: shard_time = -1.0 must be positive
    """

    shard_time: float  # simulated time recorded, after equilibration
    equilibration_time: float  # simulated time run and discarded first
    criterion_c: float  # c of eq. (criterion)
    min_step_divisor: float  # sqrt(2 delta) = v_out / min_step_divisor after each collision
    max_steps: int  # step budget, equilibration included
    speed_bins: LogBins = DEFAULT_SPEED_BINS  # outgoing speeds, P(0, v)
    position_bins: LogBins = DEFAULT_POSITION_BINS  # heights, P(x) and <v^2>_x
    min_step_floor: float = 0.0  # lower bound on delta (0: the paper's rule alone)
    velocity_bins: LinearBins = DEFAULT_VELOCITY_BINS  # v of the 2-D P(x, v) (x: position_bins)
    flight_time_bins: LogBins = DEFAULT_FLIGHT_TIME_BINS  # times between collisions

    def __post_init__(self):
        for name in (
            "shard_time",
            "equilibration_time",
            "criterion_c",
            "min_step_divisor",
            "min_step_floor",
        ):
            object.__setattr__(self, name, real_number(getattr(self, name), name))
        max_steps = real_number(self.max_steps, "max_steps")
        if not max_steps.is_integer():
            raise ValueError(f"max_steps must be a whole number, got {self.max_steps}")
        object.__setattr__(self, "max_steps", int(self.max_steps))
        for name in ("speed_bins", "position_bins", "flight_time_bins"):
            value = getattr(self, name)
            if not isinstance(value, LogBins):
                object.__setattr__(self, name, log_bins(value))
        if not isinstance(self.velocity_bins, LinearBins):
            object.__setattr__(self, "velocity_bins", linear_bins(self.velocity_bins))
        problems = [
            f"{name} = {getattr(self, name)} must be {rule}"
            for name, rule, holds in (
                ("shard_time", "positive", 0.0 < self.shard_time < math.inf),
                ("equilibration_time", "0 or more", 0.0 <= self.equilibration_time < math.inf),
                (
                    "criterion_c",
                    f"at least {MIN_CRITERION_C:g} (below it a step overshoots excursions "
                    "below the floor it cannot see, and the results are biased)",
                    MIN_CRITERION_C <= self.criterion_c < math.inf,
                ),
                ("min_step_divisor", "positive", 0.0 < self.min_step_divisor < math.inf),
                (
                    "max_steps",
                    f"between 1 and {MAX_STEPS_LIMIT:.0e}",
                    1 <= self.max_steps <= MAX_STEPS_LIMIT,
                ),
                (
                    "min_step_floor",
                    f"between 0 and {MAX_MIN_STEP_FLOOR:g} (a larger floor biases the speeds "
                    "the simulation reports)",
                    0.0 <= self.min_step_floor <= MAX_MIN_STEP_FLOOR,
                ),
            )
            if not holds
        ]
        if problems:
            raise ValueError("shard settings: " + "; ".join(problems))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The settings' keys, as in the config's ``simulation`` section.

        Returns
        -------
        tuple of str
            The field names, in the order of the class.
        """
        return tuple(field.name for field in fields(cls))

    @classmethod
    def from_mapping(cls, mapping: dict) -> "ShardSettings":
        """The settings from a config-shaped dict.

        Parameters
        ----------
        mapping : dict
            Bins as ``{lo, hi, per_decade}``, velocity_bins as ``{lo, hi, width}``; other keys
            are ignored, missing optional ones take their defaults.

        Returns
        -------
        ShardSettings
        """
        return cls(**{name: mapping[name] for name in cls.names() if name in mapping})

    def as_mapping(self) -> dict:
        """The config-shaped, JSON-ready dict: a rule parameter and a shard's provenance.

        Returns
        -------
        dict
            The inverse of ``from_mapping``.
        """
        return asdict(self)

    def replace(self, **changes) -> "ShardSettings":
        """A copy with some settings changed (and checked again).

        Parameters
        ----------
        **changes
            New values, by setting name.

        Returns
        -------
        ShardSettings
        """
        return replace(self, **changes)


def whole_number(value, name: str, least: int, most: int | None = None) -> int:
    """``value`` as an int, if it is a whole number in [``least``, ``most``].

    A Python or numpy integer; a bool is not one.

    Parameters
    ----------
    value : object
        The value given.
    name : str
        The argument's name, for the message.
    least, most : int
        The bounds, both included (``most`` None: no upper bound).

    Returns
    -------
    int

    Raises
    ------
    TypeError
        Naming ``name``, for anything but an integer (a bool, a float, a string, None).
    ValueError
        Naming ``name`` and the bound it is outside.

    Examples
    --------
    >>> from bouncing_ball.settings import whole_number
    >>> whole_number(3, "shards", 2)
    3
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be a whole number, got {value!r}")
    if value < least:
        raise ValueError(f"{name} must be >= {least}, got {value}")
    if most is not None and value > most:
        raise ValueError(f"{name} must be <= {most}, got {value}")
    return int(value)


def real_number(value, name: str) -> float:
    """``value`` as a float, if it is a real number: a Python or numpy integer or float.

    Parameters
    ----------
    value : object
        The value given.
    name : str
        The argument's name, for the message.

    Returns
    -------
    float
        ``float(value)`` (which may be NaN or infinite: the caller states the range).

    Raises
    ------
    TypeError
        Naming ``name``, for anything else (a bool, a string, None, an array).

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.settings import real_number
    >>> real_number(np.int64(50), "shard_time"), real_number(np.float32(0.5), "shard_time")
    (50.0, 0.5)
    >>> real_number("50", "shard_time")
    Traceback (most recent call last):
    ...
    TypeError: shard_time must be a number, got '50'
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a number, got {value!r}")
    return float(value)
