"""Elementwise independence of the public methods of Equilibrium and ExactEquilibrium: the value
at one argument does not depend on the other arguments of the same call, over the whole domain
(arguments spread over 600 decades, zeros and the extremes of float included).

Each method is called on a whole array and on each of its elements alone. Either the array call
is refused (ValueError) and so is some element alone, or each element of the array's answer
equals the element's own answer. A value is never NaN, and inf only where the method's docstring
says the exact value is infinite (a zero argument of p0v, px, pxv and the flight-time densities).
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bouncing_ball as bb

# The same arithmetic on one element, in an array or alone: numpy's elementwise functions may
# take another (SIMD) path for a lone element, which changes the last bits, never more than a
# few ulps through the steps of one evaluation.
RELATIVE = 1e-12

EXAMPLES = settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
    derandomize=True,
)

# magnitudes from the smallest subnormal to the largest float, and the values at the ends
MAGNITUDES = st.one_of(
    st.floats(min_value=-323.0, max_value=308.0).map(lambda e: 10.0**e),
    st.sampled_from([0.0, 5e-324, 2.2250738585072014e-308, 1.0, 1.7976931348623157e308]),
)
SIGNED = st.one_of(MAGNITUDES, MAGNITUDES.map(lambda value: -value))
ARRAYS = st.lists(MAGNITUDES, min_size=2, max_size=6)
PAIRS = st.lists(st.tuples(MAGNITUDES, SIGNED), min_size=2, max_size=6)

# method -> the arguments at which the docstring promises inf
ONE_ARGUMENT = {
    "p0v": lambda v: v == 0.0,
    "px": lambda x: x == 0.0,
    "v2_given_x": lambda x: np.zeros_like(x, dtype=bool),
    "weight": lambda F: np.zeros_like(F, dtype=bool),
    "flight_rate_density": lambda T: T == 0.0,
    "flight_time_density": lambda T: T == 0.0,
}
TWO_ARGUMENTS = {
    "pxv": lambda x, v: (x == 0.0) & (v == 0.0),
    "return_speed_density": lambda v, u: np.zeros_like(v, dtype=bool),
}


@pytest.fixture(scope="module", params=["solver", "exact"])
def equilibrium(request):
    """r = 1/2, from the solver and exactly (w(F) built once per process)."""
    return bb.Equilibrium("1/2") if request.param == "solver" else bb.ExactEquilibrium("1/2")


def _call(method, *arguments):
    """The method's answer as an array, or None where it refuses."""
    try:
        return np.asarray(method(*arguments), dtype=float)
    except ValueError:
        return None


def _assert_independent(method, infinite, arrays):
    whole = _call(method, *arrays)
    alone = [_call(method, *(array[i] for array in arrays)) for i in range(len(arrays[0]))]
    if whole is None:
        assert any(value is None for value in alone), "refused an array of valid elements"
        return
    assert all(value is not None for value in alone), "refused an element it answers in an array"
    alone = np.array([float(value) for value in alone])
    assert not np.isnan(whole).any()
    np.testing.assert_array_equal(np.isinf(whole), infinite(*arrays))
    finite = np.isfinite(whole)
    np.testing.assert_allclose(whole[finite], alone[finite], rtol=RELATIVE, atol=0.0)
    np.testing.assert_array_equal(np.isinf(alone), np.isinf(whole))


@pytest.mark.parametrize("name", sorted(ONE_ARGUMENT))
@EXAMPLES
@given(values=ARRAYS)
def test_one_value_never_changes_another(equilibrium, name, values):
    if name in ("weight",):
        values = [value for value in values if value > 0.0] or [1.0, 2.0]
    array = np.array(values)
    _assert_independent(getattr(equilibrium, name), ONE_ARGUMENT[name], (array,))


@pytest.mark.parametrize("name", sorted(TWO_ARGUMENTS))
@EXAMPLES
@given(pairs=PAIRS)
def test_one_pair_never_changes_another(equilibrium, name, pairs):
    first = np.array([pair[0] for pair in pairs])
    second = np.array([pair[1] for pair in pairs])
    if name == "return_speed_density":  # (v >= 0, u > 0)
        first, second = first, np.abs(second)
        second[second == 0.0] = 1.0
    _assert_independent(getattr(equilibrium, name), TWO_ARGUMENTS[name], (first, second))
