"""The equilibrium state at one r, as one object: ``Equilibrium`` (any r the solver answers)
and ``ExactEquilibrium`` (the paper's r = 1/2 and 1/3 solutions), with the same attributes and
methods, so that one can stand in for the other.

``Equilibrium(r)`` solves eq. (inteq) for P(0, v) once, with the given quadrature step
(``distribution.outgoing_speed_solution``: its nodes reach where P(0, v) falls to e^-690, as
w(F) at small F needs), and builds the weight function w(F) of eq. (weightfunc) from that
solution (``distribution``) the first time a position-dependent quantity is asked for (P(x),
<v^2>_x, P(x, v), w(F): about a second).  It is the workflow's solve rule (scripts/solve.py
writes its tables to ``results/solver/r{r}/``), so every number is the one the rule writes for
the same settings.  Above ``restitution.DISTRIBUTION_RESTITUTION_RANGE`` (up to
``SOLVER_RESTITUTION_RANGE``) it gives P(0, v), the time averages, the flight times and the
exponents, and its position-dependent methods raise ValueError naming r and the range.

Its accuracy is measured, not assumed: ``accuracy`` is the solver's own estimate, the largest
relative change of P(0, v) for 1e-3 <= v <= 20 against a finer solve
(``solver.accuracy_estimate``); ``position_accuracy`` is how far int P(x) dx, <x> and Delta x
from P(x) of eq. (P(x)1) are from 1 and from the Ito identities of the solver (a test of the
whole w(F) route).

Every method takes arrays and broadcasts like numpy (a scalar in, a numpy scalar out).  Input
that has no answer (a negative height, a NaN, shapes that do not broadcast) raises ValueError
naming the argument; nothing returns a silent NaN.
"""

import functools
import math
from fractions import Fraction

import numpy as np
import pandas as pd
from scipy import integrate

from .restitution import (
    DISTRIBUTION_RESTITUTION_RANGE,
    EXACT_RESTITUTIONS,
    SOLVER_RESTITUTION_RANGE,
    check_solver_restitution,
    in_range,
    parse_restitution,
    restitution_label,
)

__all__ = ["Equilibrium", "ExactEquilibrium"]


# ---------------------------------------------------------------------------------------------
# input checks


def _real_array(value, name: str) -> np.ndarray:
    """``value`` as a float array; TypeError naming ``name`` if it is not real numbers,
    ValueError if it holds NaN or an infinity."""
    try:
        array = np.asarray(value)
    except ValueError as error:  # ragged nested lists
        raise ValueError(f"{name}: not an array of numbers ({error})") from None
    if array.dtype == bool or not (
        np.issubdtype(array.dtype, np.integer) or np.issubdtype(array.dtype, np.floating)
    ):
        raise TypeError(f"{name} must be real numbers, got {value!r} (dtype {array.dtype})")
    array = array.astype(float)
    if np.isnan(array).any():
        raise ValueError(f"{name} contains NaN")
    if np.isinf(array).any():
        raise ValueError(f"{name} must be finite, got an infinity")
    return array


def _checked(value, name: str, *, low: float | None = None, strictly: bool = False) -> np.ndarray:
    """``_real_array`` refusing values below ``low`` (or at it, when ``strictly``)."""
    array = _real_array(value, name)
    if low is not None:
        bad = array <= low if strictly else array < low
        if bad.any():
            relation = ">" if strictly else ">="
            raise ValueError(
                f"{name} must be {relation} {low:g}, got {array[bad].flat[0]:g}"
                + (f" at index {np.argwhere(bad)[0].tolist()}" if array.ndim else "")
            )
    return array


def _broadcast(first, second, names):
    """The two arrays broadcast together; ValueError naming both if their shapes do not."""
    try:
        return np.broadcast_arrays(first, second)
    except ValueError:
        raise ValueError(
            f"{names[0]} (shape {first.shape}) and {names[1]} (shape {second.shape}) do not "
            "broadcast to one shape"
        ) from None


def _infinity_defects(tables) -> list:
    """'name: n of m column are infinite' for every column of every table holding +-inf (no
    table of rule solve has one where its value is defined: P(0, 0) and P(x = 0, v = 0) are
    NaN, and every flight time is > 0)."""
    defects = []
    for name, table in tables.items():
        for column in table.columns:
            values = pd.to_numeric(table[column], errors="coerce").to_numpy(dtype=float)
            infinite = np.isinf(values)
            if infinite.any():
                defects.append(
                    f"{name}: {int(infinite.sum())} of {values.size} {column} are infinite"
                )
    return defects


def _out(array):
    """A numpy scalar for a 0-d result, the array otherwise."""
    return array[()] if array.ndim == 0 else array


# ---------------------------------------------------------------------------------------------
# what both classes share


