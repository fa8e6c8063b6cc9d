/*
 * Opening a .bsdf file: parse and validate everything before anything is
 * used (style.md rule 10: hostile files are normal).
 *
 * Order of the checks: the 64-byte header first, then the size every part
 * must have, computed with overflow-checked arithmetic and compared with the
 * real size, before a single byte beyond the header is allocated or read;
 * then the contents (nodes, parameters, CDF, offset table, coefficients).
 * Every problem is LL_ERROR_FORMAT (or LL_ERROR_UNSUPPORTED for a valid
 * feature this reader does not implement) with a message naming the file
 * and the field.
 */
#include "reader/bsdf_internal.h"
#include "reader/bsdf_format.h"
#include "reader/tables_internal.h"
#include "reader/tensor.h"
#include "support/regular_file.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The header fields, decoded. */
typedef struct bsdf_header {
    unsigned version;
    uint32_t flags, n_nodes, n_coeffs, max_order, n_channels, n_bases, n_metadata;
    uint32_t n_parameters, n_parameter_values;
    float eta, alpha[2];
} bsdf_header;

/* Byte offset of each part (formats.md, "Layout"). */
typedef struct bsdf_layout {
    size_t nodes, param_counts, param_positions, cdf, table, coeffs, metadata, end;
} bsdf_layout;

/* The limits in effect (ll_open_options with the defaults filled in). */
typedef struct bsdf_limits {
    size_t max_bytes, max_order, max_nodes;
} bsdf_limits;

/* Where the coefficients and the metadata are read from: the caller's
 * memory, or the file itself (read in chunks, so that opening a file never
 * holds its bytes and their conversion to double at the same time). */
typedef struct bsdf_source {
    const unsigned char *memory; /* the whole file, or NULL            */
    int fd;                      /* else this descriptor (pread)       */
} bsdf_source;

/* LL_ERROR_FORMAT (or another status) with "ll_bsdf_open: <file>: <what>". */
static ll_status file_error(ll_status status, const char *file, const char *fmt, ...)
    LL_PRINTF(3, 4);

