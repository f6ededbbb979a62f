"""What the tests of each r's scales (bouncing_ball.scales) share: the bound an end may
leave, and the collisions outside a range of outgoing speeds by quadrature."""

import math

import numpy as np
from scipy import integrate

# the ranges aim at TAIL_FRACTION (1e-6) at each end from asymptotic forms whose constants are
# of order 1: an end may leave a few times that, never a tenth of the 1e-4 that a table may
# leave in all
END_BOUND = 1.0e-5


def collisions_outside(equilibrium, lo, hi):
    """The fractions of the collisions (v P(0, v), eq. (collrate)) below lo and above hi, by
    quadrature in ln v."""

    def flux(log_v):
        v = np.exp(log_v)
        return v * v * equilibrium.p0v(v)

    rate = equilibrium.collision_rate
    lowest = math.log(max(lo * 1e-130, equilibrium.smallest_speed))
    below = integrate.quad(flux, lowest, math.log(lo), limit=400)[0]
    above = integrate.quad(flux, math.log(hi), math.log(hi) + 20.0, limit=400)[0]
    return below / rate, above / rate