class _EquilibriumState:
    """The interface of ``Equilibrium`` and ``ExactEquilibrium``: the checks and the parts that
    do not depend on how P(0, v) is known."""

    restitution: Fraction
    r: float
    label: str

    def _set_restitution(self, exact: Fraction) -> None:
        from .asymptotics import large_speed_decay_rate, large_speed_exponent, small_speed_exponent

        self.restitution = exact
        self.r = float(exact)
        self.label = restitution_label(exact)
        self.beta = float(small_speed_exponent(self.r))
        self.m = float(large_speed_exponent(self.r))
        self.q = float(large_speed_decay_rate(self.r))

    # --- what each class supplies
    def _outgoing(self, v):  # P(0, v), v > 0
        raise NotImplementedError

    def _floor_density(self) -> float:  # P(x = 0) = int dv P(0, v), both sides
        raise NotImplementedError

    def _position(self, x):  # P(x), x > 0
        raise NotImplementedError

    def _speed_squared(self, x):  # <v^2>_x, x > 0
        raise NotImplementedError

    def _joint(self, x, v):  # P(x, v), x >= 0 (NaN at x = v = 0)
        raise NotImplementedError

    def _weight(self, force):  # w(F), F > 0
        raise NotImplementedError

    def _flight_rate(self, times):  # nu(T), T > 0 (flight_time.flight_rate_in_regimes)
        raise NotImplementedError

    def _short_flight_amplitude(self) -> float:  # A C_beta of nu ~ A C_beta T^(-beta/2)
        raise NotImplementedError

    def _check_distribution(self, what: str) -> None:  # ValueError where P(x) is not computed
        pass

    # --- the public methods
    def p0v(self, v):
        """P(0, v) on the outgoing side of the floor, eq. (P(0,v)) (exact) or eq. (inteq).

        Parameters
        ----------
        v : array_like
            Outgoing speeds, v >= 0.  (The incoming side is ``pxv(0, -v)``, eq. (bc).)

        Returns
        -------
        numpy.ndarray or numpy.float64
            P(0, v), the shape of ``v``; inf at v = 0, where P(0, v) ~ v^-beta diverges
            (eq. (asym1)).

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").p0v([0.5, 1.0, 2.0]).round(6))
        [0.404354 0.122626 0.022556]
        """
        v = _checked(v, "v", low=0.0)
        result = np.full(v.shape, np.inf)
        positive = v > 0.0
        result[positive] = self._outgoing(v[positive])
        return _out(result)

    def px(self, x):
        """P(x), the density of the height x, eq. (P(x)1) (eq. (P(x)2) for the exact solutions).

        Parameters
        ----------
        x : array_like
            Heights, x >= 0.

        Returns
        -------
        numpy.ndarray or numpy.float64
            P(x), the shape of ``x``.  At x = 0 it is int P(0, v) dv over both sides,
            (1 + r) int_0^inf P(0, v) dv by eq. (bc): inf where beta >= 1 (r <= 1/2).

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").px([0.1, 1.0, 10.0]).round(6))
        [0.503776 0.183784 0.018862]
        """
        self._check_distribution("px")
        x = _checked(x, "x", low=0.0)
        result = np.full(x.shape, self._floor_density())
        positive = x > 0.0
        if positive.any():
            result[positive] = self._position(x[positive])
        return _out(result)

    def v2_given_x(self, x):
        """<v^2>_x, the mean squared velocity at height x, eq. (moment2):
        P(x)^-1 int_x^inf P(x') dx'.

        Parameters
        ----------
        x : array_like
            Heights, x >= 0.

        Returns
        -------
        numpy.ndarray or numpy.float64
            <v^2>_x, the shape of ``x``; 1 / P(0) at x = 0 (0 where P(0) = inf).

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").v2_given_x([0.1, 1.0]).round(6))
        [1.853157 3.710784]
        """
        self._check_distribution("v2_given_x")
        x = _checked(x, "x", low=0.0)
        result = np.full(x.shape, 1.0 / self._floor_density())
        positive = x > 0.0
        if positive.any():
            result[positive] = self._speed_squared(x[positive])
        return _out(result)

    def pxv(self, x, v):
        """P(x, v), the joint density of height and velocity, eq. (fpsol); at x = 0 the
        outgoing side is P(0, v) and the incoming side eq. (bc), P(0, -v) = r^2 P(0, r v).

        Parameters
        ----------
        x : array_like
            Heights, x >= 0.
        v : array_like
            Velocities (either sign), broadcast against ``x``.

        Returns
        -------
        numpy.ndarray or numpy.float64
            P(x, v), the broadcast shape; inf at x = v = 0, where P(0, v) diverges.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").pxv(0.1, [-1.0, 0.0, 1.0]).round(6))
        [0.074292 0.198028 0.146809]
        """
        self._check_distribution("pxv")
        x = _checked(x, "x", low=0.0)
        v = _checked(v, "v")
        x, v = _broadcast(x, v, ("x", "v"))
        result = np.array(self._joint(x, v), dtype=float)
        result[(x == 0.0) & (v == 0.0)] = np.inf
        return _out(result)

    def weight(self, F):
        """The weight function w(F) of eq. (weightfunc) (eq. (weightfunc2) for the exact
        solutions): P(x, v) is a superposition of the modes of eq. (fpsol) with weight w(F).

        Parameters
        ----------
        F : array_like
            F > 0.

        Returns
        -------
        numpy.ndarray or numpy.float64
            w(F), the shape of ``F``.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").weight([0.1, 1.0]).round(6))
        [0.229053 0.153341]
        """
        self._check_distribution("weight")
        force = _checked(F, "F", low=0.0, strictly=True)
        return _out(np.asarray(self._weight(force), dtype=float))

    def _flight_times(self, T, name: str, per_collision: bool = False) -> np.ndarray:
        """``T`` checked: >= 0, and each T > 0 at least the T below which nu(T) (rho(T) =
        nu / I with ``per_collision``) exceeds the largest double (``shortest_flight_time``);
        ValueError naming ``name``, r and the bound otherwise."""
        from . import flight_time

        times = _checked(T, name, low=0.0)
        amplitude = self._short_flight_amplitude()
        if per_collision and np.isfinite(self.collision_rate):
            amplitude /= self.collision_rate
        shortest = flight_time.shortest_flight_time(amplitude, self.beta)
        bad = (times > 0.0) & (times < shortest)
        if bad.any():
            raise ValueError(
                f"{name} must be 0 or >= {shortest:.3g} at r = {self.label}: below, "
                f"{'rho' if per_collision else 'nu'}(T) ~ T^(-beta/2) (eq. (short)) exceeds "
                f"the largest double; got {times[bad].flat[0]:g}"
            )
        return times

    def flight_rate_density(self, T):
        """nu(T), flights of duration in dT per unit time, eq. (rate) of ``flight_time``:
        int du u P(0, u) f(T | u); finite for T > 0 at every r (also below r_c).

        Each T on its own (``flight_time.flight_rate_in_regimes``): below
        ``flight_time.SHORT_FLIGHT_TIME`` (1e-30) its short-flight law A C_beta T^(-beta/2),
        eq. (short) (relative correction O(T^(1/2)) < 1e-14); beyond
        ``flight_time.underflow_flight_time(r)`` (7556 for r <= 0.618, longer above), and
        wherever nu is below the smallest normal double, exactly 0; between, the quadrature
        of eq. (rate).

        Parameters
        ----------
        T : array_like
            Flight times, T = 0 or T >= the T below which nu(T) exceeds the largest double
            (``flight_time.shortest_flight_time``: 0, i.e. every T > 0, unless beta > 1.9,
            i.e. r < 0.2; 2.4e-258 at r = 0.02).

        Returns
        -------
        numpy.ndarray or numpy.float64
            nu(T), the shape of ``T``, finite; inf at T = 0, where nu ~ T^(-beta/2)
            (eq. (short)).

        Raises
        ------
        ValueError
            If a T is negative, NaN, infinite, or below the bound.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").flight_rate_density([1.0, 4.0]).round(6))
        [0.065611 0.020642]
        """
        times = self._flight_times(T, "T")
        result = np.full(times.shape, np.inf)
        positive = times > 0.0
        if positive.any():
            result[positive] = self._flight_rate(times[positive])
        return _out(result)

    def flight_time_density(self, T):
        """rho(T) = nu(T) / I, the density of the time between two collisions (per collision);
        0 for T > 0 below r_c, where I is infinite.  nu(T) as ``flight_rate_density`` gives it
        (eq. (short) below 1e-30, 0 beyond the underflow).

        Parameters
        ----------
        T : array_like
            Flight times, T = 0 or T >= the T below which rho(T) exceeds the largest double
            (``flight_time.shortest_flight_time`` of A C_beta / I: 0, i.e. every T > 0, for
            every r above r_c but within 1e-3 of it).

        Returns
        -------
        numpy.ndarray or numpy.float64
            rho(T), the shape of ``T``, finite; inf at T = 0 (eq. (short)).

        Raises
        ------
        ValueError
            If a T is negative, NaN, infinite, or below the bound.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").flight_time_density([1.0, 4.0]).round(6))
        [0.196832 0.061925]
        """
        times = self._flight_times(T, "T", per_collision=True)
        if not np.isfinite(self.collision_rate):
            return _out(np.where(times == 0.0, np.inf, 0.0))
        nu = np.full(times.shape, np.inf)
        positive = times > 0.0
        if positive.any():
            nu[positive] = self._flight_rate(times[positive])
        return _out(nu / self.collision_rate)

    def return_speed_density(self, v, u):
        """v G_g(v, u) of eq. (kernel3): the density of the speed v at the next collision of a
        ball that leaves the floor with speed u (the same at every r).

        Parameters
        ----------
        v : array_like
            Return speeds, v >= 0.
        u : array_like
            Outgoing speeds, u > 0, broadcast against ``v``.

        Returns
        -------
        numpy.ndarray or numpy.float64
            v G_g(v, u), the broadcast shape; it integrates to 1 over v (eq. (normG)).

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").return_speed_density([0.5, 1.0], 1.0).round(6))
        [0.232269 0.429368]
        """
        from .kernel import return_speed_kernel

        v = _checked(v, "v", low=0.0)
        u = _checked(u, "u", low=0.0, strictly=True)
        v, u = _broadcast(v, u, ("v", "u"))
        return _out(v * return_speed_kernel(v, u))

    def observables(self) -> dict:
        """The scalars: r, beta, m, q, collision_rate, mean_x, delta_x, mean_flight_time,
        flight_time_second_moment and accuracy, as a dict.

        Returns
        -------
        dict

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> sorted(ExactEquilibrium("1/2").observables())[:3]
        ['accuracy', 'beta', 'collision_rate']
        """
        names = ("r", "beta", "m", "q", "collision_rate", "mean_x", "delta_x")
        more = ("mean_flight_time", "flight_time_second_moment", "accuracy")
        return {name: float(getattr(self, name)) for name in names + more}

    def __repr__(self):
        return (
            f"{type(self).__name__}(r={self.restitution}): I = {self.collision_rate:.10g}, "
            f"<x> = {self.mean_x:.10g}, Delta x = {self.delta_x:.10g}, "
            f"<T> = {self.mean_flight_time:.10g}, <T^2> = {self.flight_time_second_moment:.10g}; "
            f"beta = {self.beta:.6g}, m = {self.m:.6g}, q = {self.q:.6g}"
        )


