"""``EquilibriumBase``: what ``Equilibrium`` and ``ExactEquilibrium`` share, every public
method and property, in the units the object was built in."""

import abc
import contextlib
import functools
from fractions import Fraction

import numpy as np

from ..restitution import (
    restitution_label,
)
from ..units import PhysicalUnits
from .checks import _PAPER_UNITS, _broadcast, _checked, _heights, _in_units, _out

__all__ = [
    "EquilibriumBase",
]

# ---------------------------------------------------------------------------------------------
# what both classes share


class EquilibriumBase(abc.ABC):
    """The equilibrium state of the bouncing ball at one r: what ``Equilibrium`` and
    ``ExactEquilibrium`` both answer, with the same methods and signatures.

    An abstract class: ``Equilibrium(r)`` computes it from the solver of eq. (inteq) at any r of
    ``restitution.SOLVER_RESTITUTION_RANGE``; ``ExactEquilibrium(r)`` from the paper's exact
    solutions at r = 1/2 and 1/3.  Code written against this class takes either, so the exact
    solutions stand in for the solver (and check it) wherever they exist.

    Every method takes arrays and broadcasts like numpy (a scalar in, a numpy scalar out), and
    refuses input that has no answer with a ValueError naming the argument.

    Every argument and result is in the object's ``units`` (``units.PhysicalUnits``, of the
    gravity g and noise strength Lambda of eq. (eqmo); the paper's g = Lambda = 1 by default):
    heights and speeds, times, densities, moments and rates each times its unit L^a T^b
    (``units.DIMENSIONS``).  r, beta, m, the bounce counts and eigenvalues and the relative
    accuracies have no dimension; q is per speed.  ``solution`` and ``weight_function``, the
    solver's own objects, are in the paper's units whatever ``units``.

    Attributes
    ----------
    units : units.PhysicalUnits
        g and Lambda, and the units L, T, V they make.
    restitution : fractions.Fraction
        r exactly, as parsed (the key of the solve and of the exact formulas).
    r : float
        ``float(restitution)``, for arithmetic.
    beta, m, q : float
        The exponents of P(0, v) ~ v^-beta (v -> 0, eq. (asym2)) and v^-m e^(-q v) (v -> inf,
        eqs. (asym4)-(asym6)).
    collision_rate, mean_x, delta_x : float
        I = M_1 (eq. (collrate); inf below r_c), <x> and Delta x (eq. (xandDeltax)).
    mean_flight_time, flight_time_second_moment : float
        <T> and <T^2> per collision (0 below r_c), eqs. (meanT), (meanT2).
    accuracy : float
        A bound on the relative error of P(0, v) and the time averages.
    position_accuracy : float
        A bound on the relative error of P(x) and its moments.
    distribution_available : bool
        Whether P(x), <v^2>_x, P(x, v) and w(F) are computed at this r.
    smallest_speed, smallest_force : float
        The lower bounds of ``p0v`` and ``weight``.
    relaxation_eigenvalue, correlation_bounces, bounce_chain_time, relaxation_accuracy : float
        The relaxation of the bounce-speed chain (``relaxation``).
    relaxation_rate, relaxation_time, relaxation_rate_accuracy : float
        The slowest relaxation of the process in time (``time_relaxation``).

    Examples
    --------
    >>> import bouncing_ball as bb
    >>> isinstance(bb.ExactEquilibrium("1/2"), bb.EquilibriumBase)
    True
    >>> sorted(name for name in bb.EquilibriumBase.__abstractmethods__ if name[0] != "_")
    ['accuracy', 'distribution_available', 'position_accuracy', 'solution', 'weight_function']

    In physical units, a ball under g = 9.81 m/s^2 and a noise of Lambda = 0.05 m^2/s^3:

    >>> eq = bb.ExactEquilibrium("1/2", gravity=9.81, noise=0.05)
    >>> print(f"<x> = {eq.mean_x:.4e} m = 6 L, I = {eq.collision_rate:.2f} per s = 1 / (3 T)")
    <x> = 1.5889e-05 m = 6 L, I = 641.57 per s = 1 / (3 T)
    """

    _units = _PAPER_UNITS  # each object sets its own

    def _set_units(self, gravity, noise) -> None:
        self._units = PhysicalUnits(gravity, noise)

    @property
    def units(self) -> PhysicalUnits:
        """The units of every argument and result (``units.PhysicalUnits``): gravity g and
        noise strength Lambda of eq. (eqmo), and the length L = Lambda^2 / g^3, time
        T = Lambda / g^2 and speed V = Lambda / g they make (1 each in the paper's units)."""
        return self._units

    def _physical(self, value, dimension: str):
        """A paper-unit ``value`` in ``units`` (``value`` itself in the paper's units)."""
        return self._units.to_physical(value, dimension)

    def _paper(self, value, dimension: str):
        """A ``value`` in ``units`` in the paper's units (itself in the paper's units)."""
        return self._units.to_paper(value, dimension)

    def _paper_twin(self):
        """This object in the paper's units: a shallow copy sharing the solve and everything
        computed from it (all kept in the paper's units)."""
        import copy

        twin = copy.copy(self)
        twin._units = _PAPER_UNITS
        return twin

    def _set_restitution(self, exact: Fraction) -> None:
        from ..asymptotics import large_speed_decay_rate, large_speed_exponent, small_speed_exponent

        self._restitution = exact
        self._label = restitution_label(exact)
        r = float(exact)
        self._exponents = (
            float(small_speed_exponent(r)),
            float(large_speed_exponent(r)),
            float(large_speed_decay_rate(r)),
        )

    @property
    def restitution(self) -> Fraction:
        """r exactly, as parsed: the key of the solve and of the exact formulas."""
        return self._restitution

    @property
    def r(self) -> float:
        """r as a float, ``float(restitution)``, for arithmetic."""
        return float(self._restitution)

    @property
    def beta(self) -> float:
        """beta of P(0, v) ~ A v^-beta as v -> 0, eq. (asym2)."""
        return self._exponents[0]

    @property
    def m(self) -> float:
        """m of P(0, v) ~ v^-m e^(-q v) as v -> inf, eqs. (asym4)-(asym6)."""
        return self._exponents[1]

    @property
    def q(self) -> float:
        """q of P(0, v) ~ v^-m e^(-q v) as v -> inf, eqs. (asym4), (asym6): per speed."""
        return self._physical(self._exponents[2], "per_speed")

    @property
    def collision_rate(self) -> float:
        """I = M_1 = int v P(0, v) dv, eq. (collrate): collisions per unit time (inf below
        r_c)."""
        return self._physical(self._paper_scalar("collision_rate"), "rate")

    @property
    def mean_x(self) -> float:
        """<x>, the time average of the height, eq. (xandDeltax)."""
        return self._physical(self._paper_scalar("mean_x"), "length")

    @property
    def delta_x(self) -> float:
        """Delta x = (<x^2> - <x>^2)^(1/2), eq. (xandDeltax)."""
        return self._physical(self._paper_scalar("delta_x"), "length")

    @property
    def mean_flight_time(self) -> float:
        """<T>, the mean time between two collisions, eq. (meanT) (0 below r_c)."""
        return self._physical(self._paper_scalar("mean_flight_time"), "time")

    @property
    def flight_time_second_moment(self) -> float:
        """<T^2> per collision, eq. (meanT2) (0 below r_c)."""
        return self._physical(self._paper_scalar("flight_time_second_moment"), "time_squared")

    # --- what each class supplies, in the paper's units
    @abc.abstractmethod
    def _paper_scalar(self, name: str) -> float:
        """collision_rate, mean_x, delta_x, mean_flight_time or flight_time_second_moment in
        the paper's units."""

    @property
    @abc.abstractmethod
    def accuracy(self) -> float:
        """A bound on the relative error of P(0, v), the time averages and the flight times."""

    @property
    @abc.abstractmethod
    def position_accuracy(self) -> float:
        """A bound on the relative error of P(x) of eq. (P(x)1) and its moments."""

    @property
    @abc.abstractmethod
    def distribution_available(self) -> bool:
        """Whether P(x), <v^2>_x, P(x, v) and w(F) are computed at this r."""

    @property
    @abc.abstractmethod
    def solution(self):
        """P(0, v) at the solver's nodes, a ``solver.OutgoingSpeedSolution``, in the paper's
        units whatever ``units``."""

    @property
    @abc.abstractmethod
    def weight_function(self):
        """w(F) of eq. (weightfunc) as an object with ``__call__(F)`` and ``log(F)``, in the
        paper's units whatever ``units`` (``weight`` gives w(F) in ``units``)."""

    @abc.abstractmethod
    def _outgoing(self, v):  # P(0, v), v > 0
        """P(0, v) at v > 0."""

    @abc.abstractmethod
    def _floor_density(self) -> float:  # P(x = 0) = int dv P(0, v), both sides
        """P(x = 0)."""

    @abc.abstractmethod
    def _position(self, x):
        """P(x) at x > 0."""

    @abc.abstractmethod
    def _speed_squared(self, x):
        """<v^2>_x at x > 0."""

    @abc.abstractmethod
    def _joint(self, x, v):
        """P(x, v) at x >= 0 (NaN at x = v = 0)."""

    @abc.abstractmethod
    def _weight(self, force):
        """w(F) at F > 0."""

    @abc.abstractmethod
    def _flight_rate(self, times):
        """nu(T) at T > 0 (``flight_time.flight_rate_in_regimes``)."""

    @abc.abstractmethod
    def _short_flight_amplitude(self) -> float:
        """A C_beta of nu ~ A C_beta T^(-beta/2), eq. (short)."""

    @abc.abstractmethod
    def _outgoing_bin_average(self, lo, hi):
        """int v P(0, v) dv / int v dv over each bin, 0 < lo < hi < inf."""

    @abc.abstractmethod
    def _position_bin_average(self, lo, hi):
        """int P(x) dx / (hi - lo) over each bin, checked bins."""

    @abc.abstractmethod
    def _speed_squared_bin_average(self, lo, hi):
        """int_bin dx int_x^inf P / int_bin P dx over each bin, checked bins."""

    def _check_distribution(self, what: str) -> None:
        """ValueError naming ``what`` where P(x) is not computed (nothing by default)."""
        return None

    # --- the public methods
    @functools.cached_property
    def _paper_smallest_speed(self) -> float:
        """``smallest_speed`` in the paper's units."""
        reference = 1e-30  # where P(0, v) is its power law to rounding
        prefactor = float(self._outgoing(np.array([reference]))[0]) * reference**self.beta
        largest = np.log(np.finfo(float).max) - 10.0
        return float(np.exp((np.log(prefactor) - largest) / self.beta))

    @property
    def smallest_speed(self) -> float:
        """The smallest v > 0 at which P(0, v) is a double: below it A v^-beta (eq. (asym1))
        comes within e^10 of the largest double (``p0v`` refuses such v); 0 where it stays
        below for every v > 0 (small beta, r near 1).  A speed, in ``units``."""
        return self._physical(self._paper_smallest_speed, "speed")

    def p0v(self, v):
        """P(0, v) on the outgoing side of the floor, eq. (P(0,v)) (exact) or eq. (inteq).

        Below the solver's lowest node (1e-12, 1e-20 where beta >= 2) ``Equilibrium`` gives
        the power law A v^-beta of eq. (asym1), its prefactor matched there
        (``solver.OutgoingSpeedSolution.outgoing_speed_density``): relative error of order
        1e-12 besides the solver's own.

        Parameters
        ----------
        v : array_like
            Outgoing speeds: v = 0 or ``smallest_speed`` <= v (about 1e-205 at r = 1/3, 1e-120
            at r = 0.02; below, P(0, v) exceeds the largest double), finite.  (The incoming
            side is ``pxv(0, -v)``, eq. (bc).)

        Returns
        -------
        numpy.ndarray or numpy.float64
            P(0, v), the shape of ``v``, per unit length and speed; inf at v = 0, where
            P(0, v) ~ v^-beta diverges (eq. (asym1)); 0 where it underflows (v beyond
            ~700 / q).

        Raises
        ------
        ValueError
            Naming v and the bound, for v < 0, 0 < v < ``smallest_speed``, NaN or inf.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").p0v([0.5, 1.0, 2.0]).round(6))
        [0.404354 0.122626 0.022556]
        """
        given = _checked(v, "v", low=0.0)
        v = self._paper(given, "speed")
        tiny = (given > 0.0) & (v < self._paper_smallest_speed)
        if tiny.any():
            raise ValueError(
                f"v = {given[tiny].flat[0]:g} is below smallest_speed = "
                f"{self.smallest_speed:.3g} at r = {self._label}, where P(0, v) ~ A v^-beta "
                "(eq. (asym1)) exceeds the largest double; give v = 0 (P = inf) or "
                "v >= smallest_speed"
            )
        result = np.full(v.shape, np.inf)
        positive = given > 0.0
        result[positive] = self._outgoing(v[positive])
        return _out(self._physical(result, "phase_space_density"))

    def px(self, x):
        """P(x), the density of the height x, eq. (P(x)1) (eq. (P(x)2) for the exact solutions).

        Each x is its own F integral (``distribution.position_density``), out to the small-x
        law P(x) ~ x^((1 - beta)/3) (docs/distribution.md) through the power law of w(F) above
        its largest computed F, whose first neglected term (relative F_max^(-2/3), 5e-6 at
        F_max = 1e8) bounds the error there.

        Parameters
        ----------
        x : array_like
            Heights: x = 0 or ``distribution.SMALLEST_POSITION`` (1e-300) <= x <=
            ``distribution.LARGEST_POSITION`` (1e12).

        Returns
        -------
        numpy.ndarray or numpy.float64
            P(x), the shape of ``x``; 0 where it underflows (x beyond ~1e6 at r <= 1/2).  At
            x = 0 it is int P(0, v) dv over both sides, (1 + r) int_0^inf P(0, v) dv by
            eq. (bc): inf where beta >= 1 (r <= 1/2).

        Raises
        ------
        ValueError
            Naming x and the bound, for an x outside the domain, NaN or inf.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").px([0.1, 1.0, 10.0]).round(6))
        [0.503776 0.183784 0.018862]
        """
        self._check_distribution("px")
        x = _heights(x, "x", self._units)
        result = np.full(x.shape, self._floor_density())
        positive = x > 0.0
        if positive.any():
            result[positive] = self._position(x[positive])
        return _out(self._physical(result, "per_length"))

    def v2_given_x(self, x):
        """<v^2>_x, the mean squared velocity at height x, eq. (moment2):
        P(x)^-1 int_x^inf P(x') dx'.

        The ratio is taken in logs, so it is finite where P(x) underflows (it grows like
        (x / (S + 1/12))^(1/2), ``distribution.small_force_decay``).

        Parameters
        ----------
        x : array_like
            Heights: x = 0 or ``distribution.SMALLEST_POSITION`` (1e-300) <= x <=
            ``distribution.LARGEST_POSITION`` (1e12).

        Returns
        -------
        numpy.ndarray or numpy.float64
            <v^2>_x, the shape of ``x``; 1 / P(0) at x = 0 (0 where P(0) = inf).

        Raises
        ------
        ValueError
            Naming x and the bound, for an x outside the domain, NaN or inf.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").v2_given_x([0.1, 1.0]).round(6))
        [1.853157 3.710784]
        """
        self._check_distribution("v2_given_x")
        x = _heights(x, "x", self._units)
        result = np.full(x.shape, 1.0 / self._floor_density())
        positive = x > 0.0
        if positive.any():
            result[positive] = self._speed_squared(x[positive])
        return _out(self._physical(result, "speed_squared"))

    def pxv(self, x, v):
        """P(x, v), the joint density of height and velocity, eq. (fpsol); at x = 0 the
        outgoing side is P(0, v) and the incoming side eq. (bc), P(0, -v) = r^2 P(0, r v).

        At x > 0 each value is good to ``distribution.DISTRIBUTION_NOISE`` (1e-10) of the
        largest P(x, v) at that x (the F integral's Airy factor cancels); at x = 0 it is
        ``p0v``'s.  Next to the floor at large v > 0, where the F integral oscillates too fast
        (x < 1.7e-8 v^3, ``near_wall.near_wall_points``), P(x, v) is the Taylor series in x
        of eq. (fp) from P(0, v) (``near_wall.distribution_near_wall``): good to 1e-11 of
        itself besides P(0, v)'s own error (to ~1e-13 against the exact r = 1/2 and 1/3
        solutions).

        Parameters
        ----------
        x : array_like
            Heights: x = 0 or ``distribution.SMALLEST_POSITION`` (1e-300) <= x <=
            ``distribution.LARGEST_POSITION`` (1e12).
        v : array_like
            Velocities (either sign), finite, broadcast against ``x``: every (x, v) of the
            domain (the F integral where its Airy phase stays below
            ``airy.LARGEST_AIRY_PHASE``, x >= 1.7e-8 v^3 at v > 0, the near-wall series
            below).  Beyond ``distribution.LARGEST_VELOCITY`` (1e6) in |v|, P(x, v) is 0 to
            every double and 0 is returned.

        Returns
        -------
        numpy.ndarray or numpy.float64
            P(x, v), the broadcast shape; inf at x = v = 0, the true value where beta > 0
            (P(0, v) ~ v^-beta diverges as v -> 0, eq. (asym1)); 0 where it underflows.

        Raises
        ------
        ValueError
            Naming x or v and the bound: x outside its domain, NaN or inf in either, or a
            point next to the floor whose near-wall series misses its tolerance
            (``near_wall.NEAR_WALL_TOLERANCE``; not met with the solver's P(0, v)).

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").pxv(0.1, [-1.0, 0.0, 1.0]).round(6))
        [0.074292 0.198028 0.146809]
        """
        from ..distribution import LARGEST_VELOCITY

        self._check_distribution("pxv")
        x = _heights(x, "x", self._units)
        v = self._paper(_checked(v, "v"), "speed")
        x, v = _broadcast(x, v, ("x", "v"))
        result = np.zeros(x.shape)
        computed = np.abs(v) <= LARGEST_VELOCITY
        if computed.any():
            with self._paper_bounds():
                result[computed] = self._joint(x[computed], v[computed])
        result[(x == 0.0) & (v == 0.0)] = np.inf
        return _out(self._physical(result, "phase_space_density"))

    @property
    def smallest_force(self) -> float:
        """The smallest F > 0 at which w(F) is a double: 0 where w(F) ~ F^gamma e^(-S/F)
        vanishes as F -> 0 (S >= 0, r up to 0.73: ``distribution.small_force_decay``); where
        S < 0 it grows without bound, and below this F it comes within e^10 of the largest
        double (``weight`` refuses such F).  Per length, in ``units``."""
        return self._physical(self._paper_smallest_force, "per_length")

    @functools.cached_property
    def _paper_smallest_force(self) -> float:
        """``smallest_force`` in the paper's units."""
        from scipy import optimize

        from ..distribution import small_force_decay

        if small_force_decay(self.r) >= 0.0:
            return 0.0
        largest = np.log(np.finfo(float).max) - 10.0
        log_weight = self.weight_function.log
        return float(
            np.exp(
                optimize.brentq(
                    lambda y: float(log_weight(np.exp(y))) - largest, np.log(1e-300), 0.0
                )
            )
        )

    def weight(self, F):
        """The weight function w(F) of eq. (weightfunc) (eq. (weightfunc2) for the exact
        solutions): P(x, v) is a superposition of the modes of eq. (fpsol) with weight w(F).

        ``Equilibrium`` interpolates ln w between F_min and F_max
        (``distribution.WeightFunction``, relative error ``weight_function.interpolation_error``),
        continues it by its small-F form below and by its power law F^((2 beta - 5)/6) above,
        whose first neglected term is relative (F / F_max)^(-2/3) at most (F_max = 1e8).

        In ``units`` F is per length and w(F) per square root of a length: P(x) =
        int dF F^(-1/2) w(F) exp(-1/(12 F L) - F x), eq. (P(x)1), with L the unit of length.

        Parameters
        ----------
        F : array_like
            F >= ``smallest_force`` and F > 0, finite (subnormal F included).

        Returns
        -------
        numpy.ndarray or numpy.float64
            w(F), the shape of ``F``; 0 where it underflows (F below ~1e-4 L^-1 where S > 0).

        Raises
        ------
        ValueError
            Naming F and the bound: F <= 0, F < ``smallest_force`` (where w exceeds the largest
            double: r above 0.73), NaN or inf.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").weight([0.1, 1.0]).round(6))
        [0.229053 0.153341]
        """
        self._check_distribution("weight")
        given = _checked(F, "F", low=0.0, strictly=True)
        force = self._paper(given, "per_length")
        small = (force < self._paper_smallest_force) | (force == 0.0)
        if small.any():
            raise ValueError(
                f"F = {given[small].flat[0]:g} is below smallest_force = "
                f"{self.smallest_force:.3g} at r = {self._label}, where w(F) ~ F^gamma e^(-S/F) "
                "with S < 0 exceeds the largest double (distribution.small_force_decay)"
                if self._paper_smallest_force > 0.0
                else f"F = {given[small].flat[0]:g} is 0 in the paper's units (F L underflows)"
            )
        with np.errstate(over="ignore", divide="ignore"):  # e^(-S/F) underflows at tiny F
            weight = np.asarray(self._weight(force), dtype=float)
            return _out(self._physical(weight, "per_root_length"))

    def _flight_times(self, T, name: str, per_collision: bool = False) -> np.ndarray:
        """``T`` (in ``units``) checked and in the paper's units: >= 0, and each T > 0 at
        least the T below which nu(T) (rho(T) = nu / I with ``per_collision``) exceeds the
        largest double (``shortest_flight_time``); ValueError naming ``name``, r and the bound
        in ``units`` otherwise."""
        from .. import flight_time

        given = _checked(T, name, low=0.0)
        times = self._paper(given, "time")
        amplitude = self._short_flight_amplitude()
        rate = self._paper_scalar("collision_rate")
        if per_collision and np.isfinite(rate):
            amplitude /= rate
        shortest = flight_time.shortest_flight_time(amplitude, self.beta)
        bad = (given > 0.0) & ((times < shortest) | (times == 0.0))
        if bad.any():
            raise ValueError(
                f"{name} must be 0 or >= {self._physical(shortest, 'time'):.3g} at "
                f"r = {self._label}: below, {'rho' if per_collision else 'nu'}(T) ~ "
                f"T^(-beta/2) (eq. (short)) exceeds the largest double; got "
                f"{given[bad].flat[0]:g}"
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
            nu(T), the shape of ``T``, per time squared, finite; inf at T = 0, where
            nu ~ T^(-beta/2) (eq. (short)).

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
        return _out(self._physical(result, "rate_per_time"))

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
            rho(T), the shape of ``T``, per time, finite; inf at T = 0 (eq. (short)).

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
        rate = self._paper_scalar("collision_rate")
        if not np.isfinite(rate):
            return _out(np.where(times == 0.0, np.inf, 0.0))
        nu = np.full(times.shape, np.inf)
        positive = times > 0.0
        if positive.any():
            nu[positive] = self._flight_rate(times[positive])
        return _out(self._physical(nu / rate, "rate"))

    def return_speed_density(self, v, u):
        """v G_g(v, u) of eq. (kernel3): the density of the speed v at the next collision of a
        ball that leaves the floor with speed u (the same at every r).

        Parameters
        ----------
        v : array_like
            Return speeds, finite, v >= 0.
        u : array_like
            Outgoing speeds, finite, u >= ``kernel.SMALLEST_OUTGOING_SPEED`` (1e-300: the
            density peaks near v = u at about 0.24 / u, which must stay a double), broadcast
            against ``v``.

        Returns
        -------
        numpy.ndarray or numpy.float64
            v G_g(v, u), the broadcast shape, per speed; it integrates to 1 over v
            (eq. (normG)).  Finite
            for every finite v and every u in range (computed in logs,
            ``kernel.return_speed_density``): 0 only where it underflows (below ~1e-308, e.g.
            far from v ~ u at large u).

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").return_speed_density([0.5, 1.0], 1.0).round(6))
        [0.232269 0.429368]
        """
        from ..kernel import SMALLEST_OUTGOING_SPEED, return_speed_density

        v = self._paper(_checked(v, "v", low=0.0), "speed")
        given = _checked(u, "u", low=0.0)
        u = self._paper(given, "speed")
        small = u < SMALLEST_OUTGOING_SPEED
        if small.any():
            smallest = self._physical(SMALLEST_OUTGOING_SPEED, "speed")
            raise ValueError(
                f"u must be >= {smallest:g} (kernel.SMALLEST_OUTGOING_SPEED"
                f"{_in_units(self._units, 'speed')}), got {given[small].flat[0]:g}"
            )
        v, u = _broadcast(v, u, ("v", "u"))
        return _out(self._physical(return_speed_density(v, u), "per_speed"))

    # --- averages over the bins and cells of a simulation's tables (``SimulationResult``)
    def _speed_bins(self, lo, hi):
        """Speed bins (in ``units``) checked and in the paper's units: smallest_speed <= lo <
        hi, finite, lo > 0 (ValueError naming lo or hi and the bound)."""
        given_lo, given_hi = _broadcast(
            _checked(lo, "lo", low=0.0, strictly=True), _checked(hi, "hi"), ("lo", "hi")
        )
        lo, hi = self._paper(given_lo, "speed"), self._paper(given_hi, "speed")
        small = (lo < self._paper_smallest_speed) | (lo == 0.0)
        if np.any(small):
            raise ValueError(
                f"lo = {given_lo[small].flat[0]:g} is below smallest_speed = "
                f"{self.smallest_speed:.3g} at r = {self._label}"
            )
        if np.any(hi <= lo):
            raise ValueError(f"hi must be > lo, got hi = {given_hi[hi <= lo].flat[0]:g}")
        return lo, hi

    def _height_bins(self, lo, hi, what: str):
        """Height bins (in ``units``) checked and in the paper's units: lo = 0 or
        ``distribution.SMALLEST_POSITION`` <= lo < hi <= ``distribution.LARGEST_POSITION``
        (ValueError naming lo or hi and the bound)."""
        self._check_distribution(what)
        lo, hi = _broadcast(
            _heights(lo, "lo", self._units), _heights(hi, "hi", self._units), ("lo", "hi")
        )
        if np.any(hi <= lo):
            given = self._physical(hi[hi <= lo].flat[0], "length")
            raise ValueError(f"hi must be > lo, got hi = {given:g}")
        return lo, hi

    def p0v_bin_average(self, lo, hi):
        """P(0, v) averaged over speed bins as a simulation's P(0, v) table measures it, with
        the weight v of the flux through the floor (eq. (collrate)):
        int_lo^hi v P(0, v) dv / int_lo^hi v dv.

        ``ExactEquilibrium``: in closed form (``exact.outgoing_speed_bin_average``);
        ``Equilibrium``: ``bins.outgoing_speed_bin_average`` (8-point Gauss-Legendre in ln v)
        on panels of at most ``SPEED_PANEL`` in ln v, so a wide bin is as accurate as a
        narrow one.

        Parameters
        ----------
        lo, hi : array_like
            The bins' edges, ``smallest_speed`` <= lo < hi, lo > 0, finite; they broadcast
            (the v_lo, v_hi columns of ``SimulationResult.p0v`` without its under- and
            overflow bins).

        Returns
        -------
        numpy.ndarray or numpy.float64
            The bin averages, the broadcast shape.

        Raises
        ------
        ValueError
            Naming lo or hi and the bound.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").p0v_bin_average([0.5, 1.0], [1.0, 2.0]).round(6))
        [0.212134 0.051676]
        """
        lo, hi = self._speed_bins(lo, hi)
        average = np.asarray(self._outgoing_bin_average(lo, hi), dtype=float).reshape(lo.shape)
        return _out(self._physical(average, "phase_space_density"))

    def px_bin_average(self, lo, hi):
        """P(x) averaged over height bins as a simulation's P(x) table measures it (the time
        spent in the bin over the time and the bin's width): int_lo^hi P(x) dx / (hi - lo).

        The x integral is done under the F integral of eq. (P(x)1) in closed form
        (``distribution.position_bin_average``; ``exact.position_bin_average`` for the exact
        solutions), so a narrow bin loses nothing to cancellation.

        Parameters
        ----------
        lo, hi : array_like
            The bins' edges: lo = 0 or ``distribution.SMALLEST_POSITION`` (1e-300) <= lo < hi
            <= ``distribution.LARGEST_POSITION`` (1e12); they broadcast.

        Returns
        -------
        numpy.ndarray or numpy.float64
            The bin averages, the broadcast shape (finite also where P(0) is infinite).

        Raises
        ------
        ValueError
            Naming lo or hi and the bound; r above ``DISTRIBUTION_RESTITUTION_RANGE``.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").px_bin_average([0.0, 1.0], [1.0, 2.0]).round(8))
        [0.31801854 0.1429493 ]
        """
        lo, hi = self._height_bins(lo, hi, "px_bin_average")
        average = np.asarray(self._position_bin_average(lo, hi), dtype=float).reshape(lo.shape)
        return _out(self._physical(average, "per_length"))

    def v2_given_x_bin_average(self, lo, hi):
        """<v^2>_x of eq. (moment2) averaged over height bins with the weight P(x), as a
        simulation's <v^2>_x table measures it (the integral of v^2 dt over the time spent in
        the bin): int_lo^hi dx int_x^inf P(x') dx' / int_lo^hi P(x) dx, the ratio of the bin
        integrals of P(x) <v^2>_x and of P(x).

        Parameters
        ----------
        lo, hi : array_like
            The bins' edges, as ``px_bin_average``'s.

        Returns
        -------
        numpy.ndarray or numpy.float64
            The bin averages, the broadcast shape.

        Raises
        ------
        ValueError
            Naming lo or hi and the bound; r above ``DISTRIBUTION_RESTITUTION_RANGE``.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> print(ExactEquilibrium("1/2").v2_given_x_bin_average([0.0, 1.0], [1.0, 2.0]).round(8))
        [2.53258574 4.23045873]
        """
        lo, hi = self._height_bins(lo, hi, "v2_given_x_bin_average")
        average = np.asarray(self._speed_squared_bin_average(lo, hi), dtype=float)
        return _out(self._physical(average.reshape(lo.shape), "speed_squared"))

    def pxv_cell_average(self, x_lo, x_hi, v_lo, v_hi):
        """P(x, v) of eq. (fpsol) averaged over cells of (x, v), as a simulation's P(x, v)
        table measures it: int dx int dv P(x, v) / ((x_hi - x_lo) (v_hi - v_lo)).

        ``distribution.distribution_cell_average`` of ``weight_function``: the x average in
        closed form under the F integral, the v average by Gauss-Legendre on panels no wider
        than x_lo^(1/3); good to 1e-9 for x_lo >= 0.01.  The part of a cell at speeds the F
        integral does not reach at x_lo (v > (x_lo / 1.7e-8)^(1/3)) is averaged from the
        near-wall series of eq. (fp) (``near_wall.distribution_near_wall_cell_average``).

        Parameters
        ----------
        x_lo, x_hi, v_lo, v_hi : array_like
            The cells' edges, 0 < x_lo < x_hi <= ``distribution.LARGEST_POSITION`` and finite
            v_lo < v_hi; they broadcast.  A cell reaching speeds beyond the F integral's at
            x_lo needs x_hi <= 60 x_lo (the near-wall series holds up to x = 1e-6 v^3).

        Returns
        -------
        numpy.ndarray or numpy.float64
            The cell averages, the broadcast shape.

        Raises
        ------
        ValueError
            Naming the edge and the bound; r above ``DISTRIBUTION_RESTITUTION_RANGE``.

        Examples
        --------
        >>> from bouncing_ball import ExactEquilibrium
        >>> eq = ExactEquilibrium("1/2")
        >>> print(eq.pxv_cell_average([0.5, 1.0], [1.0, 2.0], 0.0, 1.0).round(8))
        [0.06005725 0.03294018]
        """
        from .. import distribution

        self._check_distribution("pxv_cell_average")
        units = self._units
        _checked(x_lo, "x_lo", low=0.0, strictly=True)
        x_lo, x_hi = _broadcast(
            _heights(x_lo, "x_lo", units), _heights(x_hi, "x_hi", units), ("x_lo", "x_hi")
        )
        v_lo, v_hi = _broadcast(_checked(v_lo, "v_lo"), _checked(v_hi, "v_hi"), ("v_lo", "v_hi"))
        v_lo, v_hi = self._paper(v_lo, "speed"), self._paper(v_hi, "speed")
        if np.any(x_hi <= x_lo):
            given = self._physical(x_hi[x_hi <= x_lo].flat[0], "length")
            raise ValueError(f"x_hi must be > x_lo, got x_hi = {given:g}")
        if np.any(v_hi <= v_lo):
            given = self._physical(v_hi[v_hi <= v_lo].flat[0], "speed")
            raise ValueError(f"v_hi must be > v_lo, got v_hi = {given:g}")
        x_lo, x_hi, v_lo, v_hi = np.broadcast_arrays(x_lo, x_hi, v_lo, v_hi)
        with self._paper_bounds():
            average = distribution.distribution_cell_average(
                x_lo, x_hi, v_lo, v_hi, self.weight_function, outgoing=self._outgoing
            )
        return _out(self._physical(average, "phase_space_density"))

    # --- the relaxation of the bounce-speed chain (``relaxation``), computed on first use
    _relaxation_step = None  # the solver's step of the matrix (``Equilibrium``: its own)

    @property
    def _relaxation(self):
        return _chain_relaxation(self.restitution, self._relaxation_step)

    @property
    def relaxation_eigenvalue(self) -> float:
        """lambda: how much of a correlation between the outgoing speeds of two bounces
        survives one more bounce, at large separations (``relaxation.bounce_chain_relaxation``).

        The second eigenvalue of the collision-to-collision operator of eq. (inteq), from the
        solver's Nystrom matrix, where it is isolated (r above ~0.6: near r = 1, lambda =
        r + O((1 - r)^3)); else the top of the continuum of low-speed cascades,
        ``relaxation.continuum_edge`` (closed form).  Built on first use (the solver's matrix
        and its eigenvalues; a second at r = 0.999), then kept for the process.

        Defined for r_c < r <= 0.9999 (eq. (rc)); below r_c the outgoing speeds collapse to 0
        and the chain has no relaxation: ValueError.  Its error estimate is
        ``relaxation_accuracy``.

        Examples
        --------
        At r = 1/2 the continuum edge, min over 1 <= b <= 2 of 2^(2 - b) / (2 sin((2 b + 1)
        pi / 6)):

        >>> from bouncing_ball import Equilibrium
        >>> print(round(Equilibrium("1/2").relaxation_eigenvalue, 6))
        0.814364
        """
        return self._relaxation.eigenvalue

    @property
    def correlation_bounces(self) -> float:
        """n_c = -1 / ln lambda: the number of bounces over which correlations of the outgoing
        speeds fall by e (``relaxation_eigenvalue``); ~1 / (1 - r) as r -> 1.

        Defined for r_c < r <= 0.9999; ValueError below r_c.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> print(round(Equilibrium("1/2").correlation_bounces, 4))
        4.8698
        """
        return self._relaxation.correlation_bounces

    @property
    def bounce_chain_time(self) -> float:
        """n_c <T>: the time the ball takes for ``correlation_bounces`` bounces, in ``units``;
        (8/3) (1 - r)^-2 time units T = Lambda / g^2 as r -> 1.

        The bounce chain's correlation length turned into time by the mean flight time
        (``mean_flight_time``).  Not the decay time of correlations in time
        (``relaxation_time``): the flight times are correlated over n_c bounces, which makes
        the slowest time 8/3 times longer near r = 1, and where lambda is the continuum edge
        (r below ~0.6) its slow correlations live in cascades of short low-speed flights that
        take little time.

        Defined for r_c < r <= 0.9999; ValueError below r_c (there <T> = 0).

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> print(round(Equilibrium("1/2").bounce_chain_time, 4))
        14.6093
        """
        bounces = self._relaxation.correlation_bounces
        return self._physical(bounces * self._paper_scalar("mean_flight_time"), "time")

    @property
    def _time_relaxation(self):
        return _process_relaxation(self.restitution, self._relaxation_step)

    @property
    def relaxation_rate(self) -> float:
        """gamma: the slowest decay rate of correlations in time of the process, in ``units``
        (per time unit T = Lambda / g^2 in the paper's).

        The smallest gamma > 0 with E[e^(gamma T) h(r V) | u] = h(u) solvable, from the bounce
        operator of eq. (inteq) tilted by the flight time of eq. (joint)
        (``time_relaxation.time_relaxation``): an isolated root below the large-speed
        continuum at every r above r_c; (9/64) (1 - r)^2 as r -> 1.  Built on first use, then
        kept for the process.  Defined for r_c < r <= 0.9999; ValueError below r_c.  Its
        relative error estimate is ``relaxation_rate_accuracy``.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> print(round(1.0 / Equilibrium("1/2").relaxation_rate, 4))
        19.3446
        """
        return self._physical(self._time_relaxation.rate, "rate")

    @property
    def relaxation_time(self) -> float:
        """1 / gamma: the slowest relaxation time of the process, in ``units``; (64/9) (1 -
        r)^-2 (1 - (1 - r)) time units T = Lambda / g^2 as r -> 1.

        Correlations in time of the state (x(t), v(t), the collisions binned in time) decay as
        exp(-t / relaxation_time) at long times (``relaxation_rate``).  Longer than the bounce
        chain's ``bounce_chain_time`` above r ~ 0.45, 8/3 times it as r -> 1.

        Defined for r_c < r <= 0.9999; ValueError below r_c.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> print(round(Equilibrium("1/2").relaxation_time, 4))
        19.3446
        """
        return self._physical(self._time_relaxation.time, "time")

    @property
    def relaxation_rate_accuracy(self) -> float:
        """The relative error estimate of ``relaxation_rate`` (and ``relaxation_time``): its
        change against a finer matrix (``time_relaxation.time_relaxation_accuracy``).  Built on
        first use, then kept for the process.  ValueError below r_c.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> Equilibrium("1/2").relaxation_rate_accuracy < 1e-8
        True
        """
        return _process_relaxation_accuracy(self.restitution, self._relaxation_step)

    @property
    def relaxation_accuracy(self) -> float:
        """The error estimate of ``relaxation_eigenvalue``: its change against a finer matrix
        (step x 0.8, lowest node x 1e-4; ``relaxation.relaxation_accuracy``).  Built on first
        use, then kept for the process.  ValueError below r_c.

        Examples
        --------
        >>> from bouncing_ball import Equilibrium
        >>> Equilibrium("1/2").relaxation_accuracy < 1e-8
        True
        """
        return _chain_relaxation_accuracy(self.restitution, self._relaxation_step)

    def observables(self) -> dict:
        """The scalars: r, beta, m, q, collision_rate, mean_x, delta_x, mean_flight_time,
        flight_time_second_moment and accuracy, as a dict, in ``units``.

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

    @contextlib.contextmanager
    def _paper_bounds(self):
        """A ValueError raised inside, by a check of the paper's units, says so."""
        try:
            yield
        except ValueError as error:
            if self._units.is_paper:
                raise
            units = self._units
            raise ValueError(
                f"{error} (in the paper's units, g = Lambda = 1: heights x / L, speeds v / V, "
                f"L = {units.length:.6g}, V = {units.speed:.6g})"
            ) from None

    def __repr__(self):
        units = self._units
        given = "" if units.is_paper else f", gravity={units.gravity!r}, noise={units.noise!r}"
        return (
            f"{type(self).__name__}(r={self.restitution}{given}): "
            f"I = {self.collision_rate:.10g}, "
            f"<x> = {self.mean_x:.10g}, Delta x = {self.delta_x:.10g}, "
            f"<T> = {self.mean_flight_time:.10g}, <T^2> = {self.flight_time_second_moment:.10g}; "
            f"beta = {self.beta:.6g}, m = {self.m:.6g}, q = {self.q:.6g}"
        )


@functools.lru_cache(maxsize=16)
def _chain_relaxation(exact: Fraction, step):
    """``relaxation.bounce_chain_relaxation`` at (r, step), once per process (step None: the
    solver's default)."""
    from .. import relaxation, solver

    return relaxation.bounce_chain_relaxation(
        exact, step=solver.DEFAULT_STEP if step is None else step
    )


@functools.lru_cache(maxsize=16)
def _chain_relaxation_accuracy(exact: Fraction, step) -> float:
    """``relaxation.relaxation_accuracy`` of ``_chain_relaxation(exact, step)``, once per
    process."""
    from .. import relaxation

    return relaxation.relaxation_accuracy(_chain_relaxation(exact, step))


@functools.lru_cache(maxsize=16)
def _process_relaxation(exact: Fraction, step):
    """``time_relaxation.time_relaxation`` at (r, step), once per process (step None: the
    solver's default)."""
    from .. import solver, time_relaxation

    return time_relaxation.time_relaxation(
        exact, step=solver.DEFAULT_STEP if step is None else step
    )


@functools.lru_cache(maxsize=16)
def _process_relaxation_accuracy(exact: Fraction, step) -> float:
    """``time_relaxation.time_relaxation_accuracy`` of ``_process_relaxation(exact, step)``,
    once per process."""
    from .. import time_relaxation

    return time_relaxation.time_relaxation_accuracy(_process_relaxation(exact, step))
