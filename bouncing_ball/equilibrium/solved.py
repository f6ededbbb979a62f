"""``Equilibrium``: the equilibrium at any r the solver answers, from P(0, v) of eq. (inteq)
and the weight function w(F) of eq. (weightfunc) built from it."""

import collections
import functools
import inspect
import weakref
from fractions import Fraction

import numpy as np

from ..restitution import (
    DISTRIBUTION_RESTITUTION_RANGE,
    check_distribution_range,
    check_solver_range,
    in_range,
)
from .base import EquilibriumBase
from .checks import SPEED_PANEL, check_solver_settings

__all__ = [
    "Equilibrium",
    "KEPT_SOLVES",
]

# ---------------------------------------------------------------------------------------------
# any r: the solver


def _solution(exact: Fraction, step: float):
    """P(0, v) of eq. (inteq) at r = ``exact``, trapezoidal step ``step``.  Where the whole
    distribution is computed (``DISTRIBUTION_RESTITUTION_RANGE``) its nodes reach where P(0, v)
    falls to e^-690, as w(F) at small F needs (``distribution.outgoing_speed_solution``);
    above, up to the solver's own highest node (``solver.solve_outgoing_speed_density``), which
    holds P(0, v) and the time averages."""
    from .. import distribution, solver

    if in_range(exact, DISTRIBUTION_RESTITUTION_RANGE):
        return distribution.outgoing_speed_solution(exact, step=step)
    return solver.solve_outgoing_speed_density(exact, step=step)


#: How many solves a process keeps besides those a live ``Equilibrium`` holds: the last ones
#: asked for, so that an ``Equilibrium`` made again after the last one of its r was dropped (a
#: notebook cell run again, a test module after another) is not solved again.
KEPT_SOLVES = 8


class _Solve:
    """One solve of eq. (inteq) at one (r, step), and what is computed from it on first use:
    its accuracy estimate (``solver.accuracy_estimate``, a second, finer solve) and the
    interpolated w(F) of eq. (weightfunc) for each number of panel nodes
    (``distribution.interpolated_weight_function``).  Kilobytes: P(0, v) at a few hundred
    nodes, w(F) as Chebyshev series."""

    def __init__(self, solution):
        self.solution = solution
        self.accuracy = None
        self.weight_functions = {}

    def accuracy_estimate(self) -> float:
        if self.accuracy is None:
            from .. import solver

            self.accuracy = float(solver.accuracy_estimate(self.solution))
        return self.accuracy

    def weight_function(self, panel_nodes: int):
        if panel_nodes not in self.weight_functions:
            from .. import distribution

            self.weight_functions[panel_nodes] = distribution.interpolated_weight_function(
                self.solution, panel_nodes=panel_nodes
            )
        return self.weight_functions[panel_nodes]


# the solves of the process by (r, step): each kept while anything holds it (every live
# Equilibrium holds its own), and the last KEPT_SOLVES asked for held here besides
_LIVE_SOLVES = weakref.WeakValueDictionary()
_RECENT_SOLVES = collections.OrderedDict()


def _shared_solve(exact: Fraction, step: float) -> _Solve:
    """The process's solve at (r, step): the one a live ``Equilibrium`` or the recent ones
    hold, else a new one."""
    key = (exact, step)
    solve = _LIVE_SOLVES.get(key)
    if solve is None:
        solve = _Solve(_solution(exact, step))
        _LIVE_SOLVES[key] = solve
    _RECENT_SOLVES[key] = solve
    _RECENT_SOLVES.move_to_end(key)
    while len(_RECENT_SOLVES) > KEPT_SOLVES:
        _RECENT_SOLVES.popitem(last=False)
    return solve


def _restored(cls, state):
    """An ``Equilibrium`` from its pickled state (``Equilibrium.__reduce__``)."""
    restored = object.__new__(cls)
    restored.__dict__.update(state)
    return restored