static ll_status file_error(ll_status status, const char *file, const char *fmt, ...)
{
    char what[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return ll_fail(status, "ll_bsdf_open: %s: %s", file, what);
}

/* ------------------------------------------------------------- header */

static void decode_header(const unsigned char *p, bsdf_header *h)
{
    h->version = p[LL_BSDF_AT_VERSION];
    h->flags = ll_le_get_u32(p + LL_BSDF_AT_FLAGS);
    h->n_nodes = ll_le_get_u32(p + LL_BSDF_AT_NODES);
    h->n_coeffs = ll_le_get_u32(p + LL_BSDF_AT_COEFFS);
    h->max_order = ll_le_get_u32(p + LL_BSDF_AT_MAX_ORDER);
    h->n_channels = ll_le_get_u32(p + LL_BSDF_AT_CHANNELS);
    h->n_bases = ll_le_get_u32(p + LL_BSDF_AT_BASES);
    h->n_metadata = ll_le_get_u32(p + LL_BSDF_AT_METADATA_BYTES);
    h->n_parameters = ll_le_get_u32(p + LL_BSDF_AT_PARAMETERS);
    h->n_parameter_values = ll_le_get_u32(p + LL_BSDF_AT_PARAMETER_VALUES);
    h->eta = ll_le_get_f32(p + LL_BSDF_AT_ETA);
    h->alpha[0] = ll_le_get_f32(p + LL_BSDF_AT_ALPHA);
    h->alpha[1] = ll_le_get_f32(p + LL_BSDF_AT_ALPHA + 4);
}

/* offset += count * unit, checked; 0 on overflow. */
static int advance(size_t *offset, size_t count, size_t unit)
{
    size_t bytes;
    return ll_size_mul(count, unit, &bytes) && ll_size_add(*offset, bytes, offset);
}

static int compute_layout(const bsdf_header *h, bsdf_layout *l)
{
    size_t n = h->n_nodes, n2, cdf_count, at = LL_BSDF_HEADER_SIZE;
    if (!ll_size_mul(n, n, &n2) || !ll_size_mul(n2, h->n_bases, &cdf_count))
        return 0;
    l->nodes = at;
    if (!advance(&at, n, 4))
        return 0;
    l->param_counts = at;
    if (!advance(&at, h->n_parameters, 4))
        return 0;
    l->param_positions = at;
    if (!advance(&at, h->n_parameter_values, 4))
        return 0;
    l->cdf = at;
    if (!advance(&at, cdf_count, 4))
        return 0;
    l->table = at;
    if (!advance(&at, n2, 8))
        return 0;
    l->coeffs = at;
    if (!advance(&at, h->n_coeffs, 4))
        return 0;
    l->metadata = at;
    if (!advance(&at, h->n_metadata, 1))
        return 0;
    l->end = at;
    return 1;
}

/* Validate the header (the first `available` bytes of p) on its own and
 * against the file's size; nothing sized by a header field is allocated
 * before this has passed. */
static ll_status check_header(const unsigned char *p, size_t available, size_t size,
                              const bsdf_limits *lim, const char *file, bsdf_header *h,
                              bsdf_layout *l)
{
    if (available < LL_BSDF_HEADER_SIZE)
        return file_error(LL_ERROR_FORMAT, file, "truncated header (%zu of %d bytes)",
                          available, LL_BSDF_HEADER_SIZE);
    if (memcmp(p, LL_BSDF_MAGIC, LL_BSDF_MAGIC_SIZE) != 0)
        return file_error(LL_ERROR_FORMAT, file,
                          "identifier is not \"SCATFUN\" (not a .bsdf file)");
    decode_header(p, h);
    if (h->version == LL_BSDF_VERSION_LAYER_LABORATORY)
        return file_error(LL_ERROR_FORMAT, file,
                          "version 2 (a Layer Laboratory file, which reuses the SCATFUN "
                          "identifier with another layout) is not supported; only version 1 is");
    if (h->version != LL_BSDF_VERSION)
        return file_error(LL_ERROR_FORMAT, file, "version %u is not supported (only 1)",
                          h->version);
    if (h->flags & ~(LL_BSDF_FLAG_BSDF | LL_BSDF_FLAG_EXTRAPOLATED))
        return file_error(LL_ERROR_FORMAT, file, "flags = 0x%x has unknown bits",
                          (unsigned)h->flags);
    if (!(h->flags & LL_BSDF_FLAG_BSDF))
        return file_error(LL_ERROR_FORMAT, file,
                          "flags = 0x%x: bit 0 (\"contains a BSDF\") is not set",
                          (unsigned)h->flags);
    if (h->flags & LL_BSDF_FLAG_EXTRAPOLATED)
        return file_error(LL_ERROR_UNSUPPORTED, file,
                          "flags = 0x%x: harmonic extrapolation is not supported",
                          (unsigned)h->flags);
    if (h->n_nodes < 2)
        return file_error(LL_ERROR_FORMAT, file, "nNodes = %u (at least 2 are needed)",
                          (unsigned)h->n_nodes);
    if (h->n_channels != 1 && h->n_channels != 3)
        return file_error(LL_ERROR_FORMAT, file, "nChannels = %u (must be 1 or 3)",
                          (unsigned)h->n_channels);
    if (h->n_bases < 1)
        return file_error(LL_ERROR_FORMAT, file, "nBases = 0 (at least 1)");
    if (h->n_parameters == 0 && h->n_parameter_values != 0)
        return file_error(LL_ERROR_FORMAT, file,
                          "nParameterValues = %u but nParameters = 0",
                          (unsigned)h->n_parameter_values);
    if (h->n_parameters == 0 && h->n_bases != 1)
        return file_error(LL_ERROR_FORMAT, file,
                          "nBases = %u but nParameters = 0 (an untextured file has 1 basis)",
                          (unsigned)h->n_bases);
    if (h->n_parameters > h->n_parameter_values)
        return file_error(LL_ERROR_FORMAT, file,
                          "nParameters = %u exceeds nParameterValues = %u",
                          (unsigned)h->n_parameters, (unsigned)h->n_parameter_values);
    if (!(h->eta >= LL_BSDF_ETA_MIN && h->eta <= LL_BSDF_ETA_MAX))
        return file_error(LL_ERROR_FORMAT, file,
                          "eta = %g is not a relative index of refraction in [%g, %g]",
                          (double)h->eta, LL_BSDF_ETA_MIN, LL_BSDF_ETA_MAX);
    if (h->max_order > h->n_coeffs)
        return file_error(LL_ERROR_FORMAT, file,
                          "nMaxOrder = %u exceeds nCoeffs = %u (no series can be that long)",
                          (unsigned)h->max_order, (unsigned)h->n_coeffs);
    if (!isfinite(h->alpha[0]) || !(h->alpha[0] >= 0.0f) || !isfinite(h->alpha[1]) ||
        !(h->alpha[1] >= 0.0f))
        return file_error(LL_ERROR_FORMAT, file,
                          "alpha = (%g, %g) (must be finite and non-negative)",
                          (double)h->alpha[0], (double)h->alpha[1]);
    if (!compute_layout(h, l))
        return file_error(LL_ERROR_FORMAT, file,
                          "the header's counts (nNodes %u, nBases %u, nParameters %u, "
                          "nParameterValues %u, nCoeffs %u, nMetadataBytes %u) overflow",
                          (unsigned)h->n_nodes, (unsigned)h->n_bases,
                          (unsigned)h->n_parameters, (unsigned)h->n_parameter_values,
                          (unsigned)h->n_coeffs, (unsigned)h->n_metadata);
    if (l->end != size)
        return file_error(LL_ERROR_FORMAT, file,
                          "%s: the header (nNodes %u, nBases %u, nParameters %u, "
                          "nParameterValues %u, nCoeffs %u, nMetadataBytes %u) describes "
                          "%zu bytes but there are %zu",
                          l->end > size ? "truncated" : "trailing bytes",
                          (unsigned)h->n_nodes, (unsigned)h->n_bases,
                          (unsigned)h->n_parameters, (unsigned)h->n_parameter_values,
                          (unsigned)h->n_coeffs, (unsigned)h->n_metadata, l->end, size);
    /* A consistent header, then the caller's limits, still before anything
     * they bound is allocated or read. */
    if (size > lim->max_bytes)
        return file_error(LL_ERROR_UNSUPPORTED, file,
                          "%zu bytes exceed the limit of %zu (ll_open_options.max_bytes)",
                          size, lim->max_bytes);
    if (h->n_nodes > lim->max_nodes)
        return file_error(LL_ERROR_UNSUPPORTED, file,
                          "nNodes = %u exceeds the limit of %zu (ll_open_options.max_nodes)",
                          (unsigned)h->n_nodes, lim->max_nodes);
    if (h->max_order > lim->max_order)
        return file_error(LL_ERROR_UNSUPPORTED, file,
                          "nMaxOrder = %u exceeds the limit of %zu (ll_open_options.max_order)",
                          (unsigned)h->max_order, lim->max_order);
    return LL_OK;
}

/* ----------------------------------------------------------- contents */

static ll_status read_nodes(ll_bsdf *b, const unsigned char *p, const char *file)
{
    size_t k, n = b->n_nodes;
    for (k = 0; k < n; ++k) {
        float x = ll_le_get_f32(p + 4 * k);
        if (!isfinite(x) || x < -1.0f || x > 1.0f)
            return file_error(LL_ERROR_FORMAT, file, "node %zu = %g is not a cosine in [-1, 1]",
                              k, (double)x);
        if (k > 0 && !(x >= b->nodes_f[k - 1]))
            return file_error(LL_ERROR_FORMAT, file,
                              "nodes are not ascending (node %zu = %g after %g)", k, (double)x,
                              (double)b->nodes_f[k - 1]);
        /* A node may repeat once (the two mu = 0 nodes), never three times,
         * and not at the ends: the spline's difference quotients divide by
         * nodes[k + 1] - nodes[k - 1] and by the width of an end interval. */
        if (k > 1 && !(x > b->nodes_f[k - 2]))
            return file_error(LL_ERROR_FORMAT, file,
                              "node %g appears three times (nodes %zu to %zu)", (double)x,
                              k - 2, k);
        b->nodes_f[k] = x;
        b->nodes[k] = x;
    }
    if (!(b->nodes_f[1] > b->nodes_f[0]) || !(b->nodes_f[n - 1] > b->nodes_f[n - 2]))
        return file_error(LL_ERROR_FORMAT, file, "the first or last two nodes coincide");
    return LL_OK;
}

static ll_status read_parameters(ll_bsdf *b, const unsigned char *counts,
                                 const unsigned char *positions, const char *file)
{
    size_t p, k, total = 0, bases = 1;
    for (p = 0; p < b->n_parameters; ++p) {
        uint32_t c = ll_le_get_u32(counts + 4 * p);
        if (c < 1)
            return file_error(LL_ERROR_FORMAT, file, "parameter %zu has 0 sample positions", p);
        b->param_counts[p] = c;
        b->param_first[p] = total;
        if (!ll_size_add(total, c, &total) || total > b->n_parameter_values)
            return file_error(LL_ERROR_FORMAT, file,
                              "the parameter sample counts exceed nParameterValues = %zu",
                              b->n_parameter_values);
        if (!ll_size_mul(bases, c, &bases) || bases > b->n_bases)
            return file_error(LL_ERROR_FORMAT, file,
                              "the product of the parameter sample counts exceeds nBases = %zu",
                              b->n_bases);
    }
    if (total != b->n_parameter_values)
        return file_error(LL_ERROR_FORMAT, file,
                          "the parameter sample counts sum to %zu, not nParameterValues = %zu",
                          total, b->n_parameter_values);
    if (bases != b->n_bases)
        return file_error(LL_ERROR_FORMAT, file,
                          "the parameter sample counts multiply to %zu, not nBases = %zu", bases,
                          b->n_bases);
    for (p = 0; p < b->n_parameters; ++p)
        for (k = 0; k < b->param_counts[p]; ++k) {
            size_t at = b->param_first[p] + k;
            float x = ll_le_get_f32(positions + 4 * at);
            if (!isfinite(x) || (k > 0 && !(x > b->param_positions[at - 1])))
                return file_error(LL_ERROR_FORMAT, file,
                                  "parameter %zu: sample position %zu = %g is not finite "
                                  "and increasing",
                                  p, k, (double)x);
            b->param_positions[at] = x;
        }
    return LL_OK;
}

/* The CDF rows as stored (finite, starting at 0, with a non-negative
 * total); their dips are checked and flattened once a_0 is known
 * (ll_bsdf_cdf_settle, bsdf_cdf.c). */
static ll_status read_cdf(ll_bsdf *b, const unsigned char *p, const char *file)
{
    size_t n = b->n_nodes, nb = b->n_bases, i, o, k;
    for (i = 0; i < n; ++i)
        for (k = 0; k < nb; ++k) {
            size_t first = i * n * nb + k;
            double total = ll_le_get_f32(p + 4 * (first + (n - 1) * nb));
            if (!isfinite(total) || !(total >= 0.0))
                return file_error(LL_ERROR_FORMAT, file,
                                  "CDF row %zu (basis %zu): the total %g (last entry) is not "
                                  "finite and non-negative",
                                  i, k, total);
            for (o = 0; o < n; ++o) {
                size_t at = first + o * nb;
                double v = ll_le_get_f32(p + 4 * at);
                if (!isfinite(v) || (o == 0 && v != 0.0))
                    return file_error(LL_ERROR_FORMAT, file,
                                      "CDF row %zu (basis %zu) entry %zu = %g: rows must start "
                                      "at 0 and be finite",
                                      i, k, o, v);
                b->cdf[at] = v;
            }
        }
    return LL_OK;
}

static ll_status read_table(ll_bsdf *b, const unsigned char *p, const char *file)
{
    size_t k, count = b->n_nodes * b->n_nodes, block_per_order, longest = 0, total = 0;
    /* Cannot overflow: n_channels * n_bases floats of CDF-sized data fit the file. */
    block_per_order = b->n_channels * b->n_bases;
    for (k = 0; k < count; ++k) {
        uint32_t offset = ll_le_get_u32(p + 8 * k), length = ll_le_get_u32(p + 8 * k + 4);
        size_t block, end;
        if (length > b->max_order)
            return file_error(LL_ERROR_FORMAT, file,
                              "offset table entry %zu (o %zu, i %zu): length %u exceeds "
                              "nMaxOrder = %zu",
                              k, k % b->n_nodes, k / b->n_nodes, (unsigned)length, b->max_order);
        if (length > 0 &&
            (!ll_size_mul(length, block_per_order, &block) || !ll_size_add(offset, block, &end) ||
             end > b->n_coeffs))
            return file_error(LL_ERROR_FORMAT, file,
                              "offset table entry %zu (o %zu, i %zu): offset %u + %u x %zu "
                              "coefficients lies outside the %zu stored",
                              k, k % b->n_nodes, k / b->n_nodes, (unsigned)offset,
                              (unsigned)length, block_per_order, b->n_coeffs);
        b->pairs[k].offset = length > 0 ? offset : 0;
        b->pairs[k].length = length;
        if (length > longest)
            longest = length;
        if (length > 0)
            total += block; /* both <= n_coeffs: no overflow */
        if (total > b->n_coeffs)
            break;
    }
    /* Writers store the blocks one after another; a table whose blocks do
     * not add up to the coefficient count was not written for this header
     * (e.g. a wrong nChannels). */
    if (total != b->n_coeffs)
        return file_error(LL_ERROR_FORMAT, file,
                          "the offset table's series hold %s%zu coefficients, but nCoeffs = %zu",
                          total > b->n_coeffs ? "more than " : "", total > b->n_coeffs ?
                          b->n_coeffs : total, b->n_coeffs);
    if (longest != b->max_order)
        return file_error(LL_ERROR_FORMAT, file,
                          "nMaxOrder = %zu but the longest series has %zu coefficients",
                          b->max_order, longest);
    return LL_OK;
}

/* Read n bytes at offset of the file into buf; 0 if the file ends first
 * or a read fails (errno says which: 0 for the end). */
static int source_read(const bsdf_source *src, size_t offset, void *buf, size_t n)
{
    unsigned char *to = buf;
    size_t done = 0;
    if (src->memory) {
        memcpy(buf, src->memory + offset, n);
        return 1;
    }
    while (done < n) {
        ssize_t r = pread(src->fd, to + done, n - done, (off_t)(offset + done));
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0) {
            if (r == 0)
                errno = 0;
            return 0;
        }
        done += (size_t)r;
    }
    return 1;
}

