"""Each r's own scales: the ranges that hold its distributions, with no solve.

Near r = 1 speeds grow like (1 - r)^-1 and heights like (1 - r)^-2; near r_c the low-speed
end moves down by decades.  The simulation's bins and the solver's tables take their ranges
from here unless the config or the caller fixes them (``"auto"``).  Each range leaves at most
about ``TAIL_FRACTION`` of its distribution beyond each end, by the asymptotic forms of the
paper and of ``distribution.exponents``:

- outgoing speeds, collision-weighted (v P(0, v), eq. (collrate)): P(0, v) ~ v^-m e^(-q v) at
  large v, eqs. (asym4)-(asym6), so v_hi = ``DECAY_LENGTHS`` / q; P(0, v) ~ v^-beta at small
  v, eq. (asym1), so the collisions below v are a fraction of about (q v)^(2 - beta), and
  v_lo = eps^(1 / (2 - beta)) / q (eps = ``TAIL_FRACTION``);
- heights: P(x) ~ x^c e^(-b x^(1/2)) at large x, so x_hi = (``DECAY_LENGTHS`` / b)^2;
  P(x) ~ x^p at small x (p = (1 - beta)/3), so the time below x is a fraction of about
  (x / H)^(1 + p) with H = 1 / b^2, and x_lo = H eps^(1 / (1 + p)) / 5;
- flight times: a flight from speed u lasts about 2u, and a short one needs the noise to turn
  a speed below T^(1/2) round, so T_hi = 2.5 ``DECAY_LENGTHS`` / q (and at least
  ``LONGEST_NOISE_FLIGHT``, the flights the noise keeps up where q is large) and
  T_lo = eps^(2 / (2 - beta)) / q^2;
- velocities of P(x, v): abs(v) <= (``DECAY_LENGTHS`` + 4) / q, and at least 40.

Where 2 - beta is small (r just above r_c) or negative (below r_c, where the collapse is cut
off by the simulation's floor), the low ends stop at the smallest speed and time the
simulation resolves (``smallest_simulated_speed``) or the solver writes: there a range may
leave more than ``TAIL_FRACTION`` out, and each table says how much (``tail_fractions``).
The constants are checked against the solver at r = 0.05 to 0.999 (``tests/unit/test_scales.py``,
``tests/numerical/test_scales_coverage.py``).
"""

import math

import numpy as np

from .asymptotics import large_speed_decay_rate, small_speed_exponent
from .restitution import restitution_value

__all__ = [
    "TAIL_FRACTION",
    "AUTO",
    "outgoing_speed_range",
    "position_range",
    "flight_time_range",
    "velocity_range",
    "smallest_simulated_speed",
    "auto_log_bins",
    "auto_linear_bins",
    "resolve_bins",
    "has_auto",
    "resolve_grid",
    "SOLVER_TABLE_POINTS",
    "solver_table_ranges",
    "resolve_solver_grids",
    "tail_fractions",
    "outside_summary",
    "OUTSIDE_WARNING",
    "estimated_outside_fractions",
]

#: The fraction of a distribution outside an explicit bin set or grid above which the config
#: check warns, naming r, the key and the fraction.
OUTSIDE_WARNING = 1.0e-4

#: The parts of a config's log bins, linear bins and grids.
LOG_BIN_KEYS = ("lo", "hi", "per_decade")
LINEAR_BIN_KEYS = ("lo", "hi", "width")
GRID_KEYS = ("min", "max", "points")

#: The fraction of a distribution each end of an automatic range aims to leave out.
TAIL_FRACTION = 1.0e-6

#: The config's and the library's word for a range taken from r's scales.
AUTO = "auto"

#: q v_hi: e^(-q v) has fallen by e^-22 (5e-10) at the top of the speeds.
DECAY_LENGTHS = 22.0