# ---------------------------------------------------------------------------------------------
# any r: the solver


@functools.lru_cache(maxsize=8)
def _solution(exact: Fraction, step: float):
    """P(0, v) of eq. (inteq) at r = ``exact``, trapezoidal step ``step``: solved once per process
    and (r, step).  Where the whole distribution is computed (``DISTRIBUTION_RESTITUTION_RANGE``)
    its nodes reach where P(0, v) falls to e^-690, as w(F) at small F needs
    (``distribution.outgoing_speed_solution``); above, up to the solver's own highest node
    (``solver.solve_outgoing_speed_density``), which holds P(0, v) and the time averages."""
    from . import distribution, solver

    if in_range(exact, DISTRIBUTION_RESTITUTION_RANGE):
        return distribution.outgoing_speed_solution(exact, step=step)
    return solver.solve_outgoing_speed_density(exact, step=step)


@functools.lru_cache(maxsize=8)
def _accuracy(exact: Fraction, step: float) -> float:
    """``solver.accuracy_estimate`` of ``_solution(exact, step)`` (a second, finer solve)."""
    from . import solver

    return solver.accuracy_estimate(_solution(exact, step))


@functools.lru_cache(maxsize=8)
def _weight_function(exact: Fraction, step: float, panel_nodes: int):
    """The interpolated w(F) of ``_solution(exact, step)``: built once per process."""
    from . import distribution

    return distribution.interpolated_weight_function(
        _solution(exact, step), panel_nodes=panel_nodes
    )


