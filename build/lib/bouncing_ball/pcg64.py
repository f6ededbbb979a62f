"""numpy's PCG64 stream, drawn inline in compiled code: the same numbers, no calls.

The shard loop draws its normals and uniforms from numpy's ``Generator(PCG64(...))``.
numba draws those through the bit generator's function pointer, a call the compiler
cannot see into, so every float the loop keeps in registers is saved and restored
around each draw.  Here the generator's 128-bit state is two uint64 words the loop
carries as local variables, advanced by ``next_uint64`` (inlined LLVM on 128-bit
integers), and ``standard_normal`` and ``next_double`` are numpy's own algorithms on
it (its ziggurat, ``random_standard_normal``, and 53-bit doubles), so each draw is bit
for bit the one ``Generator.standard_normal`` and ``Generator.random`` give from the
same state (tests/unit/test_pcg64.py).

PCG64 (O'Neill's PCG XSL RR 128/64, numpy's layout): the state s and the odd increment
inc are 128-bit; a draw sets s = s * MULTIPLIER + inc (mod 2^128) and returns the
64-bit xor of the new state's halves rotated right by its top 6 bits.
"""

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic
from numba.np.random._constants import (
    fi_double,
    ki_double,
    wi_double,
    ziggurat_nor_inv_r,
    ziggurat_nor_r,
)

from .jit import njit

__all__ = ["MULTIPLIER", "stream_words", "next_uint64", "next_double", "standard_normal"]

MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645  # PCG's default 128-bit multiplier
_WORD = (1 << 64) - 1
_TO_DOUBLE = 1.0 / 9007199254740992.0  # 2^-53
_LOW_BYTE = np.uint64(0xFF)
_ABSCISSA = np.uint64(0x000FFFFFFFFFFFFF)


def stream_words(generator: np.random.Generator):
    """The state of a fresh PCG64 ``generator`` as four uint64 words.

    Parameters
    ----------
    generator : numpy.random.Generator
        On a ``numpy.random.PCG64`` bit generator, with no cached 32-bit half-draw (a
        generator that has only drawn 64-bit numbers, as the shard loop's).

    Returns
    -------
    tuple of numpy.uint64
        (state high, state low, increment high, increment low): the arguments of
        ``next_uint64``.

    Examples
    --------
    The first normal drawn inline (``standard_normal`` compiles on this first call) is the
    generator's own first normal:

    >>> import numpy as np
    >>> from bouncing_ball.pcg64 import standard_normal, stream_words
    >>> generator = np.random.Generator(np.random.PCG64(7))
    >>> high, low, z = standard_normal(*stream_words(generator))
    >>> z == generator.standard_normal()
    True
    """
    state = generator.bit_generator.state
    if state["bit_generator"] != "PCG64" or state["has_uint32"]:
        raise ValueError(
            f"generator: a PCG64 Generator with no cached 32-bit draw, got {state['bit_generator']}"
        )
    s, inc = state["state"]["state"], state["state"]["inc"]
    return (np.uint64(s >> 64), np.uint64(s & _WORD), np.uint64(inc >> 64), np.uint64(inc & _WORD))


@intrinsic
def next_uint64(typingctx, high, low, inc_high, inc_low):
    """One PCG64 draw: the state advanced once and its 64-bit output.

    Parameters
    ----------
    high, low : numpy.uint64
        The generator's 128-bit state, its upper and lower word.
    inc_high, inc_low : numpy.uint64
        Its odd 128-bit increment, upper and lower word (fixed for a stream).

    Returns
    -------
    tuple of numpy.uint64
        (new state high, new state low, the 64-bit output), as numpy's PCG64 gives them.
    """
    signature = types.UniTuple(types.uint64, 3)(
        types.uint64, types.uint64, types.uint64, types.uint64
    )

    def codegen(context, builder, sig, args):
        word, double_word = ir.IntType(64), ir.IntType(128)
        shift = ir.Constant(double_word, 64)

        def joined(high, low):
            return builder.or_(
                builder.shl(builder.zext(high, double_word), shift),
                builder.zext(low, double_word),
            )

        state = builder.add(
            builder.mul(joined(args[0], args[1]), ir.Constant(double_word, MULTIPLIER)),
            joined(args[2], args[3]),
        )
        new_high = builder.trunc(builder.lshr(state, shift), word)
        new_low = builder.trunc(state, word)
        rotation = builder.lshr(new_high, ir.Constant(word, 58))
        mixed = builder.xor(new_high, new_low)
        back = builder.and_(builder.sub(ir.Constant(word, 64), rotation), ir.Constant(word, 63))
        output = builder.or_(builder.lshr(mixed, rotation), builder.shl(mixed, back))
        return context.make_tuple(builder, sig.return_type, [new_high, new_low, output])

    return signature, codegen