#: The longest flights where q is large (r < 1/2): kept up by the noise, not by the outgoing
#: speed (the solver's flight-time density holds 1 - 1e-6 of the flights below about 70).
LONGEST_NOISE_FLIGHT = 150.0

#: Velocity bins of P(x, v) an automatic range is cut into.
VELOCITY_BINS = 320


def _exponents(restitution):
    r = restitution_value(restitution)
    return r, large_speed_decay_rate(r), small_speed_exponent(r)


def _low_end(scale, power, smallest, tail):
    """scale tail^(1 / power), or ``smallest`` where that is below it (or power <= 0)."""
    if power <= 0.0:
        return smallest
    log_end = math.log(scale) + math.log(tail) / power
    return max(smallest, math.exp(max(log_end, -745.0)))


def smallest_simulated_speed(min_step_floor=0.0, min_step_divisor=500.0) -> float:
    """The lowest outgoing speed the simulation's bins go down to.

    Without a floor on the step Delta a shard stops when its step falls below
    ``simulation.loop.COLLAPSED_STEP`` (1e-80), at the speed min_step_divisor (2 x 1e-80)^(1/2)
    (the paper's rule, sqrt(2 Delta) = v / divisor): a thousandth of that.  A floor cuts the
    collapse off at speeds of order (2 floor)^(1/2) (docs/methods.md, below r_c), but the
    collisions found inside a step reach far below it: at r = 0.05 and 0.1 with a floor of
    1e-12, 1e-4 of them are below 1e-17; so 1e-20 (2 floor)^(1/2).

    Parameters
    ----------
    min_step_floor : float, optional
        The shards' ``min_step_floor``, >= 0.
    min_step_divisor : float, optional
        The shards' ``min_step_divisor``, > 0.

    Returns
    -------
    float

    Examples
    --------
    >>> from bouncing_ball.scales import smallest_simulated_speed
    >>> print(f"{smallest_simulated_speed():.3g} {smallest_simulated_speed(1e-12):.3g}")
    7.07e-41 1.41e-26
    """
    collapsed_step = 1.0e-80  # simulation.loop.COLLAPSED_STEP (not imported: numba)
    if min_step_floor > 0.0:
        return 1e-20 * math.sqrt(2.0 * min_step_floor)
    return 1e-3 * min_step_divisor * math.sqrt(2.0 * collapsed_step)


def outgoing_speed_range(restitution, smallest=1e-100, tail=TAIL_FRACTION):
    """The outgoing speeds that hold all but about ``tail`` of the collisions at each end.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.
    smallest : float, optional
        The lowest speed to go to (``smallest_simulated_speed`` for the simulation; the
        solver's ``SMALLEST_OUTPUT_SPEED``, 1e-100, by default).
    tail : float, optional
        The fraction to leave beyond each end, 0 < tail < 1.

    Returns
    -------
    tuple of float
        (v_lo, v_hi): e^(-q v) is e^-22 at v_hi = 22 / q, eqs. (asym4)-(asym6); the
        collisions below v_lo, about (q v_lo)^(2 - beta) of them (eq. (asym1)), are ``tail``,
        or v_lo is ``smallest`` where 2 - beta is too small for that (r near or below r_c).

    Examples
    --------
    >>> from bouncing_ball.scales import outgoing_speed_range
    >>> print([f"{v:.3g}" for v in outgoing_speed_range(0.5)])
    ['1e-06', '22']
    >>> print([f"{v:.3g}" for v in outgoing_speed_range(0.99)])
    ['0.0635', '1.45e+03']
    """
    _, q, beta = _exponents(restitution)
    return _low_end(1.0 / q, 2.0 - beta, smallest, tail), DECAY_LENGTHS / q