def _solver_restitution(r) -> Fraction:
    """r parsed and within the solver's range; the range is named whatever is wrong with r."""
    low, high = SOLVER_RESTITUTION_RANGE
    try:
        exact = parse_restitution(r, "r")
    except ValueError as error:
        raise ValueError(f"{error}; the solver answers {low} <= r <= {high}") from None
    if not in_range(exact, SOLVER_RESTITUTION_RANGE):
        raise ValueError(
            f"r: r = {r!r} is outside the solver's range {low} <= r <= {high}, where P(0, v) of "
            "eq. (inteq) meets its 1e-8 accuracy target (restitution.SOLVER_RESTITUTION_RANGE)"
        )
    return exact


class Equilibrium(_EquilibriumState):
    """The equilibrium state of the bouncing ball at one coefficient of restitution r,
    from the numerical solution of eq. (inteq).

    Parameters
    ----------
    r : float or str
        The coefficient of restitution, eq. (restitution): a decimal (read as written: 0.3 is
        3/10) or an exact fraction string such as ``"1/3"``, within the solver's range
        (``restitution.SOLVER_RESTITUTION_RANGE``).  The position-dependent quantities (P(x),
        <v^2>_x, P(x, v), w(F)) are computed in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``;
        above it they raise ValueError, and P(0, v), the time averages, the flight times and the
        exponents remain.
    exact : bool, optional
        If True, return the paper's exact solution, ``ExactEquilibrium(r)`` (r = 1/2 or 1/3).
    quadrature_step : float, optional
        The trapezoidal step of the solver in s = ln v + v^(1/2) (``solver.DEFAULT_STEP``; the
        config's ``solver.quadrature_step``), 0 < step <= ``solver.LARGEST_STEP``.
    weight_panel_nodes : int, optional
        Chebyshev nodes per panel of the interpolated w(F) (``distribution.PANEL_CHEBYSHEV_NODES``;
        the config's ``solver.weight_panel_nodes``).

    Attributes
    ----------
    r : float
    restitution : fractions.Fraction
        r exactly, as parsed.
    label : str
        The label the workflow files r's outputs under.
    collision_rate : float
        I = M_1, eq. (collrate); inf below r_c.
    mean_x, delta_x : float
        <x> and Delta x, eq. (xandDeltax), from the Ito identities of ``solver``.
    mean_flight_time, flight_time_second_moment : float
        <T> and <T^2> per collision (0 below r_c), ``flight_time``.
    beta, m, q : float
        The exponents of P(0, v) ~ v^-beta (v -> 0, eq. (asym2)) and v^-m e^(-q v)
        (v -> inf, eqs. (asym4)-(asym6)).
    accuracy : float
        The solver's error estimate: the largest relative change of P(0, v) over
        1e-3 <= v <= 20 against a finer solve (computed on first use: a second solve).
    position_accuracy : float
        The largest of ``|int P dx - 1|`` and the relative differences of <x>, Delta x from P(x)
        (eq. (P(x)1)) and from the Ito identities (builds w(F) on first use).
    distribution_available : bool
        Whether r lies in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``, where P(x), <v^2>_x,
        P(x, v) and w(F) are computed.
    solution : solver.OutgoingSpeedSolution
        P(0, v) at the solver's nodes: the one solve everything here is computed from (the
        workflow's solve rule writes the same numbers).
    quadrature_step : float
    weight_panel_nodes : int

    Examples
    --------
    >>> from bouncing_ball import Equilibrium
    >>> eq = Equilibrium("1/2")
    >>> print(f"I = {eq.collision_rate:.8f}, <x> = {eq.mean_x:.8f}, beta = {eq.beta:.6f}")
    I = 0.33333333, <x> = 6.00000000, beta = 1.000000
    >>> print(eq.p0v([0.5, 1.0, 2.0]).round(6))
    [0.404354 0.122626 0.022556]
    >>> eq.accuracy < 1e-8
    True
    >>> print(eq.px([0.1, 1.0]).round(6))  # builds w(F): a few seconds
    [0.503776 0.183784]
    >>> Equilibrium("1/2", exact=True)
    ExactEquilibrium(r=1/2): I = 0.3333333333, ...
    """

    def __new__(cls, r, *, exact=False, **settings):
        if exact:
            if settings:
                raise TypeError(
                    f"exact=True takes no solver settings, got {', '.join(sorted(settings))}"
                )
            return ExactEquilibrium(r)
        return super().__new__(cls)

    def __init__(
        self, r, *, exact=False, quadrature_step=None, weight_panel_nodes=None
    ):  # exact=True is handled by __new__
        from . import distribution, flight_time, solver

        self._set_restitution(_solver_restitution(r))
        step = solver.DEFAULT_STEP if quadrature_step is None else quadrature_step
        nodes = (
            distribution.PANEL_CHEBYSHEV_NODES if weight_panel_nodes is None else weight_panel_nodes
        )
        if (
            isinstance(step, bool)
            or not isinstance(step, (int, float))
            or not 0.0 < step <= solver.LARGEST_STEP
        ):
            raise ValueError(
                f"quadrature_step must be a number in (0, {solver.LARGEST_STEP}], got {step!r}"
            )
        if isinstance(nodes, bool) or not isinstance(nodes, int) or nodes < 2:
            raise ValueError(f"weight_panel_nodes must be a whole number >= 2, got {nodes!r}")
        self.quadrature_step = float(step)
        self.weight_panel_nodes = nodes
        self.distribution_available = in_range(self.restitution, DISTRIBUTION_RESTITUTION_RANGE)
        self.solution = _solution(self.restitution, self.quadrature_step)
        averages = solver.time_averages(self.solution)
        self.collision_rate = float(averages["collision_rate"])
        self.mean_x = float(averages["mean_x"])
        self.delta_x = float(averages["delta_x"])
        self.mean_flight_time = float(flight_time.mean_flight_time(self.solution))
        self.flight_time_second_moment = float(flight_time.flight_time_second_moment(self.solution))

    def _check_distribution(self, what: str) -> None:
        if not self.distribution_available:
            try:
                check_solver_restitution(self.r, "r")
            except ValueError as error:
                raise ValueError(
                    f"{error}: Equilibrium.{what} needs w(F) of eq. (weightfunc), computed "
                    f"only there; at r = {self.label} Equilibrium gives P(0, v), the time "
                    "averages, the flight times and the exponents"
                ) from None

    # --- lazily built
    @property
    def accuracy(self) -> float:
        """The solver's error estimate (``solver.accuracy_estimate``): the largest relative
        change of P(0, v) over 1e-3 <= v <= 20 against a finer solve (computed on first use)."""
        return _accuracy(self.restitution, self.quadrature_step)

    @property
    def weight_function(self):
        """w(F) of eq. (weightfunc), interpolated from ``solution``
        (``distribution.WeightFunction``); built on first use (about a second), then kept for
        the process."""
        self._check_distribution("weight_function")
        return _weight_function(self.restitution, self.quadrature_step, self.weight_panel_nodes)

    @functools.cached_property
    def _position_averages(self) -> dict:
        """int P dx, <x> and Delta x from P(x) of eq. (P(x)1) (``distribution.position_averages``)."""
        from . import distribution

        self._check_distribution("position_accuracy")
        return distribution.position_averages(self.weight_function)

    @property
    def position_accuracy(self) -> float:
        """``max(|int P dx - 1|, |<x>_P / <x> - 1|, |Delta x_P / Delta x - 1|)``: P(x) of
        eq. (P(x)1) against the normalisation and the solver's Ito identities (builds w(F))."""
        averages = self._position_averages
        return float(
            max(
                abs(averages["normalization"] - 1.0),
                abs(averages["mean_x"] / self.mean_x - 1.0),
                abs(averages["delta_x"] / self.delta_x - 1.0),
            )
        )

    # --- the quantities
    def _outgoing(self, v):
        return self.solution.outgoing_speed_density(v)

    def _floor_density(self):
        return (1.0 + self.r) * self.solution.moment(0) if self.beta < 1.0 else np.inf

    def _position(self, x):
        from . import distribution

        return distribution.position_density(x, self.weight_function)

    def _speed_squared(self, x):
        from . import distribution

        return distribution.mean_speed_squared_given_position(x, self.weight_function)

    def _joint(self, x, v):
        from . import distribution

        return distribution.distribution(x, v, self.weight_function, self.solution)

    def _weight(self, force):
        return self.weight_function(force)

    def _flight_rate(self, times):
        from . import flight_time

        return flight_time.flight_rate_density(self.solution, times)

    def _short_flight_amplitude(self) -> float:
        from . import flight_time

        amplitude = flight_time.small_speed_amplitude(self.solution)
        return amplitude * flight_time.short_time_constant(self.beta)

    # --- the workflow's tables (results/solver/r{r}/)
    @functools.cached_property
    def _summary(self) -> dict:
        from . import distribution, flight_time, solver

        self._check_distribution("summary")
        row = solver.solution_summary(self.solution, with_accuracy_estimate=False)
        row["accuracy_estimate"] = self.accuracy
        collisions = flight_time.flight_time_summary(self.solution)
        row.update({key: value for key, value in collisions.items() if key not in row})
        weight = self.weight_function
        averages = self._position_averages
        row["position_normalization"] = averages["normalization"]
        row["mean_x_from_position"] = averages["mean_x"]
        row["delta_x_from_position"] = averages["delta_x"]
        row["weight_interpolation_error"] = weight.interpolation_error
        measured = distribution.measured_exponents(weight)
        for key, value in distribution.predicted_exponents(self.restitution).items():
            row[f"{key}_measured"], row[f"{key}_predicted"] = measured[key], value
        row["large_x_window_lo"], row["large_x_window_hi"] = measured["large_x_window"]
        return row

    def summary(self) -> dict:
        """The solve rule's summary row: ``solver.solution_summary`` (with the accuracy
        estimate), the collision statistics (``flight_time.flight_time_summary``), <x>, Delta x
        and the normalisation from P(x) (eqs. (P(x)1), (xandDeltax)), the interpolation error
        of w(F) (``WeightFunction.interpolation_error``), and the measured and predicted
        exponents of P(x) with the large-x fit window (``distribution.measured_exponents``).

        Returns
        -------
        dict
            One row of ``results/solver/r{r}/summary.parquet`` (a copy: computed once).

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> row = Equilibrium("1/2").summary()
        >>> print(f"{row['mean_x']:.8f} {row['mean_x_from_position']:.8f}")
        6.00000000 6.00000000
        """
        return dict(self._summary)

    def check(self, tables) -> None:
        """The solve rule's checks of its tables and of ``summary()``: no infinity in any table
        (``_infinity_defects``), no NaN where a value is defined, int P dx = 1 and the moments from P(x) equal the Ito moments within the
        accuracy estimate, the measured exponents within their tolerance of the predicted ones
        (``distribution.check_solve_tables``, held to ``solver.ACCURACY_TARGET``).

        Parameters
        ----------
        tables : dict of str to pandas.DataFrame
            Any of p0v, flight_time, return_speed, position, distribution, weight, as the table
            methods give them.

        Raises
        ------
        ValueError
            Naming r and every check that fails (the infinities first, naming the table and
            column).

        Examples
        --------
        >>> import numpy as np
        >>> from bouncing_ball import Equilibrium
        >>> eq = Equilibrium("1/2")
        >>> eq.check({"position": eq.position_table([0.1, 1.0])})
        >>> table = eq.flight_time_table([1.0, 2.0])
        >>> table.loc[1, "rate_density"] = np.inf
        >>> eq.check({"flight_time": table})
        Traceback (most recent call last):
        ...
        ValueError: r = 0.5: the solver's tables hold infinities: flight_time: 1 of 2 rate_density are infinite
        """
        from . import distribution, solver

        infinite = _infinity_defects(tables)
        if infinite:
            raise ValueError(
                f"r = {self.label}: the solver's tables hold infinities: " + "; ".join(infinite)
            )
        distribution.check_solve_tables(self.label, self.summary(), tables, solver.ACCURACY_TARGET)

    def p0v_table(self, speeds):
        """P(0, v) of eq. (inteq) as a table (``results/solver/r{r}/p0v``).

        Parameters
        ----------
        speeds : array_like
            Outgoing speeds, v > 0.

        Returns
        -------
        pandas.DataFrame
            Columns v, p0v.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> Equilibrium("1/2").p0v_table([1.0, 2.0]).round(6)
             v       p0v
        0  1.0  0.122626
        1  2.0  0.022556
        """
        import pandas as pd

        speeds = _checked(speeds, "speeds", low=0.0, strictly=True)
        return pd.DataFrame({"v": speeds, "p0v": self.solution.outgoing_speed_density(speeds)})

    def position_table(self, positions):
        """P(x) and <v^2>_x, eqs. (P(x)1), (moment2), as a table
        (``results/solver/r{r}/position``).

        Parameters
        ----------
        positions : array_like
            Heights, x > 0.

        Returns
        -------
        pandas.DataFrame
            Columns x, px, v2_given_x.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> Equilibrium("1/2").position_table([0.1, 1.0]).round(6)
             x        px  v2_given_x
        0  0.1  0.503776    1.853157
        1  1.0  0.183784    3.710784
        """
        from . import distribution

        self._check_distribution("position_table")
        positions = _checked(positions, "positions", low=0.0, strictly=True)
        return distribution.position_table(self.weight_function, positions)

    def distribution_table(self, positions, speeds):
        """P(x, v), eq. (fpsol), on the grid of ``positions`` and ``speeds``, with the largest
        relative error quad estimates for it (``results/solver/r{r}/distribution``).

        Parameters
        ----------
        positions : array_like
            Heights, x >= 0.
        speeds : array_like
            Velocities (either sign).

        Returns
        -------
        table : pandas.DataFrame
            Columns x, v, pxv, one row per (x, v), v fastest (NaN at x = v = 0).
        worst : float
            The largest relative error estimate of the F integrals.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> table, worst = Equilibrium("1/2").distribution_table([0.1], [-1.0, 1.0])
        >>> print(table["pxv"].to_numpy().round(6), worst < 1e-8)
        [0.074292 0.146809] True
        """
        from . import distribution

        self._check_distribution("distribution_table")
        positions = _checked(positions, "positions", low=0.0)
        speeds = _checked(speeds, "speeds")
        return distribution.distribution_table(
            self.weight_function, self.solution, positions, speeds
        )

    def weight_table(self, forces):
        """w(F) of eq. (weightfunc) as a table (``results/solver/r{r}/weight``).

        Parameters
        ----------
        forces : array_like
            F > 0.

        Returns
        -------
        pandas.DataFrame
            Columns F, w, log_w (log_w stays finite where w over- or underflows).

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> Equilibrium("1/2").weight_table([1.0]).round(6)
             F         w     log_w
        0  1.0  0.153341 -1.875093
        """
        from . import distribution

        self._check_distribution("weight_table")
        forces = _checked(forces, "forces", low=0.0, strictly=True)
        return distribution.weight_table(self.weight_function, forces)

    def flight_time_table(self, times):
        """The flight-time densities of eq. (rate) and their short- and long-time forms,
        eqs. (short), (long1), (long2) (``flight_time.flight_time_table``;
        ``results/solver/r{r}/flight_time``).

        Parameters
        ----------
        times : array_like
            Flight times, T > 0 and at least the bounds of ``flight_rate_density`` and
            ``flight_time_density`` (every value of the table is finite).  The pipeline writes
            ``flight_time.FLIGHT_TIME_TABLE_RANGE`` (config ``solver.flight_times``).

        Returns
        -------
        pandas.DataFrame
            Columns t, density, rate_density, time_weighted_density, short_time_form,
            long_time_form.

        Raises
        ------
        ValueError
            If a T is not positive, or below a bound.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> Equilibrium("1/2").flight_time_table([1.0])["density"].round(6).tolist()
        [0.196832]
        """
        from . import flight_time

        times = _checked(times, "times", low=0.0, strictly=True)
        for per_collision in (False, True):  # nu(T) and rho(T) finite
            self._flight_times(times, "times", per_collision=per_collision)
        return flight_time.flight_time_table(self.solution, times)

    def return_speed_table(self, speed_bins):
        """The return-speed law v G_g(v, u) of eq. (kernel3) averaged over a simulation's speed
        bins, with u weighted by the collision rate u P(0, u) in its bin
        (``flight_time.return_speed_table``; ``results/solver/r{r}/return_speed``).

        Parameters
        ----------
        speed_bins : bins.LogBins
            The bins of the outgoing and return speeds (``settings.ShardSettings.speed_bins``).

        Returns
        -------
        pandas.DataFrame
            Columns u_lo, u_hi, v_lo, v_hi, probability.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> from bouncing_ball.bins import LogBins
        >>> table = Equilibrium("1/2").return_speed_table(LogBins(0.1, 10.0, 1))
        >>> table.groupby("u_lo")["probability"].sum().round(12).tolist()
        [1.0, 1.0]
        """
        from . import flight_time

        return flight_time.return_speed_table(self.solution, speed_bins)