static ll_status read_failure(const char *file)
{
    if (errno == 0)
        return file_error(LL_ERROR_FORMAT, file, "truncated while reading (the file shrank)");
    return file_error(LL_ERROR_IO, file, "read failed: %s", strerror(errno));
}

/* Coefficients whose magnitude exceeds this are not a reflectance: with
 * it, every spline-weighted sum of them, scaled by the caller's basis
 * weights, 1 / |mu_o| (bounded, bsdf_eval.c) and eta^2, stays far inside
 * the range of double, so evaluation and sampling stay finite. 2^100
 * (1.3e30) is far beyond any reflectance a file can hold: even a mirror's
 * peak, one node's quadrature weight wide, is below 1e8 at 10^4 nodes. */
#define LL_BSDF_MAX_COEFF 1.2676506002282294e30

/* The coefficients, checked in chunks of 1024 (4 KiB read at a
 * time, so no buffer sized by the file besides b->coeffs itself). */
static ll_status read_coeffs(ll_bsdf *b, const bsdf_source *src, size_t at, const char *file)
{
    unsigned char chunk[4096];
    size_t k, j, count;
    for (k = 0; k < b->n_coeffs; k += count) {
        count = b->n_coeffs - k < sizeof chunk / 4 ? b->n_coeffs - k : sizeof chunk / 4;
        if (!source_read(src, at + 4 * k, chunk, 4 * count))
            return read_failure(file);
        for (j = 0; j < count; ++j) {
            float v = ll_le_get_f32(chunk + 4 * j);
            if (!isfinite(v) || !(fabs(v) <= LL_BSDF_MAX_COEFF))
                return file_error(LL_ERROR_FORMAT, file,
                                  "coefficient %zu is %g (not finite, or beyond the %g that "
                                  "evaluation can scale without overflow)",
                                  k + j, (double)v, LL_BSDF_MAX_COEFF);
            b->coeffs[k + j] = v;
        }
    }
    return LL_OK;
}