@njit(cache=True, inline="always")
def next_double(high, low, inc_high, inc_low):
    """A uniform double in [0, 1), numpy's ``Generator.random`` (53 bits of one draw).

    Parameters
    ----------
    high, low : numpy.uint64
        The generator's 128-bit state, its upper and lower word.
    inc_high, inc_low : numpy.uint64
        Its odd 128-bit increment, upper and lower word (fixed for a stream).

    Returns
    -------
    tuple
        (new state high, new state low, u).
    """
    high, low, bits = next_uint64(high, low, inc_high, inc_low)
    return high, low, (bits >> np.uint64(11)) * _TO_DOUBLE


@njit(cache=True, inline="always")
def _ziggurat_layer(high, low, inc_high, inc_low):
    """One draw of the ziggurat: its layer ``idx``, the bits ``rabs`` (bit 8 of them the tail's
    sign) and the candidate ``x``, accepted where ``rabs < ki_double[idx]``."""
    high, low, r = next_uint64(high, low, inc_high, inc_low)
    idx = r & _LOW_BYTE
    r >>= np.uint64(8)
    rabs = (r >> np.uint64(1)) & _ABSCISSA
    x = rabs * wi_double[idx]
    if r & np.uint64(1):
        x = -x
    return high, low, idx, rabs, x


@njit(cache=True)
def _normal_rejected(high, low, inc_high, inc_low, idx, rabs, x):
    """The rare part of ``standard_normal``: the tail (idx 0) or the wedge test, then fresh
    draws until one is accepted (numpy's ``random_standard_normal``)."""
    while True:
        if idx == 0:
            while True:
                high, low, u = next_double(high, low, inc_high, inc_low)
                xx = -ziggurat_nor_inv_r * np.log1p(-u)
                high, low, u = next_double(high, low, inc_high, inc_low)
                yy = -np.log1p(-u)
                if yy + yy > xx * xx:
                    if (rabs >> np.uint64(8)) & np.uint64(1):
                        return high, low, -(ziggurat_nor_r + xx)
                    return high, low, ziggurat_nor_r + xx
        else:
            high, low, u = next_double(high, low, inc_high, inc_low)
            if (fi_double[idx - 1] - fi_double[idx]) * u + fi_double[idx] < np.exp(-0.5 * x * x):
                return high, low, x
        high, low, idx, rabs, x = _ziggurat_layer(high, low, inc_high, inc_low)
        if rabs < ki_double[idx]:
            return high, low, x


@njit(cache=True, inline="always")
def standard_normal(high, low, inc_high, inc_low):
    """A standard normal, numpy's ziggurat (``Generator.standard_normal``), bit for bit.

    Parameters
    ----------
    high, low : numpy.uint64
        The generator's 128-bit state, its upper and lower word.
    inc_high, inc_low : numpy.uint64
        Its odd 128-bit increment, upper and lower word (fixed for a stream).

    Returns
    -------
    tuple
        (new state high, new state low, z).
    """
    high, low, idx, rabs, x = _ziggurat_layer(high, low, inc_high, inc_low)
    if rabs < ki_double[idx]:
        return high, low, x
    return _normal_rejected(high, low, inc_high, inc_low, idx, rabs, x)
