/*
 * The .bsdf file layout ("SCATFUN" version 1; docs/formats.md),
 * shared by the writer and the reader, and explicit little-endian
 * (de)serialisation of its 32-bit fields: the file is never read or written
 * by casting a struct over bytes, so the code is independent of the host's
 * byte order and alignment.
 */
#ifndef LL_BSDF_FORMAT_H
#define LL_BSDF_FORMAT_H

#include <stdint.h>
#include <string.h>

#define LL_BSDF_MAGIC "SCATFUN"
#define LL_BSDF_MAGIC_SIZE 7
#define LL_BSDF_VERSION 1
/* The later "Layer Laboratory" writes version 2 with the same magic and a
 * different layout; it is recognised only to be refused by name. */
#define LL_BSDF_VERSION_LAYER_LABORATORY 2
#define LL_BSDF_HEADER_SIZE 64

/* Header flags. */
#define LL_BSDF_FLAG_BSDF 1u          /* the file holds a BSDF (always set)    */
#define LL_BSDF_FLAG_EXTRAPOLATED 2u  /* harmonic extrapolation, 3 coefficients */

/* Byte offsets of the header fields. */
enum {
    LL_BSDF_AT_VERSION = 7,
    LL_BSDF_AT_FLAGS = 8,
    LL_BSDF_AT_NODES = 12,
    LL_BSDF_AT_COEFFS = 16,
    LL_BSDF_AT_MAX_ORDER = 20,
    LL_BSDF_AT_CHANNELS = 24,
    LL_BSDF_AT_BASES = 28,
    LL_BSDF_AT_METADATA_BYTES = 32,
    LL_BSDF_AT_PARAMETERS = 36,
    LL_BSDF_AT_PARAMETER_VALUES = 40,
    LL_BSDF_AT_ETA = 44,
    LL_BSDF_AT_ALPHA = 48,   /* two floats: top, bottom */
    LL_BSDF_AT_UNUSED = 56   /* two floats, written as zero */
};

/* The header's eta is a relative index of refraction; values outside this
 * range are not physical and would scale radiance by eta^2 beyond reason
 * (the file is taken as damaged). */
#define LL_BSDF_ETA_MIN 1e-3
#define LL_BSDF_ETA_MAX 1e3

/* Stored colour channels: luminance first, then red and blue (the original
 * layerlab's fromLayerRGB); green is rebuilt from them when reading. */
#define LL_BSDF_Y_FROM_R 0.212671
#define LL_BSDF_Y_FROM_G 0.715160
#define LL_BSDF_Y_FROM_B 0.072169
#define LL_BSDF_G_FROM_Y 1.39829
#define LL_BSDF_G_FROM_B (-0.100913)
#define LL_BSDF_G_FROM_R (-0.297375)

static inline uint32_t ll_le_get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

static inline void ll_le_put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v & 0xffu);
    p[1] = (unsigned char)((v >> 8) & 0xffu);
    p[2] = (unsigned char)((v >> 16) & 0xffu);
    p[3] = (unsigned char)((v >> 24) & 0xffu);
}

/* IEEE-754 binary32 travels as its bit pattern (memcpy is the defined way
 * to reinterpret it). */
static inline float ll_le_get_f32(const unsigned char *p)
{
    uint32_t bits = ll_le_get_u32(p);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

static inline void ll_le_put_f32(unsigned char *p, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    ll_le_put_u32(p, bits);
}

#endif /* LL_BSDF_FORMAT_H */
