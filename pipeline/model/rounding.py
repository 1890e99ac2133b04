"""The next double below and above each value (``pipeline.model.intervals.down`` and ``up``):
numpy's ``nextafter`` towards -inf and +inf bit for bit, as one compiled pass over the values'
IEEE 754 bit patterns (numba, ``SIGNATURES``, cached: ``pipeline.model.jit.compiled_loops``),
where numpy calls the C library once per value (a twelfth of the time at the paving's arrays of
thousands; benchmarks/LOG.md, 2026-11-30).

Read as signed 64-bit integers, the patterns of the positive doubles increase with their values
and those of the negative ones decrease with them: the next double below a positive x is the
pattern b - 1 (below +inf: the largest double), below a negative one b + 1 (below -0: the
smallest negative subnormal, as below +0); -inf and NaN stay. Above: the mirror.
"""

from __future__ import annotations

from numba import njit

MAGNITUDE = 0x7FFFFFFFFFFFFFFF  # every bit but the sign
POS_INF = 0x7FF0000000000000  # +inf's pattern; a larger magnitude is a NaN
NEG_INF = -0x10000000000000  # -inf's pattern, as a signed integer
NEG_ZERO = -0x8000000000000000
NEG_TINY = -0x7FFFFFFFFFFFFFFF  # -5e-324
SIGNATURES = {"step": "void(i8[::1], i8[::1], b1)"}


@njit(SIGNATURES["step"], cache=True, nogil=True)
def step(bits, out, upward):
    """out[i]: the pattern of the next double above (``upward``) or below the one of pattern
    bits[i]."""
    stays = POS_INF if upward else NEG_INF
    for i in range(bits.size):
        b = bits[i]
        if (b & MAGNITUDE) > POS_INF or b == stays:
            out[i] = b
        elif b == 0 or b == NEG_ZERO:
            out[i] = 1 if upward else NEG_TINY
        elif (b > 0) == upward:  # away from zero
            out[i] = b + 1
        else:
            out[i] = b - 1
