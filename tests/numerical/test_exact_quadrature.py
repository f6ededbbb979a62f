"""The exact solutions' bin averages against brute-force nested quadrature (seconds each: the
numerical tier)."""

from fractions import Fraction

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import exact


@pytest.mark.parametrize(("lo", "hi"), [(0.0, 1.0e-3), (0.1, 0.158), (30.0, 50.0)])
def test_bin_averaged_speed_squared_at_one_third_agrees_with_nested_quadrature(lo, hi):
    """<v^2>_x averaged over a bin at r = 1/3, eq. (moment2): the single F integral of
    eq. (P(x)2) with both x integrals done analytically equals the direct route,
    int_bin dx int_x^inf P(x') dx' / int_bin P(x) dx by quadrature of P(x)."""
    r = Fraction(1, 3)

    def tail(x):
        return integrate.quad(lambda y: float(exact.position_density(y, r)), x, np.inf)[0]

    numerator = integrate.quad(tail, lo, hi, epsrel=1e-10)[0]
    denominator = integrate.quad(lambda y: float(exact.position_density(y, r)), lo, hi)[0]
    value = exact.speed_squared_given_position_bin_average(np.array([lo]), np.array([hi]), r)
    assert value[0] == pytest.approx(numerator / denominator, rel=1e-8)
