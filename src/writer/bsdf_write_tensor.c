/*
 * The tensor container's writer (bsdf_write_tensor.h): the header and
 * field table first, with every offset computed in advance, then the data
 * blocks, padded with zeros to 8-byte boundaries.
 */
#include "writer/bsdf_write_tensor.h"
#include "writer/bsdf_file_out.h"
#include "reader/bsdf_format.h"

#include <string.h>

static void put_u16(ll_bsdf_out *o, size_t v)
{
    unsigned char b[2] = { (unsigned char)(v & 0xffu), (unsigned char)((v >> 8) & 0xffu) };
    ll_bsdf_out_bytes(o, b, 2);
}

static void put_u64(ll_bsdf_out *o, uint64_t v)
{
    ll_bsdf_out_u32(o, (uint32_t)(v & 0xffffffffu));
    ll_bsdf_out_u32(o, (uint32_t)(v >> 32));
}

static void pad_to(ll_bsdf_out *o, size_t *at, size_t target)
{
    static const unsigned char zeros[8] = { 0 };
    while (*at < target) {
        size_t n = target - *at > 8 ? 8 : target - *at;
        ll_bsdf_out_bytes(o, zeros, n);
        *at += n;
    }
}

/* Bytes of field f's data (0 on overflow, then *ok is cleared). */
static size_t field_bytes(const ll_tensor_out_field *f, int *ok)
{
    size_t r, count = 1, bytes;
    for (r = 0; r < f->rank; ++r)
        if (!ll_size_mul(count, f->shape[r], &count))
            *ok = 0;
    if (!ll_size_mul(count, ll_tensor_dtype_size(f->dtype), &bytes))
        *ok = 0;
    return bytes;
}

/* Elements v[0..n) of field f, elements first..first+n of it, as its
 * dtype: float32 as they are, float16 rounded (a value it cannot hold is
 * refused rather than stored as an infinity: the readers refuse those). */
static ll_status put_floats(ll_bsdf_out *o, const ll_tensor_out_field *f, const float *v,
                            size_t n, size_t first)
{
    size_t i;
    if (f->dtype == LL_TENSOR_F32) {
        for (i = 0; i < n; ++i)
            ll_bsdf_out_f32(o, v[i]);
        return LL_OK;
    }
    for (i = 0; i < n; ++i) {
        uint16_t h = ll_half_from_float(v[i]);
        if ((h & 0x7c00u) == 0x7c00u)
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "writing field \"%s\": element %zu = %g is not a finite value "
                           "within float16's range (+-65504)",
                           f->name, first + i, (double)v[i]);
        put_u16(o, h);
    }
    return LL_OK;
}

/* A filled field (data NULL): block by block, one block's buffer held. */
static ll_status fill_blocks(ll_bsdf_out *o, const ll_tensor_out_field *f)
{
    size_t block, blocks = 1, per = 1, r;
    float *buf;
    ll_status s = LL_OK;
    for (r = 0; r < f->rank; ++r) {
        if (r + 2 < f->rank)
            blocks *= f->shape[r]; /* the whole product was checked */
        else
            per *= f->shape[r];
    }
    buf = ll_alloc_array(per, sizeof *buf);
    if (!buf)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "writing field \"%s\": out of memory", f->name);
    for (block = 0; block < blocks && s == LL_OK; ++block) {
        s = f->fill(f->fill_ctx, block, buf);
        if (s == LL_OK)
            s = put_floats(o, f, buf, per, block * per);
    }
    ll_free(buf);
    return s;
}

/* ll_tensor_write with offset[n_fields] to fill. */
static ll_status write_fields(const char *path, const char *fn, const ll_tensor_out_field *fields,
                              size_t n_fields, size_t *offset)
{
    size_t k, r, at = LL_TENSOR_HEADER_SIZE, data_at;
    int ok = 1;
    ll_bsdf_out *o;
    ll_status s;
    for (k = 0; k < n_fields; ++k) {
        size_t len = strlen(fields[k].name);
        int floats = fields[k].dtype == LL_TENSOR_F32 || fields[k].dtype == LL_TENSOR_F16;
        if ((!floats && fields[k].dtype != LL_TENSOR_U8) || len == 0 ||
            len > LL_TENSOR_MAX_NAME || fields[k].rank > LL_TENSOR_MAX_RANK ||
            (!fields[k].data && (!fields[k].fill || !floats || fields[k].rank < 2)))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: field \"%s\" cannot be written", fn,
                           fields[k].name);
        at += 2 + len + 2 + 1 + 8 + 8 * fields[k].rank;
    }
    /* Offsets: each block at the next multiple of 8. */
    data_at = at;
    for (k = 0; k < n_fields; ++k) {
        size_t bytes = field_bytes(&fields[k], &ok);
        if (!ll_size_add(data_at, 7, &data_at))
            ok = 0;
        data_at &= ~(size_t)7;
        offset[k] = data_at;
        if (!ll_size_add(data_at, bytes, &data_at))
            ok = 0;
    }
    if (!ok)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the tables' size overflows", fn);

    s = ll_bsdf_out_begin(path, fn, &o);
    if (s != LL_OK)
        return s;
    ll_bsdf_out_bytes(o, LL_TENSOR_MAGIC, LL_TENSOR_MAGIC_SIZE);
    {
        const unsigned char version[2] = { 1, 0 };
        ll_bsdf_out_bytes(o, version, 2);
    }
    ll_bsdf_out_u32(o, (uint32_t)n_fields);
    for (k = 0; k < n_fields; ++k) {
        const ll_tensor_out_field *f = &fields[k];
        unsigned char dtype = (unsigned char)f->dtype;
        put_u16(o, strlen(f->name));
        ll_bsdf_out_bytes(o, f->name, strlen(f->name));
        put_u16(o, f->rank);
        ll_bsdf_out_bytes(o, &dtype, 1);
        put_u64(o, (uint64_t)offset[k]);
        for (r = 0; r < f->rank; ++r)
            put_u64(o, (uint64_t)f->shape[r]);
    }
    for (k = 0; k < n_fields; ++k) {
        const ll_tensor_out_field *f = &fields[k];
        size_t bytes = field_bytes(f, &ok);
        pad_to(o, &at, offset[k]);
        if (f->dtype == LL_TENSOR_U8)
            ll_bsdf_out_bytes(o, f->data, bytes);
        else if ((s = f->data ? put_floats(o, f, f->data, bytes / ll_tensor_dtype_size(f->dtype), 0)
                              : fill_blocks(o, f)) != LL_OK) {
            ll_bsdf_out_abort(o);
            return s;
        }
        at += bytes;
    }
    return ll_bsdf_out_commit(o);
}

ll_status ll_tensor_write(const char *path, const char *fn, const ll_tensor_out_field *fields,
                          size_t n_fields)
{
    size_t *offset;
    ll_status s;
    if (n_fields == 0 || n_fields > LL_TENSOR_MAX_FIELDS)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu fields (1..%d)", fn, n_fields,
                       LL_TENSOR_MAX_FIELDS);
    offset = ll_alloc_array(n_fields, sizeof *offset);
    if (!offset)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    s = write_fields(path, fn, fields, n_fields, offset);
    ll_free(offset);
    return s;
}
