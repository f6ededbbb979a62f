"""The Airy function of eq. (psi) (bouncing_ball.airy): the Maclaurin and asymptotic series of
``scaled_airy_ai`` against scipy's airye (AMOS), an independent implementation.  Against mpmath
at 30 digits the series are within 1e-15 and airye within 4e-15 in these regions (measured
once; mpmath is not a dependency), so the two are held to 5e-15 of each other."""

import numpy as np
import pytest
from scipy import special

from bouncing_ball.airy import ASYMPTOTIC_AIRY, SERIES_AIRY, scaled_airy_ai


@pytest.mark.parametrize(
    ("lo", "hi"),
    [(1e-20, 1e-3), (1e-3, SERIES_AIRY), (ASYMPTOTIC_AIRY, 13.0), (13.0, 100.0), (100.0, 1e5)],
)
def test_the_series_match_scipys_airye_where_they_are_used(lo, hi):
    generator = np.random.default_rng(7)
    size = np.exp(generator.uniform(np.log(lo), np.log(hi), 2000))
    angle = generator.uniform(-2.0 * np.pi / 3.0, 2.0 * np.pi / 3.0, 2000)
    z = size * np.exp(1j * angle)
    np.testing.assert_allclose(scaled_airy_ai(z), special.airye(z)[0], rtol=5e-15, atol=0.0)
    real = size[size < 1e5]
    np.testing.assert_allclose(scaled_airy_ai(real), special.airye(real)[0], rtol=5e-15, atol=0.0)


def test_real_arguments_stay_real_and_the_far_tail_is_finite():
    """Where scipy's airye gives NaN (beyond 1e6) the asymptotic series still answers:
    z^(-1/4) / (2 pi^(1/2)) to its first correction, 5 / (48 z^(3/2)), at z = 1e7."""
    values = scaled_airy_ai(np.array([0.0, 0.5, 30.0, 1e7]))
    assert values.dtype == np.float64 and np.all(np.isfinite(values))
    assert values[0] == pytest.approx(special.airy(0.0)[0], rel=1e-15)
    leading = 1e7**-0.25 / (2.0 * np.sqrt(np.pi)) * (1.0 - 5.0 / (48.0 * 1e7**1.5))
    assert values[-1] == pytest.approx(leading, rel=1e-15)
