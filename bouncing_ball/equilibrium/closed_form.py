"""``ExactEquilibrium``: the paper's exact equilibrium at r = 1/2 and 1/3, eqs. (P(0,v)),
(constants), (weightfunc2) (``bouncing_ball.exact``)."""

import functools
import math
from fractions import Fraction

import numpy as np

from ..restitution import (
    EXACT_RESTITUTIONS,
    parse_restitution,
)
from .base import EquilibriumBase
from .checks import EXACT_ACCURACY

__all__ = [
    "ExactEquilibrium",
]

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


class ExactEquilibrium(EquilibriumBase):
    """The paper's exact equilibrium at r = 1/2 or r = 1/3: eqs. (P(0,v)), (constants),
    (P(x)2), (weightfunc2), (fpsol), with the interface of ``Equilibrium``.

    The time averages come from these distributions (``exact.position_moments``), the flight
    times from eq. (rate) of ``flight_time`` integrated against the exact P(0, u) by adaptive
    quadrature (independent of the solver's rule).

    Parameters
    ----------
    r : str or fractions.Fraction
        ``"1/2"`` or ``"1/3"`` (or 0.5).
    gravity : float, optional
        g > 0, finite, of eq. (eqmo) (1: the paper's units); with ``noise``, the units of
        every argument and result (``units.PhysicalUnits``).
    noise : float, optional
        Lambda > 0, finite: <eta(t) eta(t')> = 2 Lambda delta(t - t'), eq. (eqmo) (1: the
        paper's units).

    Attributes
    ----------
    The same as ``EquilibriumBase``'s.  ``accuracy`` and ``position_accuracy`` are
    ``EXACT_ACCURACY``, the relative tolerance of its quadratures, held against the solver at
    its finest settings in tests/unit/test_equilibrium.py.  ``solution`` is the exact P(0, v)
    at the solver's nodes (step ``solver.DEFAULT_STEP``), on which the tables of
    ``workflow.solver_tables`` run their quadratures; ``weight_function`` is w(F) of
    eq. (weightfunc2) in closed form (``distribution.ClosedFormWeight``).

    Examples
    --------
    >>> from bouncing_ball import ExactEquilibrium
    >>> eq = ExactEquilibrium("1/3")
    >>> print(f"I = {eq.collision_rate:.10f}, beta = {eq.beta:.6f}, q = {eq.q:.6f}")
    I = 0.7500000000, beta = 1.500000, q = 1.500000
    >>> print(eq.px([0.1, 1.0]).round(6))
    [0.815666 0.199051]
    """

    def __init__(self, r, *, gravity=1.0, noise=1.0):
        self._set_restitution(_exact_restitution(r))
        self._set_units(gravity, noise)

    @property
    def distribution_available(self) -> bool:
        """True: P(x), <v^2>_x, P(x, v) and w(F) are known in closed form or by quadrature."""
        return True

    @property
    def accuracy(self) -> float:
        """``EXACT_ACCURACY``: the relative tolerance of the quadratures of the time averages
        and flight times (P(0, v) is in closed form, to rounding)."""
        return EXACT_ACCURACY

    @property
    def position_accuracy(self) -> float:
        """``EXACT_ACCURACY``: the relative tolerance of the F integrals of P(x), <v^2>_x,
        P(x, v) (closed forms at r = 1/2)."""
        return EXACT_ACCURACY

    @functools.cached_property
    def solution(self):
        """The exact P(0, v) of eq. (P(0,v)) at the solver's nodes (``solver.DEFAULT_STEP`` in
        s = ln v + v^(1/2), from 1e-12 to where P(0, v) has fallen by e^-700), as a
        ``solver.OutgoingSpeedSolution`` (eigenvalue 1): the nodes the quadratures of the
        flight-time and return-speed tables run on."""
        from .. import exact, solver

        s = np.arange(
            solver.coordinate_of_speed(1e-12),
            solver.coordinate_of_speed(700.0 / self._exponents[2]),
            solver.DEFAULT_STEP,
        )
        nodes = solver.speed_of_coordinate(s)
        density = exact.outgoing_speed_density(nodes, self.restitution)
        return solver.OutgoingSpeedSolution(
            self.r, self.beta, solver.DEFAULT_STEP, nodes, density, 1.0
        )

    @functools.cached_property
    def weight_function(self):
        """w(F) of eq. (weightfunc2) in closed form (``distribution.closed_form_weight_function``)."""
        from .. import distribution

        return distribution.closed_form_weight_function(self.r, self._log_weight)

    def _log_weight(self, force):
        from .. import exact

        with np.errstate(divide="ignore"):
            return np.log(exact.weight_function(force, self.restitution))

    # the time averages: computed on first use (a second at r = 1/3, nested quadratures)
    @functools.cached_property
    def _moments(self) -> dict:
        from .. import exact

        return exact.position_moments(self.restitution)

    @functools.cached_property
    def _flight_moments(self) -> dict:
        """<T> and <T^2> per collision, in the paper's units (computed on first use)."""
        rate = self._paper_scalar("collision_rate")
        return {
            "mean_flight_time": self._flight_moment(1) / rate,
            "flight_time_second_moment": self._flight_moment(2) / rate,
        }

    def _paper_scalar(self, name: str) -> float:
        if name in ("mean_flight_time", "flight_time_second_moment"):
            return self._flight_moments[name]
        return float(self._moments[name])

    def _flight_moment(self, k: int) -> float:
        """int du u P(0, u) E[T^k | u], eqs. (meanT), (meanT2), by adaptive quadrature."""
        from scipy import integrate

        from .. import exact, flight_time

        given_speed = {
            1: flight_time.mean_flight_time_given_speed,
            2: flight_time.flight_time_second_moment_given_speed,
        }[k]

        def integrand(u):
            return u * float(exact.outgoing_speed_density(u, self.restitution) * given_speed(u))

        value, _ = integrate.quad(integrand, 0.0, np.inf, epsabs=0.0, epsrel=1e-13, limit=200)
        return value

    def _outgoing(self, v):
        from .. import exact

        return exact.outgoing_speed_density(v, self.restitution)

    def _floor_density(self):
        return np.inf  # beta >= 1 at r = 1/2 and 1/3

    def _position(self, x):
        from .. import exact

        return exact.position_density(x, self.restitution)

    def _speed_squared(self, x):
        from .. import exact

        return exact.mean_speed_squared_given_position(x, self.restitution)

    def _joint(self, x, v):
        from .. import exact

        return exact.distribution(x, v, self.restitution)

    def _weight(self, force):
        from .. import exact

        return exact.weight_function(force, self.restitution)

    def _outgoing_bin_average(self, lo, hi):
        from .. import exact

        return exact.outgoing_speed_bin_average(lo, hi, self.restitution)

    def _position_bin_average(self, lo, hi):
        from .. import exact

        return exact.position_bin_average(lo, hi, self.restitution)

    def _speed_squared_bin_average(self, lo, hi):
        from .. import exact

        return exact.speed_squared_given_position_bin_average(lo, hi, self.restitution)

    def _short_flight_amplitude(self) -> float:
        from .. import exact, flight_time

        amplitude = exact.normalization_constant(self.restitution)  # P(0, v) ~ A v^-beta
        return amplitude * flight_time.short_time_constant(self.beta)

    def _flight_rate(self, times):
        """nu(T) in the regimes of ``flight_time.flight_rate_in_regimes``, with the exact A of
        eq. (constants) in eq. (short) and ``_direct_flight_rate`` between."""
        from .. import flight_time

        return flight_time.flight_rate_in_regimes(
            times, self._direct_flight_rate, self._short_flight_amplitude(), self.beta, self.r
        )

    def _direct_flight_rate(self, times):
        """nu(T) = int du u P(0, u) f(T | u), eq. (rate): adaptive quadrature in ln u from
        1e-7 T^(1/2) (below, the integrand is u^(5/2 - beta) and is summed in closed form) to
        where P(0, u) and f(T | u) have both fallen by e^-60, for each T on its own."""
        from scipy import integrate

        from .. import exact, flight_time

        def integrand(log_u, t):
            u = np.exp(np.atleast_1d(log_u))
            rate = u * u * exact.outgoing_speed_density(u, self.restitution)
            return float((rate * flight_time.flight_time_density(t, u))[0])

        values = []
        for t in np.asarray(times, dtype=float).ravel():
            lo = math.log(1e-7 * math.sqrt(t))
            hi = math.log(0.5 * t + 12.0 * math.sqrt(t) + 60.0 / self._exponents[2])
            peak = math.log(max(math.sqrt(t), 0.5 * t))
            value, _ = integrate.quad(
                integrand, lo, hi, args=(t,), points=[peak], epsabs=0.0, epsrel=1e-12, limit=400
            )
            values.append(value + integrand(lo, t) / (2.5 - self.beta))
        return np.asarray(values).reshape(np.shape(times))