# ---------------------------------------------------------------------------------------------
# r = 1/2 and 1/3: the paper's exact solutions


def _exact_restitution(r) -> Fraction:
    exact = parse_restitution(r, "r")
    if exact not in EXACT_RESTITUTIONS:
        raise ValueError(
            f"r: exact solutions exist only for r = 1/2 and r = 1/3 (eq. (P(0,v))), not "
            f'r = {r!r}; give "1/2" or "1/3" (a float such as 1/3 is not exactly 1/3), or '
            f"use Equilibrium({r!r}) for the numerical solution"
        )
    return exact


class ExactEquilibrium(_EquilibriumState):
    """The paper's exact equilibrium at r = 1/2 or r = 1/3: eqs. (P(0,v)), (constants),
    (P(x)2), (weightfunc2), (fpsol), with the interface of ``Equilibrium``.

    The time averages come from these distributions (``exact.position_moments``), the flight
    times from eq. (rate) of ``flight_time`` integrated against the exact P(0, u) by adaptive
    quadrature (independent of the solver's rule).

    Parameters
    ----------
    r : str or fractions.Fraction
        ``"1/2"`` or ``"1/3"`` (or 0.5).

    Attributes
    ----------
    The same as ``Equilibrium``'s (``accuracy`` is 0: closed forms and quadratures to ~1e-11).

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> eq = ExactEquilibrium("1/3")
    >>> print(f"I = {eq.collision_rate:.10f}, beta = {eq.beta:.6f}, q = {eq.q:.6f}")
    I = 0.7500000000, beta = 1.500000, q = 1.500000
    >>> print(eq.px([0.1, 1.0]).round(6))
    [0.815666 0.199051]
    """

    distribution_available = True

    def __init__(self, r):
        self._set_restitution(_exact_restitution(r))
        self.accuracy = 0.0
        self.position_accuracy = 0.0

    # the time averages: computed on first use (a second at r = 1/3, nested quadratures)
    @functools.cached_property
    def _moments(self) -> dict:
        from . import exact

        return exact.position_moments(self.restitution)

    @property
    def collision_rate(self) -> float:
        return float(self._moments["collision_rate"])

    @property
    def mean_x(self) -> float:
        return float(self._moments["mean_x"])

    @property
    def delta_x(self) -> float:
        return float(self._moments["delta_x"])

    @functools.cached_property
    def mean_flight_time(self) -> float:
        return self._flight_moment(1) / self.collision_rate

    @functools.cached_property
    def flight_time_second_moment(self) -> float:
        return self._flight_moment(2) / self.collision_rate

    def _flight_moment(self, k: int) -> float:
        """int du u P(0, u) E[T^k | u], eqs. (meanT), (meanT2), by adaptive quadrature."""
        from . import exact, flight_time

        given_speed = {
            1: flight_time.mean_flight_time_given_speed,
            2: flight_time.flight_time_second_moment_given_speed,
        }[k]

        def integrand(u):
            return u * float(exact.outgoing_speed_density(u, self.restitution) * given_speed(u))

        value, _ = integrate.quad(integrand, 0.0, np.inf, epsabs=0.0, epsrel=1e-13, limit=200)
        return value

    def _outgoing(self, v):
        from . import exact

        return exact.outgoing_speed_density(v, self.restitution)

    def _floor_density(self):
        return np.inf  # beta >= 1 at r = 1/2 and 1/3

    def _position(self, x):
        from . import exact

        return exact.position_density(x, self.restitution)

    def _speed_squared(self, x):
        from . import exact

        return exact.mean_speed_squared_given_position(x, self.restitution)

    def _joint(self, x, v):
        from . import exact

        return exact.distribution(x, v, self.restitution)

    def _weight(self, force):
        from . import exact

        return exact.weight_function(force, self.restitution)

    def _short_flight_amplitude(self) -> float:
        from . import exact, flight_time

        amplitude = exact.normalization_constant(self.restitution)  # P(0, v) ~ A v^-beta
        return amplitude * flight_time.short_time_constant(self.beta)

    def _flight_rate(self, times):
        """nu(T) in the regimes of ``flight_time.flight_rate_in_regimes``, with the exact A of
        eq. (constants) in eq. (short) and ``_direct_flight_rate`` between."""
        from . import flight_time

        return flight_time.flight_rate_in_regimes(
            times, self._direct_flight_rate, self._short_flight_amplitude(), self.beta, self.r
        )

    def _direct_flight_rate(self, times):
        """nu(T) = int du u P(0, u) f(T | u), eq. (rate): adaptive quadrature in ln u from
        1e-7 T^(1/2) (below, the integrand is u^(5/2 - beta) and is summed in closed form) to
        where P(0, u) and f(T | u) have both fallen by e^-60, for each T on its own."""
        from . import exact, flight_time

        def integrand(log_u, t):
            u = np.exp(np.atleast_1d(log_u))
            rate = u * u * exact.outgoing_speed_density(u, self.restitution)
            return float((rate * flight_time.flight_time_density(t, u))[0])

        values = []
        for t in np.asarray(times, dtype=float).ravel():
            lo = math.log(1e-7 * math.sqrt(t))
            hi = math.log(0.5 * t + 12.0 * math.sqrt(t) + 60.0 / self.q)
            peak = math.log(max(math.sqrt(t), 0.5 * t))
            value, _ = integrate.quad(
                integrand, lo, hi, args=(t,), points=[peak], epsabs=0.0, epsrel=1e-12, limit=400
            )
            values.append(value + integrand(lo, t) / (2.5 - self.beta))
        return np.asarray(values).reshape(np.shape(times))
