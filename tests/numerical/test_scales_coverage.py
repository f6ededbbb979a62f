"""Each r's own scales against the solver over the whole range of r (bouncing_ball.scales):
the automatic ranges of the simulation's bins and the solver's tables leave at most a few
1e-6 of the collisions, the time and the flights beyond each end."""

import math

import numpy as np
import pytest
from scales_support import END_BOUND, collisions_outside
from scipy import integrate

from bouncing_ball import Equilibrium, scales


@pytest.mark.parametrize("r", [0.2, 0.25, 0.6, 0.75, 0.9, 0.95, 0.99, 0.999])
def test_the_speed_range_holds_the_solved_collisions(r):
    lo, hi = scales.outgoing_speed_range(r, smallest=scales.smallest_simulated_speed())
    below, above = collisions_outside(Equilibrium(r), lo, hi)
    assert below < END_BOUND * (10 if r == 0.2 else 1)  # r = 0.2: at the simulation's floor
    assert above < END_BOUND


def _outside(density, lo, hi, lowest, decades_above):
    """The mass of ``density`` (over z) below lo (from ``lowest``) and above hi, by quadrature
    in ln z."""

    def weighted(log_z):
        z = np.exp(log_z)
        return z * density(z)

    below = integrate.quad(weighted, math.log(lowest), math.log(lo), limit=400)[0]
    above = integrate.quad(weighted, math.log(hi), math.log(hi) + decades_above, limit=400)[0]
    return below, above


@pytest.mark.parametrize("r", [0.05, 0.2, 0.25, 0.75, 0.95, 0.99])
def test_the_position_range_holds_the_solved_time(r):
    """The solver's P(x) (eq. (P(x)1); int P dx = 1): the time below x_lo and above x_hi."""
    equilibrium = Equilibrium(r)
    lo, hi = scales.position_range(r)
    below, above = _outside(equilibrium.px, lo, hi, lo * 1e-20, 6.0)
    assert below < END_BOUND
    assert above < END_BOUND


@pytest.mark.parametrize("r", [0.5, 0.75, 0.95, 0.99])
def test_the_flight_time_range_holds_the_solved_flights(r):
    """The solver's flight-time density (eq. (rate)), normalised per flight: the flights
    shorter than T_lo and longer than T_hi (where T_lo is above the table's 1e-30)."""
    equilibrium = Equilibrium(r)
    lo, hi = scales.flight_time_range(r)
    below, above = _outside(
        equilibrium.flight_time_density, lo, min(hi, 1e4), max(lo * 1e-20, 1e-30), 3.0
    )
    assert below < END_BOUND
    assert above < END_BOUND