def _solver_restitution(r) -> Fraction:
    """r parsed and within the solver's range of r."""
    return check_solver_range(r, "r")


class Equilibrium(EquilibriumBase):
    """The equilibrium state of the bouncing ball at one coefficient of restitution r,
    from the numerical solution of eq. (inteq).

    Parameters
    ----------
    r : float or str
        The coefficient of restitution, eq. (restitution): a decimal (read as written: 0.3 is
        3/10; a numpy float as the shortest decimal that gives it back, so np.float32(0.1) is
        1/10), a whole number, or an exact fraction string such as ``"1/3"`` or a
        ``Fraction``, within the solver's range
        (``restitution.SOLVER_RESTITUTION_RANGE``).  The position-dependent quantities (P(x),
        <v^2>_x, P(x, v), w(F)) are computed in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``;
        above it they raise ValueError, and P(0, v), the time averages, the flight times and the
        exponents remain.
    quadrature_step : float, optional
        The trapezoidal step of the solver in s = ln v + v^(1/2) (``solver.DEFAULT_STEP``; the
        config's ``solver.quadrature_step``), 0.1 <= step <= 0.3 (``QUADRATURE_STEP_RANGE``,
        where the 1e-8 accuracy target is met).
    weight_panel_nodes : int, optional
        Chebyshev nodes per panel of the interpolated w(F) (``distribution.PANEL_CHEBYSHEV_NODES``;
        the config's ``solver.weight_panel_nodes``), 10 to 40 (``WEIGHT_PANEL_NODES_RANGE``,
        where P(x) meets the 1e-8 accuracy target).
    gravity : float, optional
        g > 0, finite: the acceleration toward the floor, eq. (eqmo) (1: the paper's units;
        9.81 for metres and seconds on Earth).
    noise : float, optional
        Lambda > 0, finite: the strength of the random force, <eta(t) eta(t')> =
        2 Lambda delta(t - t'), eq. (eqmo), the velocity variance the noise adds per unit time
        being 2 Lambda (1: the paper's units; m^2/s^3 with g in m/s^2).  With ``gravity`` it
        fixes ``units`` (``units.PhysicalUnits``): every argument and result is in them,
        each times its unit L^a T^b, L = Lambda^2 / g^3, T = Lambda / g^2.  The solve is the
        same whatever the units (it is in the paper's).

    Attributes
    ----------
    units : units.PhysicalUnits
        g and Lambda, and the units they make.
    r : float
    restitution : fractions.Fraction
        r exactly, as parsed.
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
        1e-3 <= v <= 20 against a finer solve (computed on first use: a second solve; then
        kept with the solve).
    position_accuracy : float
        The largest of ``|int P dx - 1|`` and the relative differences of <x>, Delta x from P(x)
        (eq. (P(x)1)) and from the Ito identities (builds w(F) on first use).
    relaxation_eigenvalue, correlation_bounces, bounce_chain_time, relaxation_accuracy : float
        The relaxation of the bounce-speed chain (``relaxation``): lambda, n_c = -1 / ln lambda,
        n_c <T> and the error estimate of lambda (built on first use; ValueError below r_c).
    relaxation_rate, relaxation_time, relaxation_rate_accuracy : float
        The slowest relaxation of the process in time (``time_relaxation``): gamma, 1 / gamma
        and the relative error estimate of gamma (built on first use; ValueError below r_c).
    distribution_available : bool
        Whether r lies in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``, where P(x), <v^2>_x,
        P(x, v) and w(F) are computed.
    solution : solver.OutgoingSpeedSolution
        P(0, v) at the solver's nodes: the one solve everything here is computed from (the
        workflow's solve rule writes the same numbers), shared by the ``Equilibrium`` objects
        of this r and step in the process.
    quadrature_step : float
    weight_panel_nodes : int

    Notes
    -----
    The solve, its accuracy estimate and w(F) are built once per process and (r, settings),
    and kept for as long as any ``Equilibrium`` of that r and step lives, so a sweep over many
    r built once answers each again at no cost; the last ``KEPT_SOLVES`` made are kept besides,
    after their objects are dropped.  A pickle or a copy carries the solve and what has been
    computed from it (kilobytes), so the copy answers the same numbers, to the bit, in another
    process without solving again.

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
    >>> print(eq.px([0.1, 1.0]).round(6))  # builds w(F) first
    [0.503776 0.183784]

    In metres and seconds, a ball under g = 9.81 m/s^2 shaken with Lambda = 0.05 m^2/s^3
    (the same solve: <x> is 6 L, L = Lambda^2 / g^3):

    >>> ball = Equilibrium("1/2", gravity=9.81, noise=0.05)
    >>> print(f"<x> = {ball.mean_x:.6e} m, 6 L = {6 * ball.units.length:.6e} m")
    <x> = 1.588855e-05 m, 6 L = 1.588855e-05 m

    The exact solutions are their own class, ``ExactEquilibrium("1/2")``, not a flag of this
    one: each class is built one way, with one signature, and both are ``EquilibriumBase``.
    Passing ``exact=`` raises a TypeError that names ``ExactEquilibrium``.
    """

    def __new__(cls, *args, **kwargs):
        if "exact" in kwargs:
            raise TypeError(
                "Equilibrium takes no exact argument: the paper's exact solutions are "
                "ExactEquilibrium(r), r = 1/2 or 1/3 (the same interface, EquilibriumBase)"
            )
        return super().__new__(cls)

    def __init__(self, r, *, quadrature_step=None, weight_panel_nodes=None, gravity=1.0, noise=1.0):
        from .. import flight_time, solver

        self._set_restitution(_solver_restitution(r))
        self._set_units(gravity, noise)
        self.quadrature_step, self.weight_panel_nodes = check_solver_settings(
            quadrature_step, weight_panel_nodes
        )
        self._solve = _shared_solve(self.restitution, self.quadrature_step)
        averages = solver.time_averages(self.solution)
        self._averages = {
            "collision_rate": float(averages["collision_rate"]),
            "mean_x": float(averages["mean_x"]),
            "delta_x": float(averages["delta_x"]),
            "mean_flight_time": float(flight_time.mean_flight_time(self.solution)),
            "flight_time_second_moment": float(
                flight_time.flight_time_second_moment(self.solution)
            ),
        }
        self._relaxation_step = self.quadrature_step

    def __reduce__(self):
        """Pickled and copied as its state: r, the settings, the solve and what has been
        computed from it (kilobytes; rebuilding them would cost a solve and w(F), and could
        differ in the last bits on another machine), restored on an object made without
        calling ``__init__`` (``_restored``)."""
        return (_restored, (type(self), dict(self.__dict__)))

    def _paper_scalar(self, name: str) -> float:
        return self._averages[name]

    @property
    def distribution_available(self) -> bool:
        """Whether r lies in ``restitution.DISTRIBUTION_RESTITUTION_RANGE``, where P(x),
        <v^2>_x, P(x, v) and w(F) are computed."""
        return in_range(self.restitution, DISTRIBUTION_RESTITUTION_RANGE)

    @property
    def solution(self):
        """P(0, v) of eq. (inteq) at the solver's nodes (``solver.OutgoingSpeedSolution``): the
        one solve everything here is computed from, shared by the ``Equilibrium`` objects of
        this r and step in the process."""
        return self._solve.solution

    def _check_distribution(self, what: str) -> None:
        if not self.distribution_available:
            try:
                check_distribution_range(self.r, "r")
            except ValueError as error:
                raise ValueError(
                    f"{error}: Equilibrium.{what} needs w(F) of eq. (weightfunc), computed "
                    f"only there; at r = {self._label} Equilibrium gives P(0, v), the time "
                    "averages, the flight times and the exponents"
                ) from None

    # --- lazily built
    @property
    def accuracy(self) -> float:
        """The solver's error estimate (``solver.accuracy_estimate``): the largest relative
        change of P(0, v) over 1e-3 <= v <= 20 against a finer solve (computed on first use,
        then kept with the solve).  It does not cover the speeds that carry <x> and Delta x
        near r = 1 (M_4 and M_6 peak near 4/q and 6/q, about 260 and 400 at r = 0.99); there
        the check is the energy balance, ``solver.energy_balance_residual`` (the summary's
        ``energy_balance_residual``)."""
        return self._solve.accuracy_estimate()

    @property
    def weight_function(self):
        """w(F) of eq. (weightfunc), interpolated from ``solution``
        (``distribution.WeightFunction``); built on first use, then kept with the solve: for as
        long as any ``Equilibrium`` of this r and step lives (``KEPT_SOLVES``)."""
        self._check_distribution("weight_function")
        return self._solve.weight_function(self.weight_panel_nodes)

    @functools.cached_property
    def _position_averages(self) -> dict:
        """int P dx, <x> and Delta x from P(x) of eq. (P(x)1) (``distribution.position_averages``)."""
        from .. import distribution

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
                abs(averages["mean_x"] / self._paper_scalar("mean_x") - 1.0),
                abs(averages["delta_x"] / self._paper_scalar("delta_x") - 1.0),
            )
        )

    # --- the quantities
    def _outgoing(self, v):
        return self.solution.outgoing_speed_density(v)

    def _floor_density(self):
        return (1.0 + self.r) * self.solution.moment(0) if self.beta < 1.0 else np.inf

    def _position(self, x):
        from .. import distribution

        return distribution.position_density(x, self.weight_function)

    def _speed_squared(self, x):
        from .. import distribution

        return distribution.mean_speed_squared_given_position(x, self.weight_function)

    def _joint(self, x, v):
        from .. import distribution

        return distribution.distribution(x, v, self.weight_function, self.solution)

    def _weight(self, force):
        return self.weight_function(force)

    def _flight_rate(self, times):
        from .. import flight_time

        return flight_time.flight_rate_density(self.solution, times)

    def _short_flight_amplitude(self) -> float:
        from .. import flight_time

        amplitude = flight_time.small_speed_amplitude(self.solution)
        return amplitude * flight_time.short_time_constant(self.beta)

    def _outgoing_bin_average(self, lo, hi):
        """``bins.outgoing_speed_bin_average`` on panels of at most ``SPEED_PANEL`` in ln v,
        recombined with their weights int v dv."""
        from ..bins import outgoing_speed_bin_average

        lo, hi = lo.ravel(), hi.ravel()
        panels = np.maximum(np.ceil(np.log(hi / lo) / SPEED_PANEL), 1).astype(int)
        owner = np.repeat(np.arange(lo.size), panels)
        step = np.concatenate([np.arange(n) for n in panels])
        ratio = (hi / lo) ** (1.0 / panels)
        lower = lo[owner] * ratio[owner] ** step
        upper = np.where(step + 1 == panels[owner], hi[owner], lower * ratio[owner])
        flux = outgoing_speed_bin_average(self._outgoing, lower, upper) * (upper**2 - lower**2)
        return np.bincount(owner, flux, minlength=lo.size) / (hi**2 - lo**2)

    def _position_bin_average(self, lo, hi):
        from .. import distribution

        return distribution.position_bin_average(lo, hi, self.weight_function)

    def _speed_squared_bin_average(self, lo, hi):
        from .. import distribution

        return distribution.speed_squared_given_position_bin_average(lo, hi, self.weight_function)


# the class's signature is its __init__'s (``__new__`` only refuses ``exact``)
Equilibrium.__signature__ = inspect.Signature(
    list(inspect.signature(Equilibrium.__init__).parameters.values())[1:]
)