def position_range(restitution, smallest=1e-300, tail=TAIL_FRACTION):
    """The heights that hold all but about ``tail`` of the time at each end.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.
    smallest : float, optional
        The lowest height to go to (``distribution.SMALLEST_POSITION`` by default).
    tail : float, optional
        The fraction to leave beyond each end, 0 < tail < 1.

    Returns
    -------
    tuple of float
        (x_lo, x_hi): P(x) ~ x^c e^(-b x^(1/2)) is e^-22 at x_hi = (22 / b)^2, and the time
        below x_lo, about (x / H)^(1 + p) with P(x) ~ x^p, p = (1 - beta)/3, H = 1 / b^2
        (``distribution.exponents.predicted_exponents``), is ``tail``.

    Examples
    --------
    >>> from bouncing_ball.scales import position_range
    >>> print([f"{x:.3g}" for x in position_range(0.5)])
    ['3e-07', '726']
    """
    _, q, beta = _exponents(restitution)
    b = _large_height_rate(q)
    power = 1.0 + (1.0 - beta) / 3.0
    return _low_end(0.2 / b**2, power, smallest, tail), (DECAY_LENGTHS / b) ** 2


def _large_height_rate(q):
    """b of P(x) ~ e^(-b x^(1/2)): (2/3)^(1/2) where q >= 1 (r <= 1/2), q (2 (3 - 2q)/3)^(1/2)
    above (``distribution.exponents.predicted_exponents``; not imported: it loads the solver)."""
    return math.sqrt(2.0 / 3.0) if q >= 1.0 else q * math.sqrt(2.0 * (3.0 - 2.0 * q) / 3.0)


def flight_time_range(restitution, smallest=1e-300, tail=TAIL_FRACTION):
    """The times between collisions that hold all but about ``tail`` of the flights at each end.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.
    smallest : float, optional
        The shortest flight to go to (the simulation's: its smallest speed squared).
    tail : float, optional
        The fraction to leave beyond each end, 0 < tail < 1.

    Returns
    -------
    tuple of float
        (T_lo, T_hi): T_hi = max(2.5 x 22 / q, 150); T_lo = tail^(2 / (2 - beta)) / q^2, the
        flights whose outgoing speed is below T^(1/2), or ``smallest``.

    Examples
    --------
    >>> from bouncing_ball.scales import flight_time_range
    >>> print([f"{t:.3g}" for t in flight_time_range(0.5)])
    ['1e-12', '150']
    """
    _, q, beta = _exponents(restitution)
    longest = max(2.5 * DECAY_LENGTHS / q, LONGEST_NOISE_FLIGHT)
    return _low_end(1.0 / q**2, 0.5 * (2.0 - beta), smallest, tail), longest


def velocity_range(restitution):
    """The largest abs(v) of the velocities P(x, v) is tabulated on.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    float
        max(26 / q, 40): a flight's abs(v) stays below its incoming speed, up to the noise, and
        the time at speeds above 26 / q is about e^-26 (q v)^2 of the whole; where q is large
        the noise keeps flights up longer (at r = 1/4 and 1/2 about 1e-6 of the time has
        abs(v) > 22, and in some runs at r = 1/4 3e-5 has v < -30).

    Examples
    --------
    >>> from bouncing_ball.scales import velocity_range
    >>> print(f"{velocity_range(0.5):.3g} {velocity_range(0.99):.4g}")
    40 1716
    """
    _, q, _ = _exponents(restitution)
    return max((DECAY_LENGTHS + 4.0) / q, 40.0)


def _power_tail(ratio, power):
    """min(1, ratio^power): the part of a power-law end below ``ratio`` of its scale."""
    if power <= 0.0:
        return 1.0
    return min(1.0, math.exp(power * math.log(max(ratio, 1e-300))))


def _exponential_tail(length, powers=1):
    """e^-length (1 + length)^powers, at most 1: an exponential end beyond ``length`` of its
    decay lengths."""
    return min(1.0, math.exp(-length) * (1.0 + length) ** powers) if length > 0 else 1.0


