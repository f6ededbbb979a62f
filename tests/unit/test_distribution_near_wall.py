"""P(x, v) next to the floor at large v (bouncing_ball.near_wall): the Taylor series in x of
eq. (fp) from P(0, v), where the F integral of eq. (fpsol) oscillates too fast on the real axis.

Held against the exact P(x, v) of r = 1/2 and 1/3 on a rotated F ray
(``exact.distribution_on_ray``, itself held against eq. (P(0,v)) and the real-axis integral),
and against the real-axis F integral where both work (x from 1.7e-8 v^3 to 1e-6 v^3)."""

import numpy as np
import pytest

from bouncing_ball import ExactEquilibrium, exact
from bouncing_ball.airy import check_force_integral_point
from bouncing_ball.distribution import (
    DISTRIBUTION_NOISE,
    closed_form_weight_function,
    distribution_by_force_rule,
)
from bouncing_ball.near_wall import (
    NEAR_WALL_REACH,
    distribution_near_wall,
    distribution_near_wall_cell_average,
    near_wall_points,
)

#: The ray's accuracy, relative (its docstring: ~3e-13 at r = 1/2; at r = 1/3 its rounding grows
#: like e^(v / 2) x 1e-16, 3e-13 at v = 10), below the v each r is tested to.
RAY_ACCURACY = {"1/2": 5e-13, "1/3": 5e-13}


RAY_SPEEDS = {"1/2": [2.0, 5.0, 20.0, 60.0, 250.0], "1/3": [2.0, 5.0, 10.0]}


def _outgoing(which):
    return lambda v: exact.outgoing_speed_density(v, which)


@pytest.mark.parametrize("which", ["1/2", "1/3"])
def test_the_ray_reproduces_the_floor_and_the_real_axis_integral(which):
    """The reference: at x = 0 the F ray gives eq. (P(0,v)) (where the real-axis integral
    converges only conditionally), and at x > 0 where the real-axis integral works it agrees
    with it within the latter's error estimate and the ray's accuracy."""
    speeds = np.array(RAY_SPEEDS[which])
    floor = exact.distribution_on_ray(0.0, speeds, which)
    np.testing.assert_allclose(
        floor, exact.outgoing_speed_density(speeds, which), rtol=RAY_ACCURACY[which], atol=0.0
    )
    x, v = np.meshgrid([1e-3, 0.1, 2.0, 30.0], [0.01, 0.5, 1.0, 3.0], indexing="ij")
    reference, error = exact.distribution_with_error(x, v, which)
    ray = exact.distribution_on_ray(x, v, which)
    assert np.all(np.abs(ray - reference) <= error + RAY_ACCURACY[which] * reference)


@pytest.mark.parametrize("which", ["1/2", "1/3"])
def test_the_series_matches_the_exact_solution_at_large_speeds_next_to_the_floor(which):
    """From x = 1e-9 to NEAR_WALL_REACH v^3, at v where the real-axis F integral is refused:
    the series with the exact P(0, v) against the exact P(x, v) on the F ray, within the
    series' error estimate and the ray's accuracy (both ~1e-13 relative: 1e-10 of the largest
    P(x, v) at that x is the library's stated accuracy)."""
    r = 0.5 if which == "1/2" else 1.0 / 3.0
    for v in RAY_SPEEDS[which]:
        x = np.geomspace(1e-9, 0.999 * NEAR_WALL_REACH * v**3, 7)
        values, errors = distribution_near_wall(x, v, _outgoing(which), r)
        reference = exact.distribution_on_ray(x, v, which)
        assert np.all(errors <= 1e-12 * values)
        assert np.all(np.abs(values - reference) <= errors + RAY_ACCURACY[which] * reference)
        with pytest.raises(ValueError, match="oscillates too fast"):
            check_force_integral_point(float(x[0]), v)


def test_the_series_matches_the_force_integral_where_both_work():
    """x from 2e-8 v^3 (just inside the F integral's reach) to NEAR_WALL_REACH v^3 at r = 1/2,
    with the exact w(F) in the fixed rule: within DISTRIBUTION_NOISE of the largest P(x, v) at
    that x (the rule's stated accuracy) plus both error estimates."""
    weight = closed_form_weight_function(0.5, lambda f: np.log(exact.weight_function(f, "1/2")))
    for v in (6.0, 12.0, 22.0):
        x = np.array([2e-8, 1e-7, 5e-7, 0.99e-6]) * v**3
        near, near_error = distribution_near_wall(x, v, _outgoing("1/2"), 0.5)
        for xi, value, value_error in zip(x, near, near_error):
            peak_speeds = np.array([v, 0.3, 1.0, 3.0]) * np.array([1.0] + 3 * [xi ** (1 / 3)])
            rule, rule_error = distribution_by_force_rule(xi, peak_speeds, weight)
            allowed = DISTRIBUTION_NOISE * rule.max() + rule_error[0] + value_error
            assert abs(value - rule[0]) <= allowed