/* The order-0 luminance per pair and basis (what pbrt-v3 calls a0,
 * interpolated when sampling mu; the CDF rows are its running integral). */
static void derive_a0(ll_bsdf *b)
{
    size_t n = b->n_nodes, nb = b->n_bases, k, basis;
    for (k = 0; k < n * n; ++k) {
        const ll_bsdf_pair *pr = &b->pairs[k];
        for (basis = 0; basis < nb; ++basis)
            b->a0[k * nb + basis] =
                pr->length ? b->coeffs[pr->offset + basis * pr->length] : 0.0;
    }
}

/* Derived tables: the reciprocals for integrating the series in phi and
 * the spline constants. */
static void derive_tables(ll_bsdf *b)
{
    size_t k;
    for (k = 0; k < b->max_order + 4; ++k)
        b->recip[k] = (k > 0 && k < b->max_order) ? 1.0 / (double)k : 0.0;
    ll_bsdf_spline_prepare(b);
}

static ll_status allocate(ll_bsdf *b, const char *file)
{
    size_t n2 = b->n_nodes * b->n_nodes, cdf_count = n2 * b->n_bases; /* checked in layout */
    b->nodes_f = ll_alloc_array(b->n_nodes, sizeof *b->nodes_f);
    b->nodes = ll_alloc_array(b->n_nodes, sizeof *b->nodes);
    b->param_counts = ll_alloc_array(b->n_parameters, sizeof *b->param_counts);
    b->param_first = ll_alloc_array(b->n_parameters, sizeof *b->param_first);
    b->param_positions = ll_alloc_array(b->n_parameter_values, sizeof *b->param_positions);
    b->cdf = ll_alloc_array(cdf_count, sizeof *b->cdf);
    b->a0 = ll_alloc_array(cdf_count, sizeof *b->a0);
    b->pairs = ll_alloc_array(n2, sizeof *b->pairs);
    b->coeffs = ll_calloc_array(b->n_coeffs + 4, sizeof *b->coeffs);
    /* Padded so that vector loops over whole groups of 4 stay inside. */
    b->recip = ll_alloc_array(b->max_order + 4, sizeof *b->recip);
    b->metadata = ll_malloc(b->metadata_size + 1);
    b->n_buckets = 4 * b->n_nodes; /* n_nodes^2 table entries fit the file */
    b->bucket_first = ll_alloc_array(b->n_buckets, sizeof *b->bucket_first);
    b->intervals = ll_alloc_array(b->n_nodes - 1, sizeof *b->intervals);
    if (!b->nodes_f || !b->nodes || !b->param_counts || !b->param_first ||
        !b->param_positions || !b->cdf || !b->a0 || !b->pairs || !b->coeffs || !b->recip ||
        !b->metadata || !b->bucket_first || !b->intervals)
        return file_error(LL_ERROR_OUT_OF_MEMORY, file, "out of memory for a %zu-byte file",
                          b->file_size);
    return LL_OK;
}

