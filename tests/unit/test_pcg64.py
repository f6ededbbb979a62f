"""The inline PCG64 draws are numpy's, bit for bit, from the same state."""

import numpy as np
import pytest

from bouncing_ball.jit import njit
from bouncing_ball.pcg64 import next_double, next_uint64, standard_normal, stream_words


@njit
def _draws(words, n, kind):
    high, low, inc_high, inc_low = words
    out = np.empty(n)
    raw = np.empty(n, dtype=np.uint64)
    for i in range(n):
        if kind == 0:
            high, low, raw[i] = next_uint64(high, low, inc_high, inc_low)
        elif kind == 1:
            high, low, out[i] = next_double(high, low, inc_high, inc_low)
        else:
            high, low, out[i] = standard_normal(high, low, inc_high, inc_low)
    return raw, out


def _generator(seed):
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed)))


def test_raw_draws_are_numpys():
    raw, _ = _draws(stream_words(_generator(3)), 10_000, 0)
    assert np.array_equal(raw, _generator(3).bit_generator.random_raw(10_000))


def test_uniforms_are_numpys():
    _, out = _draws(stream_words(_generator(4)), 10_000, 1)
    assert np.array_equal(out, _generator(4).random(10_000))


def test_normals_are_numpys_tail_and_wedges_included():
    # 10^6 normals reach the ziggurat's rare paths: the tail beyond its last layer (|z| >
    # 3.654, about 260 of them) and rejections in the wedges
    n = 1_000_000
    _, out = _draws(stream_words(_generator(5)), n, 2)
    expected = _generator(5).standard_normal(n)
    assert np.abs(expected).max() > 3.6541528853610088
    assert np.array_equal(out, expected)


def test_a_generator_with_a_cached_half_draw_is_refused():
    generator = _generator(6)
    generator.integers(0, 2**16, dtype=np.uint16)  # leaves half a 32-bit draw cached
    with pytest.raises(ValueError, match="generator"):
        stream_words(generator)