def estimated_outside_fractions(settings: dict, restitution) -> dict:
    """About how much of each distribution explicit shard bins leave outside at r.

    From the asymptotic forms that the automatic ranges follow (no solve).

    Parameters
    ----------
    settings : dict
        Config-shaped shard settings with explicit bins (``resolve_bins``' result).
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    dict
        {bin setting: fraction outside (both ends)}: of the collisions for speed_bins, the
        time for position_bins and velocity_bins, the flights for flight_time_bins; a rough
        estimate (within a factor of about 10 where it is small), for a warning.

    Examples
    --------
    >>> from bouncing_ball.scales import estimated_outside_fractions
    >>> bins = {"speed_bins": {"lo": 1e-4, "hi": 100, "per_decade": 10},
    ...         "position_bins": {"lo": 1e-3, "hi": 1e3, "per_decade": 5},
    ...         "velocity_bins": {"lo": -24, "hi": 20, "width": 0.25},
    ...         "flight_time_bins": {"lo": 1e-12, "hi": 1e3, "per_decade": 5}}
    >>> outside = estimated_outside_fractions(bins, 0.99)
    >>> print(f"{outside['speed_bins']:.2f} {outside['position_bins']:.2f}")
    0.55 0.85
    """
    _, q, beta = _exponents(restitution)
    b = _large_height_rate(q)
    speeds, heights = settings["speed_bins"], settings["position_bins"]
    flights, velocities = settings["flight_time_bins"], settings["velocity_bins"]
    largest = max(-velocities["lo"], velocities["hi"])
    fractions = {
        "speed_bins": _power_tail(q * speeds["lo"], 2.0 - beta)
        + _exponential_tail(q * speeds["hi"]),
        "position_bins": _power_tail(5.0 * b**2 * heights["lo"], (4.0 - beta) / 3.0)
        + _exponential_tail(b * math.sqrt(heights["hi"])),
        "flight_time_bins": _power_tail(q**2 * flights["lo"], 1.0 - 0.5 * beta)
        + max(_exponential_tail(q * flights["hi"] / 2.5), math.exp(-flights["hi"] / 5.0)),
        "velocity_bins": 2.0 * _exponential_tail(q * min(-velocities["lo"], largest), 2),
    }
    return {name: min(1.0, fraction) for name, fraction in fractions.items()}


def has_auto(spec, keys) -> bool:
    """Whether a bin set or grid (config-shaped) asks for any part from r's scales.

    Parameters
    ----------
    spec : object
        ``"auto"``, a dict, or anything else (a ``bins.LogBins``: explicit).
    keys : tuple of str
        Its parts: ("lo", "hi", "per_decade") of log bins, ("lo", "hi", "width") of linear
        bins, ("min", "max", "points") of a grid.

    Returns
    -------
    bool
        True for ``"auto"``, or a dict with a part ``"auto"`` or missing.

    Examples
    --------
    >>> from bouncing_ball.scales import has_auto
    >>> has_auto({"lo": 1e-4, "hi": 100}, ("lo", "hi", "per_decade"))
    True
    """
    if isinstance(spec, str):
        return spec == AUTO
    return isinstance(spec, dict) and any(spec.get(key, AUTO) == AUTO for key in keys)


def _filled(spec, defaults: dict) -> dict:
    """The parts of ``spec`` ("auto" or a dict), each one that is "auto" or missing taken from
    ``defaults``."""
    spec = {} if spec == AUTO else spec
    return {
        key: value if spec.get(key, AUTO) == AUTO else spec[key] for key, value in defaults.items()
    }


def _decade_aligned(lo, hi, per_decade):
    """lo rounded down and hi up to the grid 10^(k / per_decade)."""
    k_lo = math.floor(math.log10(lo) * per_decade + 1e-9)
    k_hi = math.ceil(math.log10(hi) * per_decade - 1e-9)
    return 10.0 ** (k_lo / per_decade), 10.0 ** (k_hi / per_decade)


