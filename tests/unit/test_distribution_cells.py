"""distribution.distribution_cell_average, the cell averages of P(x, v) that a simulation's (x, v)
histogram measures, against brute-force 2-D quadrature of the exact r = 1/2, 1/3 solutions."""

import warnings
from fractions import Fraction

import numpy as np
import pytest
from scipy import integrate

from bouncing_ball import distribution, exact

# (x_lo, x_hi, v_lo, v_hi): log x bins (5 per decade) from near the floor to the tail, v cells
# of width 0.5 and 1 on both sides of v = 0
CELLS = np.array(
    [
        (0.01, 0.0158489, -0.5, 0.0),
        (0.01, 0.0158489, 0.0, 1.0),
        (0.1, 0.158489, -1.0, -0.5),
        (1.0, 1.58489, 1.5, 2.0),
        (10.0, 15.8489, -3.0, -2.0),
    ]
)


def _closed_form(r):
    return distribution.closed_form_weight_function(
        float(r), lambda force: np.log(exact.weight_function(force, r))
    )


def _brute_force(x_lo, x_hi, v_lo, v_hi, r, nodes=12):
    """Gauss-Legendre in ln x and in v of exact.distribution over the cell, divided by its area."""
    t, weights = np.polynomial.legendre.leggauss(nodes)
    half = 0.5 * np.log(x_hi / x_lo)
    x = np.exp(0.5 * np.log(x_hi * x_lo) + half * t)
    v = 0.5 * (v_hi + v_lo) + 0.5 * (v_hi - v_lo) * t
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", integrate.IntegrationWarning)
        values = exact.distribution(x[:, None], v[None, :], r)
    integral = half * 0.5 * (v_hi - v_lo) * (weights * x) @ values @ weights
    return integral / ((x_hi - x_lo) * (v_hi - v_lo))


@pytest.mark.parametrize("r", [Fraction(1, 2), Fraction(1, 3)], ids=str)
def test_cell_average_matches_brute_force_quadrature(r):
    ours = distribution.distribution_cell_average(*CELLS.T, _closed_form(r))
    theirs = np.array([_brute_force(*cell, r) for cell in CELLS])
    assert np.max(np.abs(ours / theirs - 1.0)) < 1e-9


def test_four_speed_nodes_suffice_for_statistical_tests():
    """The statistical tests use 4 nodes per panel (their data are good to ~1e-3)."""
    weight = _closed_form(Fraction(1, 2))
    default = distribution.distribution_cell_average(*CELLS.T, weight)
    four = distribution.distribution_cell_average(*CELLS.T, weight, speed_nodes=4)
    assert np.max(np.abs(four / default - 1.0)) < 1e-7


def test_a_thin_cell_is_the_value_at_its_centre():
    weight = _closed_form(Fraction(1, 2))
    cell = distribution.distribution_cell_average(0.5, 0.5 + 1e-7, 0.3, 0.3 + 1e-7, weight)
    point, _ = distribution.distribution_by_force_integral(0.5 + 5e-8, 0.3 + 5e-8, weight)
    assert float(cell[()]) == pytest.approx(point, rel=1e-8)


@pytest.mark.parametrize(
    "cell", [(0.0, 0.1, 0.0, 1.0), (0.1, 0.1, 0.0, 1.0), (0.1, 0.2, 0.0, np.inf)]
)
def test_cells_must_be_finite_and_above_the_floor(cell):
    with pytest.raises(ValueError):
        distribution.distribution_cell_average(*cell, _closed_form(Fraction(1, 2)))
