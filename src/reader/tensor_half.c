/*
 * IEEE 754 binary16 (the container's float16, dtype LL_TENSOR_F16) to
 * and from float, bit by bit, so that a file reads the same on any
 * compiler (C99 has no half type). A textured table file stores its
 * per-basis grids so (docs/formats.md, "Textured files").
 *
 * binary16: 1 sign bit, 5 exponent bits (bias 15), 10 mantissa bits;
 * exponent 0 holds the subnormals m 2^-24, exponent 31 the infinities and
 * NaNs. Every binary16 value is a float, so the conversion to float is
 * exact; the conversion from float rounds to nearest, ties to even (the
 * rounding of IEEE 754's default mode: relative error at most 2^-11 for a
 * normal result, |v| >= 2^-14).
 */
#include "reader/tensor.h"

#include <math.h>
#include <string.h>

float ll_half_to_float(uint16_t h)
{
    uint32_t sign = (uint32_t)(h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    uint32_t bits;
    float v;
    if (e == 0) {
        /* 0 or a subnormal: m units of 2^-24, exact in a float. */
        v = ldexpf((float)m, -24);
        return sign ? -v : v;
    }
    if (e == 31)
        bits = sign | 0x7f800000u | (m << 13); /* infinity, or NaN with its payload */
    else
        bits = sign | ((e + 112u) << 23) | (m << 13); /* rebias 15 -> 127 */
    memcpy(&v, &bits, sizeof v);
    return v;
}

/* q rounded by the bits dropped (rem out of 2^shift): to nearest, ties to
 * the even q. A carry out of the mantissa moves into the exponent, which
 * is what the next binary16 value up is. */
static uint32_t round_even(uint32_t q, uint32_t rem, uint32_t shift)
{
    uint32_t halfway = 1u << (shift - 1);
    return q + (rem > halfway || (rem == halfway && (q & 1u)));
}

uint16_t ll_half_from_float(float v)
{
    uint32_t x, sign, ax, e, m;
    memcpy(&x, &v, sizeof x);
    sign = (x >> 16) & 0x8000u;
    ax = x & 0x7fffffffu;
    if (ax > 0x7f800000u)
        return (uint16_t)(sign | 0x7e00u); /* NaN (quiet) */
    /* 65520 = 65504 + half its spacing rounds (to even) to infinity. */
    if (ax >= 0x477ff000u)
        return (uint16_t)(sign | 0x7c00u);
    e = ax >> 23;
    m = ax & 0x7fffffu;
    if (e >= 113) /* 2^-14 and above: a normal binary16 */
        return (uint16_t)(sign | round_even(((e - 112u) << 10) | (m >> 13), m & 0x1fffu, 13));
    /* Below 2^-25 (and 2^-25 itself, a tie to the even 0) rounds to 0. */
    if (ax <= 0x33000000u)
        return (uint16_t)sign;
    /* A subnormal result: the float's value (m with its leading 1) in units
     * of 2^-24 is m 2^(e - 126), e = 102..112, a right shift by 14..24. */
    m |= 0x800000u;
    return (uint16_t)(sign | round_even(m >> (126u - e), m & ((1u << (126u - e)) - 1u), 126u - e));
}

float ll_half_round(float v)
{
    return ll_half_to_float(ll_half_from_float(v));
}