def auto_log_bins(spec, default_range, per_decade):
    """A config-shaped ``{lo, hi, per_decade}`` with each ``"auto"`` part filled in.

    Parameters
    ----------
    spec : str or dict
        ``"auto"``, or a dict whose lo, hi and per_decade may each be ``"auto"`` or missing.
    default_range : tuple of float
        (lo, hi) of r's scales.
    per_decade : int
        Bins per decade where the spec does not say.

    Returns
    -------
    dict
        {lo, hi, per_decade}: the automatic ends on the grid 10^(k / per_decade), so that the
        bins of two r share edges where they overlap.
    """
    density = int(_filled(spec, {"per_decade": per_decade})["per_decade"])
    lo, hi = _decade_aligned(*default_range, density)
    filled = _filled(spec, {"lo": lo, "hi": hi})
    return {"lo": float(filled["lo"]), "hi": float(filled["hi"]), "per_decade": density}


def auto_linear_bins(spec, largest, bins=VELOCITY_BINS):
    """A config-shaped ``{lo, hi, width}`` with each ``"auto"`` part filled in.

    Parameters
    ----------
    spec : str or dict
        ``"auto"``, or a dict whose lo, hi and width may each be ``"auto"`` or missing.
    largest : float
        The largest abs(v) of r's scales (``velocity_range``).
    bins : int, optional
        The bins an automatic width cuts [lo, hi] into.

    Returns
    -------
    dict
        {lo, hi, width}; an automatic width is 1, 2, 2.5 or 5 times a power of 10.
    """
    filled = _filled(spec, {"lo": -largest, "hi": largest, "width": AUTO})
    lo, hi, width = float(filled["lo"]), float(filled["hi"]), filled["width"]
    if width == AUTO:
        raw = (hi - lo) / bins
        decade = 10.0 ** math.floor(math.log10(raw))
        width = next(step * decade for step in (1.0, 2.0, 2.5, 5.0, 10.0) if step * decade >= raw)
        lo, hi = math.floor(lo / width) * width, math.ceil(hi / width) * width
    return {"lo": float(lo), "hi": float(hi), "width": float(width)}


def resolve_bins(settings: dict, restitution) -> dict:
    """The shard settings (config-shaped) with every ``"auto"`` bin set made explicit at r.

    Parameters
    ----------
    settings : dict
        Config-shaped shard settings; speed_bins, position_bins, velocity_bins and
        flight_time_bins may be ``"auto"``, partly automatic dicts, or missing (automatic).
        min_step_floor and min_step_divisor (missing: 0 and 500) set the lowest speed.
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    dict
        A copy with the four bin sets explicit: the same for every shard of r, a function of r
        and the settings only.

    Examples
    --------
    >>> from bouncing_ball.scales import resolve_bins
    >>> bins = resolve_bins({"speed_bins": "auto"}, 0.99)["speed_bins"]
    >>> print(f"{bins['lo']:.3g} {bins['hi']:.4g} {bins['per_decade']}")
    0.0631 1585 10
    """
    floor = float(settings.get("min_step_floor", 0.0))
    divisor = float(settings.get("min_step_divisor", 500.0))
    # out of range, the shard settings' own check refuses them; the bins need some value
    floor = floor if 0.0 <= floor < 1.0 else 0.0
    divisor = divisor if 0.0 < divisor < 1e100 else 500.0
    speed = smallest_simulated_speed(floor, divisor)
    automatic = {
        "speed_bins": lambda spec: auto_log_bins(
            spec, outgoing_speed_range(restitution, speed), 10
        ),
        "position_bins": lambda spec: auto_log_bins(spec, position_range(restitution, speed**2), 5),
        "flight_time_bins": lambda spec: auto_log_bins(
            spec, flight_time_range(restitution, speed**2), 5
        ),
        "velocity_bins": lambda spec: auto_linear_bins(spec, velocity_range(restitution)),
    }
    resolved = dict(settings)
    for name, fill in automatic.items():
        spec = settings.get(name, AUTO)
        keys = LINEAR_BIN_KEYS if name == "velocity_bins" else LOG_BIN_KEYS
        if has_auto(spec, keys):
            resolved[name] = fill(spec)
    return resolved


