"""The exact solutions' bin averages against brute-force nested quadrature (seconds each: the
numerical tier)."""

from fractions import Fraction

import numpy as np
import pytest
from scipy import integrate
from workflow_support import REPOSITORY

from bouncing_ball import exact
from bouncing_ball.bins import linear_grid
from bouncing_ball.workflow.config import read_config


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


def test_bin_averaged_position_density_at_one_third_agrees_with_quadrature_of_p_of_x():
    """P(x) averaged over bins at r = 1/3, all at once with the x integral done under the F
    integral of eq. (P(x)2), against quadrature of P(x) over each bin."""
    r = Fraction(1, 3)
    lo = np.array([0.0, 1.0e-3, 0.1, 2.0, 30.0])
    hi = np.array([1.0e-3, 2.0e-3, 0.158, 3.0, 50.0])
    expected = [
        integrate.quad(lambda y: float(exact.position_density(y, r)), a, b, epsrel=1e-11)[0]
        / (b - a)
        for a, b in zip(lo, hi, strict=True)
    ]
    np.testing.assert_allclose(exact.position_bin_average(lo, hi, r), expected, rtol=1e-9)


@pytest.mark.parametrize("r", [Fraction(1, 2), Fraction(1, 3)], ids=str)
def test_distribution_table_agrees_with_one_point_quad_everywhere(r):
    """Every x > 0 point of the pipeline's exact P(x, v) table (config.yaml's exact.positions
    and exact.speeds), all at once by adaptive Gauss-Kronrod, against scipy's quad one point
    at a time (distribution_by_force_integral): within the sum of the two error estimates and
    1e-10 relative."""
    settings = read_config(REPOSITORY / "config" / "config.yaml")["exact"]
    table, worst = exact.distribution_table(
        settings["positions"], linear_grid(settings["speeds"]), r
    )
    inside = table[table["x"] > 0.0]
    _, errors = exact.distribution_with_error(inside["x"], inside["v"], r)
    theirs, their_errors = np.array(
        [
            exact.distribution_by_force_integral(x, v, r)
            for x, v in zip(inside["x"], inside["v"], strict=True)
        ]
    ).T
    values = inside["pxv"].to_numpy()
    assert np.all(np.abs(values - theirs) <= errors + their_errors)
    assert np.max(np.abs(values / theirs - 1.0)) < 1e-10
    assert worst == pytest.approx(np.max(errors / values))