/* Parse a file whose header (checked) and every part before the
 * coefficients are in front[0 .. l->coeffs); the coefficients and metadata
 * come from src. */
static ll_status parse_body(const unsigned char *front, const bsdf_header *h,
                            const bsdf_layout *l, const bsdf_source *src, const char *file,
                            ll_bsdf **out)
{
    ll_status s;
    ll_bsdf *b = ll_calloc(1, sizeof *b);
    if (!b)
        return file_error(LL_ERROR_OUT_OF_MEMORY, file, "out of memory");
    b->refcount = 1;
    b->n_nodes = h->n_nodes;
    b->max_order = h->max_order;
    b->n_channels = h->n_channels;
    b->n_bases = h->n_bases;
    b->n_parameters = h->n_parameters;
    b->n_parameter_values = h->n_parameter_values;
    b->n_coeffs = h->n_coeffs;
    b->file_size = l->end;
    b->flags = h->flags;
    b->eta = h->eta;
    b->alpha[0] = h->alpha[0];
    b->alpha[1] = h->alpha[1];
    b->metadata_size = h->n_metadata;

    s = allocate(b, file);
    if (s == LL_OK)
        s = read_nodes(b, front + l->nodes, file);
    if (s == LL_OK)
        s = read_parameters(b, front + l->param_counts, front + l->param_positions, file);
    if (s == LL_OK)
        s = read_cdf(b, front + l->cdf, file);
    if (s == LL_OK)
        s = read_table(b, front + l->table, file);
    if (s == LL_OK)
        s = read_coeffs(b, src, l->coeffs, file);
    if (s == LL_OK) {
        derive_a0(b);
        s = ll_bsdf_cdf_settle(b, file);
    }
    if (s == LL_OK && !source_read(src, l->metadata, b->metadata, b->metadata_size))
        s = read_failure(file);
    if (s == LL_OK && !ll_bsdf_read_parameter_names(b))
        s = file_error(LL_ERROR_OUT_OF_MEMORY, file, "out of memory (parameter names)");
    if (s != LL_OK) {
        ll_bsdf_free(b);
        return s;
    }
    derive_tables(b);
    b->metadata[b->metadata_size] = '\0';
    *out = b;
    return LL_OK;
}

