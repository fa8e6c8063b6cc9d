/*
 * Parsing the tensor container (tensor.h, docs/formats.md), byte by
 * byte in little-endian order (style.md rule 10). Every count, extent and
 * offset of the field table is checked against the real size of the file,
 * with overflow-checked arithmetic, before the one allocation sized by the
 * field count (itself bounded by what the table's bytes can hold).
 */
#include "reader/tensor.h"

#include <string.h>

static uint16_t get_u16(const unsigned char *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

static uint32_t get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

static uint64_t get_u64(const unsigned char *p)
{
    return (uint64_t)get_u32(p) | ((uint64_t)get_u32(p + 4) << 32);
}

int ll_tensor_is_tensor(const void *data, size_t size)
{
    return data && size >= LL_TENSOR_MAGIC_SIZE &&
           memcmp(data, LL_TENSOR_MAGIC, LL_TENSOR_MAGIC_SIZE) == 0;
}

size_t ll_tensor_dtype_size(int dtype)
{
    switch (dtype) {
    case LL_TENSOR_U8: case LL_TENSOR_I8: return 1;
    case LL_TENSOR_U16: case LL_TENSOR_I16: case LL_TENSOR_F16: return 2;
    case LL_TENSOR_U32: case LL_TENSOR_I32: case LL_TENSOR_F32: return 4;
    case LL_TENSOR_U64: case LL_TENSOR_I64: case LL_TENSOR_F64: return 8;
    default: return 0;
    }
}

float ll_tensor_f32(const ll_tensor_field *f, size_t i)
{
    uint32_t bits = get_u32(f->data + 4 * i);
    float v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

float ll_tensor_value(const ll_tensor_field *f, size_t i)
{
    if (f->dtype == LL_TENSOR_F16)
        return ll_half_to_float(get_u16(f->data + 2 * i));
    return ll_tensor_f32(f, i);
}

void ll_tensor_file_free(ll_tensor_file *t)
{
    if (!t)
        return;
    ll_free(t->fields);
    t->fields = NULL;
    t->n_fields = 0;
}

const ll_tensor_field *ll_tensor_find(const ll_tensor_file *t, const char *name)
{
    size_t k;
    for (k = 0; k < t->n_fields; ++k)
        if (strcmp(t->fields[k].name, name) == 0)
            return &t->fields[k];
    return NULL;
}

#define FAIL(...) do { s = ll_fail(LL_ERROR_FORMAT, __VA_ARGS__); goto fail; } while (0)

/* Entry k of the field table at *at (advanced past it). */
static ll_status parse_entry(const unsigned char *data, size_t size, size_t *at, size_t k,
                             const char *file, ll_tensor_field *f)
{
    size_t pos = *at, name_len, r, end;
    uint64_t offset;
    ll_status s = LL_OK;
    if (size - pos < 2)
        FAIL("ll_bsdf_open: %s: field table entry %zu: truncated (name length)", file, k);
    name_len = get_u16(data + pos);
    pos += 2;
    if (name_len == 0 || name_len > LL_TENSOR_MAX_NAME)
        FAIL("ll_bsdf_open: %s: field table entry %zu: name length %zu outside 1..%d", file, k,
             name_len, LL_TENSOR_MAX_NAME);
    /* name, rank (2), dtype (1), offset (8) */
    if (size - pos < name_len + 11)
        FAIL("ll_bsdf_open: %s: field table entry %zu: truncated", file, k);
    memcpy(f->name, data + pos, name_len);
    f->name[name_len] = '\0';
    if (memchr(f->name, '\0', name_len))
        FAIL("ll_bsdf_open: %s: field table entry %zu: the name holds a NUL byte", file, k);
    pos += name_len;
    f->rank = get_u16(data + pos);
    f->dtype = data[pos + 2];
    offset = get_u64(data + pos + 3);
    pos += 11;
    if (f->rank > LL_TENSOR_MAX_RANK)
        FAIL("ll_bsdf_open: %s: field \"%s\": rank %zu above %d", file, f->name, f->rank,
             LL_TENSOR_MAX_RANK);
    if (ll_tensor_dtype_size(f->dtype) == 0)
        FAIL("ll_bsdf_open: %s: field \"%s\": unknown dtype code %d", file, f->name, f->dtype);
    if ((size - pos) / 8 < f->rank)
        FAIL("ll_bsdf_open: %s: field \"%s\": truncated (shape)", file, f->name);
    f->count = 1;
    for (r = 0; r < f->rank; ++r) {
        uint64_t e = get_u64(data + pos + 8 * r);
        if (e > (uint64_t)SIZE_MAX || !ll_size_mul(f->count, (size_t)e, &f->count))
            FAIL("ll_bsdf_open: %s: field \"%s\": shape overflows (extent %zu = %llu)", file,
                 f->name, r, (unsigned long long)e);
        f->shape[r] = (size_t)e;
    }
    pos += 8 * f->rank;
    if (!ll_size_mul(f->count, ll_tensor_dtype_size(f->dtype), &f->bytes) ||
        offset > (uint64_t)size || !ll_size_add((size_t)offset, f->bytes, &end) || end > size)
        FAIL("ll_bsdf_open: %s: field \"%s\": data at offset %llu (%zu elements) lies outside "
             "the file (%zu bytes)",
             file, f->name, (unsigned long long)offset, f->count, size);
    f->offset = (size_t)offset;
    f->data = data + f->offset;
    *at = pos;
fail:
    return s;
}

ll_status ll_tensor_parse(const unsigned char *data, size_t size, const char *file,
                          ll_tensor_file *out)
{
    ll_tensor_file t = { 0, NULL };
    size_t at = LL_TENSOR_HEADER_SIZE, k, j;
    uint32_t n;
    ll_status s = LL_OK;
    out->n_fields = 0;
    out->fields = NULL;
    if (!ll_tensor_is_tensor(data, size))
        FAIL("ll_bsdf_open: %s: not a tensor file (magic)", file);
    if (size < LL_TENSOR_HEADER_SIZE)
        FAIL("ll_bsdf_open: %s: truncated header (%zu of %d bytes)", file, size,
             LL_TENSOR_HEADER_SIZE);
    if (data[12] != 1 || data[13] != 0)
        FAIL("ll_bsdf_open: %s: tensor file version %u.%u (this reader reads 1.0)", file,
             (unsigned)data[12], (unsigned)data[13]);
    n = get_u32(data + 14);
    /* The smallest entry takes 14 bytes (a 1-byte name, rank 0). */
    if (n == 0 || n > LL_TENSOR_MAX_FIELDS || (size_t)n > (size - at) / 14)
        FAIL("ll_bsdf_open: %s: field count %lu does not fit the file (1..%d fields, %zu bytes)",
             file, (unsigned long)n, LL_TENSOR_MAX_FIELDS, size);
    t.fields = ll_calloc_array(n, sizeof *t.fields);
    if (!t.fields) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory (field table)", file);
        goto fail;
    }
    for (k = 0; k < n; ++k) {
        s = parse_entry(data, size, &at, k, file, &t.fields[k]);
        if (s != LL_OK)
            goto fail;
        for (j = 0; j < k; ++j)
            if (strcmp(t.fields[j].name, t.fields[k].name) == 0)
                FAIL("ll_bsdf_open: %s: field \"%s\" appears twice", file, t.fields[k].name);
        t.n_fields = k + 1;
    }
    /* Data blocks may not overlap the header or the field table. */
    for (k = 0; k < n; ++k)
        if (t.fields[k].bytes > 0 && t.fields[k].offset < at)
            FAIL("ll_bsdf_open: %s: field \"%s\": data at offset %zu overlaps the field table "
                 "(which ends at %zu)",
                 file, t.fields[k].name, t.fields[k].offset, at);
    *out = t;
    return LL_OK;
fail:
    ll_free(t.fields);
    return s;
}
