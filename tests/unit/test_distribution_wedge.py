"""The interpolant of P(0, v) e^(q v) in the wedge 0 <= arg v <= THETA_MAX
(distribution._OutgoingDensity.scaled_complex) against the Nystrom sums it is built from, and the
scalar fast path of WeightFunction.log against the array one."""

import numpy as np
import pytest
from distribution_support import build

from bouncing_ball import distribution


@pytest.mark.parametrize("r", [0.25, 0.75])
def test_wedge_interpolant_matches_the_nystrom_sums(r):
    """At random v in the wedge, 1e-3 <= |v| <= 100, the interpolated P(0, v) e^(q v) equals the
    direct Nystrom sum to 1e-11 relative (the sums' own rounding is ~1e-14 there), and its
    rounding-error bound is at least the direct sum's."""
    solution = distribution.outgoing_speed_solution(r)
    density = distribution._outgoing_density(solution)
    rng = np.random.default_rng(7)
    v = np.exp(rng.uniform(np.log(1e-3), np.log(100.0), 60)) * np.exp(
        1j * rng.uniform(0.0, distribution.THETA_MAX, 60)
    )
    value, magnitude = density.scaled_complex(v)
    direct, direct_magnitude = density.scaled_complex_direct(v)
    assert any(cell is not None for cell in density.cells.values())  # interpolated, not summed
    assert np.max(np.abs(value / direct - 1.0)) < 1e-11
    assert np.all(magnitude >= 0.5 * direct_magnitude)


def test_wedge_cells_where_the_sums_cancel_are_not_interpolated():
    """At r = 0.9, |v| = 600, arg v = THETA_MAX the Nystrom sum cancels by more than WEDGE_CLEAN:
    that v is summed directly (its value and bound are the direct ones)."""
    solution = distribution.outgoing_speed_solution(0.9)
    density = distribution._outgoing_density(solution)
    v = np.array([min(600.0, 0.9 * density.largest) * np.exp(1j * distribution.THETA_MAX)])
    direct, direct_magnitude = density.scaled_complex_direct(v)
    assert direct_magnitude[0] > distribution.WEDGE_CLEAN * abs(direct[0])
    value, magnitude = density.scaled_complex(v)
    assert value[0] == direct[0] and magnitude[0] == direct_magnitude[0]


def test_scalar_log_weight_equals_the_array_one():
    """WeightFunction.log_scalar (used by the F integrals of eq. (fpsol)) equals WeightFunction.log
    below F_min, inside, and above F_max."""
    _, weight = build(0.5)
    forces = np.concatenate(
        [
            np.geomspace(weight.smallest_force / 10.0, weight.smallest_force, 4, endpoint=False),
            np.geomspace(weight.smallest_force, weight.largest_force, 9),
            np.geomspace(weight.largest_force * 1.01, 1e20, 4),
        ]
    )
    scalar = np.array([weight.log_scalar(float(f)) for f in forces])
    assert np.max(np.abs(scalar - weight.log(forces))) < 1e-12