def resolve_grid(spec, default_range, points):
    """A config-shaped log grid ``{min, max, points}`` with each ``"auto"`` part filled in.

    Parameters
    ----------
    spec : str or dict
        ``"auto"``, or a dict whose min, max and points may each be ``"auto"`` or missing.
    default_range : tuple of float
        (min, max) of r's scales.
    points : int
        Points where the spec does not say.

    Returns
    -------
    dict
        {min, max, points}.
    """
    filled = _filled(spec, {"min": default_range[0], "max": default_range[1], "points": points})
    return {
        "min": float(filled["min"]),
        "max": float(filled["max"]),
        "points": int(filled["points"]),
    }


#: The solver's tables that follow r (rule solve, ``solver.*`` of the config): their points
#: where the config does not say.
SOLVER_TABLE_POINTS = {
    "output_speeds": 401,
    "flight_times": 151,
    "position_grid": 141,
    "speeds": 801,
    "forces": 121,
}

# the ends the solver's tables may reach: solver.SMALLEST_OUTPUT_SPEED, the flight-time table's
# range (flight_time.FLIGHT_TIME_TABLE_RANGE) and distribution.SMALLEST_WEIGHT_FORCE (not
# imported: they load the solver)
_SOLVER_SMALLEST_SPEED = 1e-100
_FLIGHT_TIME_TABLE_RANGE = (1e-100, 1e5)
_SMALLEST_WEIGHT_FORCE = 2e-4


def solver_table_ranges(restitution) -> dict:
    """The ranges of the solver's tables at r, with no solve: {config key: (min, max)}.

    Parameters
    ----------
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    dict
        ``output_speeds`` (``outgoing_speed_range`` down to 1e-100), ``flight_times``
        (``flight_time_range`` within the flight-time table's 1e-100 .. 1e5),
        ``position_grid`` (``position_range``), ``speeds`` (+- ``velocity_range``) and
        ``forces``: the F of eq. (weightfunc) whose saddle point F ~ b / (2 x^(1/2)) of
        eq. (P(x)1) lies in the heights' range, a decade more each way, from 2e-4 (below,
        w(F) overflows as r -> 1).

    Examples
    --------
    >>> from bouncing_ball.scales import solver_table_ranges
    >>> ranges = solver_table_ranges(0.5)
    >>> print(f"{ranges['position_grid'][1]:.3g} {ranges['forces'][0]:.3g}")
    726 0.00152
    """
    _, q, _ = _exponents(restitution)
    heights = position_range(restitution)
    b = _large_height_rate(q)
    shortest, longest = flight_time_range(restitution, _FLIGHT_TIME_TABLE_RANGE[0])
    largest = velocity_range(restitution)
    return {
        "output_speeds": outgoing_speed_range(restitution, _SOLVER_SMALLEST_SPEED),
        "flight_times": (shortest, min(longest, _FLIGHT_TIME_TABLE_RANGE[1])),
        "position_grid": heights,
        "speeds": (-largest, largest),
        "forces": (
            max(_SMALLEST_WEIGHT_FORCE, 0.05 * b / math.sqrt(heights[1])),
            5.0 * b / math.sqrt(heights[0]),
        ),
    }