def test_pxv_answers_next_to_the_floor_with_the_series():
    """ExactEquilibrium.pxv (exact.distribution) at points the real-axis F integral refuses,
    among points it computes: the near-wall series there, the F integral elsewhere, all finite
    and each within its accuracy of the ray."""
    x = np.array([1e-8, 1e-9, 1e-6, 1e-3, 1e-3, 0.5])
    v = np.array([2.0, 2.0, 6.0, 40.0, -40.0, 1.0])
    values = ExactEquilibrium("1/2").pxv(x, v)
    assert list(near_wall_points(x, v)) == [True, True, True, True, False, False]
    outgoing = v > 0.0
    reference = exact.distribution_on_ray(x[outgoing], v[outgoing], "1/2")
    np.testing.assert_allclose(values[outgoing], reference, rtol=1e-12, atol=0.0)
    assert np.all(np.isfinite(values)) and np.all(values > 0.0)


def test_the_near_wall_cell_average_matches_the_exact_cell():
    """Cells above the F integral's reach at x_lo, averaged from the series, against the exact
    P(x, v) on the ray averaged by a 10 x 60 Gauss-Legendre product rule (exact to rounding for
    a function this smooth over the cell): within the series' error estimate and the ray's
    accuracy."""
    nodes_x, weights_x = np.polynomial.legendre.leggauss(10)
    nodes_v, weights_v = np.polynomial.legendre.leggauss(60)
    for x_lo, x_hi, v_lo, v_hi in ((1e-4, 2e-4, 20.0, 25.0), (1e-3, 5e-3, 60.0, 80.0)):
        value, error = distribution_near_wall_cell_average(
            x_lo, x_hi, v_lo, v_hi, _outgoing("1/2"), 0.5
        )
        xs = 0.5 * (x_lo + x_hi) + 0.5 * (x_hi - x_lo) * nodes_x
        vs = 0.5 * (v_lo + v_hi) + 0.5 * (v_hi - v_lo) * nodes_v
        grid = exact.distribution_on_ray(xs[:, None], vs[None, :], "1/2")
        reference = float(weights_x @ grid @ weights_v) / 4.0
        assert abs(value - reference) <= error + RAY_ACCURACY["1/2"] * reference
        assert ExactEquilibrium("1/2").pxv_cell_average(x_lo, x_hi, v_lo, v_hi) == pytest.approx(
            value, rel=1e-14
        )


def test_the_series_refuses_outside_its_reach_and_on_a_noisy_floor_density():
    """x beyond NEAR_WALL_REACH v^3, v <= 0, and a P(0, v) with noise of 1e-7 (far beyond the
    rounding FLOOR_NOISE the estimate assumes: its spectral derivatives then disagree between
    the interpolant and its check beyond NEAR_WALL_TOLERANCE) are refused, naming x or v."""
    with pytest.raises(ValueError, match="holds for 0 <= x <= 1e-06 v\\^3"):
        distribution_near_wall(2e-6 * 8.0, 2.0, _outgoing("1/2"), 0.5)
    with pytest.raises(ValueError, match="needs finite v > 0"):
        distribution_near_wall(1e-6, -2.0, _outgoing("1/2"), 0.5)
    generator = np.random.default_rng(1)

    def noisy(v):
        return exact.outgoing_speed_density(v, "1/2") * (
            1.0 + 1e-7 * generator.standard_normal(v.shape)
        )

    with pytest.raises(ValueError, match="at v = 20.0 the near-wall series .* use a smaller x"):
        distribution_near_wall(0.9 * NEAR_WALL_REACH * 20.0**3, 20.0, noisy, 0.5)
    with pytest.raises(ValueError, match="x_hi <= 60 x_lo"):
        ExactEquilibrium("1/2").pxv_cell_average(1e-4, 1e-2, 20.0, 25.0)


def test_the_series_holds_at_the_smallest_heights_and_speeds():
    """At x = 1e-300, v = 1e-90 (and 1e-50) the series' terms are of relative order
    x / v^3 (2 x / v^3 = 2e-30 at r = 1/2, where L P(0, .) / P(0, .) = (2 / v^2 + 1 / v) / v):
    P(x, v) is P(0, v) = e^(-v) / (3 v) to rounding, with no overflow in the coefficients."""
    for v in (1e-90, 1e-50):
        assert near_wall_points(1e-300, v)
        value = ExactEquilibrium("1/2").pxv(1e-300, v)
        assert value == pytest.approx(exact.outgoing_speed_density(v, "1/2"), rel=1e-14)
