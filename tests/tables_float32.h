/*
 * A table file rewritten with its float16 grids as float32: what a file of
 * the writer held before it stored them as float16 (textured bases,
 * transmissive sets), to check that the reader takes both and reads them
 * the same. Header-only (static), for the tests that include the reader's
 * and writer's internal headers.
 */
#ifndef LL_TEST_TABLES_FLOAT32_H
#define LL_TEST_TABLES_FLOAT32_H

#include "test_util.h"
#include "reader/tensor.h"
#include "writer/bsdf_write_tensor.h"

#include <stdlib.h>
#include <string.h>

/* Rewrites the table file src as dst with every float field float32 and
 * the text fields as they are; checks that the grids (a set's or a
 * basis' vndf, luminance and rgb: the part of a field's name after its
 * first '.') are float16 in src and every other float field float32,
 * and that there are grids of them. */
static void tables_rewrite_float32(const char *src, const char *dst, size_t grids)
{
    size_t size = 0, k, e, n_grids = 0;
    unsigned char *bytes = ll_test_read_file(src, &size);
    ll_tensor_file tf;
    ll_tensor_out_field *out;
    float **decoded;
    assert_non_null(bytes);
    assert_int_equal(ll_tensor_parse(bytes, size, src, &tf), LL_OK);
    out = calloc(tf.n_fields, sizeof *out);
    decoded = calloc(tf.n_fields, sizeof *decoded);
    assert_true(out && decoded);
    for (k = 0; k < tf.n_fields; ++k) {
        const ll_tensor_field *f = &tf.fields[k];
        const char *dot = strchr(f->name, '.');
        const char *base = dot ? dot + 1 : "";
        int grid = strcmp(base, "vndf") == 0 || strcmp(base, "luminance") == 0 ||
                   strcmp(base, "rgb") == 0;
        if (f->dtype != LL_TENSOR_U8)
            assert_int_equal(f->dtype, grid ? LL_TENSOR_F16 : LL_TENSOR_F32);
        n_grids += (size_t)grid;
        out[k].name = f->name;
        out[k].dtype = f->dtype == LL_TENSOR_U8 ? LL_TENSOR_U8 : LL_TENSOR_F32;
        out[k].rank = f->rank;
        memcpy(out[k].shape, f->shape, sizeof f->shape);
        if (f->dtype == LL_TENSOR_U8) {
            out[k].data = f->data;
            continue;
        }
        decoded[k] = malloc((f->count ? f->count : 1) * sizeof(float));
        assert_non_null(decoded[k]);
        for (e = 0; e < f->count; ++e)
            decoded[k][e] = ll_tensor_value(f, e);
        out[k].data = decoded[k];
    }
    assert_int_equal(n_grids, grids);
    assert_int_equal(ll_tensor_write(dst, "test", out, tf.n_fields), LL_OK);
    for (k = 0; k < tf.n_fields; ++k)
        free(decoded[k]);
    free(decoded);
    free(out);
    ll_tensor_file_free(&tf);
    free(bytes);
}

#endif /* LL_TEST_TABLES_FLOAT32_H */