def resolve_solver_grids(settings: dict, restitution) -> dict:
    """The solver's settings (config-shaped) with every ``"auto"`` grid made explicit at r.

    Parameters
    ----------
    settings : dict
        The config's ``solver`` settings; each grid of ``SOLVER_TABLE_POINTS`` may be
        ``"auto"``, partly automatic, or explicit.
    restitution : float, str or fractions.Fraction
        r, 0 < r < 1.

    Returns
    -------
    dict
        A copy with those grids explicit ({min, max, points}).
    """
    resolved = dict(settings)
    ranges = None
    for name, points in SOLVER_TABLE_POINTS.items():
        spec = settings.get(name, AUTO)
        if has_auto(spec, GRID_KEYS):
            ranges = solver_table_ranges(restitution) if ranges is None else ranges
            resolved[name] = resolve_grid(spec, ranges[name], points)
    return resolved


def tail_fractions(edges, mass_density):
    """The fractions of a distribution below and above a table's range, from the table alone.

    Each end's tail is continued by the power law that the table's last two points show
    (``mass_density`` ~ z^s near the end): the mass below the lowest point z_0 is
    z_0 f(z_0) / (s_0 + 1) for s_0 > -1, the mass above the highest z_n is z_n f(z_n) / (-s_n - 1)
    for s_n < -1, over the mass inside (the trapezoidal rule in ln z).  A tail that the slope
    cannot bound (s_0 <= -1 or s_n >= -1) is reported as inf: the table does not hold the
    distribution's end.

    Parameters
    ----------
    edges : array_like
        The table's points z, positive and increasing, at least 3.
    mass_density : array_like
        The density of the distribution over z at those points (of collisions: v P(0, v); of
        time: P(x); of flights), >= 0.

    Returns
    -------
    tuple of float
        (below, above), each a fraction of the whole (inside and both tails).

    Examples
    --------
    >>> import numpy as np
    >>> from bouncing_ball.scales import tail_fractions
    >>> z = np.geomspace(1e-3, 30.0, 400)
    >>> below, above = tail_fractions(z, z * np.exp(-z))   # mass z e^-z: Gamma(2)
    >>> print(f"{below:.2e} {above:.2e}")
    5.00e-07 3.05e-12
    """
    z = np.asarray(edges, dtype=float)
    f = np.asarray(mass_density, dtype=float)
    log_z = np.log(z)
    inside = np.sum(0.5 * (z[1:] * f[1:] + z[:-1] * f[:-1]) * np.diff(log_z))
    tails = []
    for first, second in ((0, 1), (-1, -2)):
        if f[first] <= 0.0:
            tails.append(0.0)
            continue
        slope = (np.log(f[second]) - np.log(f[first])) / (log_z[second] - log_z[first])
        beyond = slope + 1.0 if first == 0 else -slope - 1.0
        tails.append(z[first] * f[first] / beyond if beyond > 0.0 else math.inf)
    total = inside + sum(tails)
    if not math.isfinite(total) or total <= 0.0:
        # an unbounded end holds all of an infinite whole; a bounded one, none of it
        return tuple(math.inf if not math.isfinite(t) else 0.0 for t in tails)
    return tails[0] / total, tails[1] / total


def outside_summary(fractions: dict) -> str:
    """One line of how much of each table's distribution lies outside its range.

    Parameters
    ----------
    fractions : dict
        {table: {"below", "above", "outside", "counts"}}, as ``estimators.outside_fractions``
        and ``workflow.solver_tables.outside_fractions`` give them (None: unbounded).

    Returns
    -------
    str

    Examples
    --------
    >>> from bouncing_ball.scales import outside_summary
    >>> print(outside_summary({"p0v": {"below": 1e-7, "above": 0.0, "outside": 1e-7,
    ...                                "counts": "collisions"}}))
    outside the tables' ranges: p0v 1.0e-07 of the collisions (below 1.0e-07, above 0.0e+00)
    """

    def shown(value):
        return "unbounded" if value is None else f"{value:.1e}"

    return "outside the tables' ranges: " + "; ".join(
        f"{name} {shown(part['outside'])} of the {part['counts']} (below {shown(part['below'])}, "
        f"above {shown(part['above'])})"
        for name, part in fractions.items()
    )