/* The limits of opts (NULL: the defaults; a field of 0: its default). */
static ll_status resolve_limits(const ll_open_options *opts, const char *fn, bsdf_limits *lim)
{
    ll_open_options caller = LL_OPEN_OPTIONS_INIT;
    if (opts) {
        /* Read up to the caller's struct_size; later fields stay 0. */
        ll_status s = ll_struct_read(&caller, sizeof caller, opts, fn, "ll_open_options");
        if (s != LL_OK)
            return s;
    }
    lim->max_bytes = caller.max_bytes ? caller.max_bytes : LL_OPEN_DEFAULT_MAX_BYTES;
    lim->max_order = caller.max_order ? caller.max_order : LL_OPEN_DEFAULT_MAX_ORDER;
    lim->max_nodes = caller.max_nodes ? caller.max_nodes : LL_OPEN_DEFAULT_MAX_NODES;
    return LL_OK;
}

ll_status ll_bsdf_open_memory(const void *data, size_t size, const ll_open_options *opts,
                              ll_bsdf **out)
{
    bsdf_source src = { NULL, -1 };
    bsdf_limits lim;
    bsdf_header h;
    bsdf_layout l;
    ll_status s;
    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_open_memory: out is NULL");
    *out = NULL;
    if (!data && size > 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_open_memory: data is NULL but size is %zu", size);
    s = resolve_limits(opts, "ll_bsdf_open_memory", &lim);
    if (s != LL_OK)
        return s;
    if (!data)
        return file_error(LL_ERROR_FORMAT, "<memory>", "truncated header (0 of %d bytes)",
                          LL_BSDF_HEADER_SIZE);
    if (ll_tensor_is_tensor(data, size)) {
        if (size > lim.max_bytes)
            return file_error(LL_ERROR_UNSUPPORTED, "<memory>",
                              "%zu bytes exceed the limit max_bytes = %zu", size, lim.max_bytes);
        return ll_measured_open(data, size, "<memory>", out);
    }
    s = check_header(data, size, size, &lim, "<memory>", &h, &l);
    if (s != LL_OK)
        return s;
    src.memory = data;
    return parse_body(data, &h, &l, &src, "<memory>", out);
}

/* ---------------------------------------------------------------- files */

ll_status ll_bsdf_open(const char *path, const ll_open_options *opts, ll_bsdf **out)
{
    char file[600];
    unsigned char head[LL_BSDF_HEADER_SIZE], *front = NULL;
    bsdf_source src = { NULL, -1 };
    bsdf_limits lim;
    struct stat st;
    size_t size, got;
    bsdf_header h;
    bsdf_layout l;
    ll_status s;

    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_open: out is NULL");
    *out = NULL;
    if (!path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_open: path is NULL");
    s = resolve_limits(opts, "ll_bsdf_open", &lim);
    if (s != LL_OK)
        return s;
    snprintf(file, sizeof file, "\"%s\"", path);

    /* Never blocks: a FIFO or device is refused before any read. */
    if (ll_open_regular(path, "ll_bsdf_open:", &src.fd, &st) != LL_OK)
        return LL_ERROR_IO;
    if ((uintmax_t)st.st_size > (uintmax_t)SIZE_MAX) {
        s = file_error(LL_ERROR_FORMAT, file, "too large for this machine's address space");
        goto done;
    }
    size = (size_t)st.st_size;

    /* The header alone decides whether the file is worth reading. */
    got = size < sizeof head ? size : sizeof head;
    if (!source_read(&src, 0, head, got)) {
        s = read_failure(file);
        goto done;
    }
    /* A table file of the `measured` format, whatever the name: read
     * whole (within max_bytes) and validated from memory. */
    if (ll_tensor_is_tensor(head, got)) {
        if (size > lim.max_bytes) {
            s = file_error(LL_ERROR_UNSUPPORTED, file,
                           "%zu bytes exceed the limit max_bytes = %zu", size, lim.max_bytes);
            goto done;
        }
        front = ll_malloc(size);
        if (!front) {
            s = file_error(LL_ERROR_OUT_OF_MEMORY, file, "out of memory reading %zu bytes", size);
            goto done;
        }
        if (!source_read(&src, 0, front, size))
            s = read_failure(file);
        else
            s = ll_measured_open(front, size, file, out);
        goto done;
    }
    s = check_header(head, got, size, &lim, file, &h, &l);
    if (s != LL_OK)
        goto done;

    /* Everything up to the coefficients (nodes, parameters, CDF, offset
     * table) is parsed from memory; the coefficients are converted as they
     * are read. */
    front = ll_malloc(l.coeffs);
    if (!front) {
        s = file_error(LL_ERROR_OUT_OF_MEMORY, file, "out of memory reading %zu bytes",
                       l.coeffs);
        goto done;
    }
    memcpy(front, head, sizeof head);
    if (!source_read(&src, sizeof head, front + sizeof head, l.coeffs - sizeof head)) {
        s = read_failure(file);
        goto done;
    }
    s = parse_body(front, &h, &l, &src, file, out);
done:
    ll_free(front);
    close(src.fd);
    return s;
}
