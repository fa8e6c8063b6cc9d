/*
 * Writing the tensor container of the `measured` format
 * (docs/formats.md) atomically, through the .bsdf writer's
 * temporary-file-and-rename output (bsdf_file_out.h). Writer side only.
 */
#ifndef LL_BSDF_WRITE_TENSOR_H
#define LL_BSDF_WRITE_TENSOR_H

#include "reader/tensor.h"

/* One field to write: float32 or float16 data as floats (a float16
 * field's rounded to nearest binary16, each a finite value within its
 * range, +-65504), uint8 data as bytes (the only dtypes the format's
 * producers need). */
typedef struct ll_tensor_out_field {
    const char *name;
    int dtype;                          /* LL_TENSOR_F32, _F16 or _U8    */
    size_t rank;
    size_t shape[LL_TENSOR_MAX_RANK];
    const void *data;                   /* count elements, or NULL: fill */
    /* A float field too large to hold (data NULL): its elements in
     * blocks of the last two extents' product, block b (row-major over the
     * leading extents) written into out by fill(fill_ctx, b, out). */
    ll_status (*fill)(void *fill_ctx, size_t block, float *out);
    void *fill_ctx;
} ll_tensor_out_field;

/* Write the fields in the given order, each data block at an offset
 * rounded up to a multiple of 8 (as the format's Python writers do).
 * fn names the caller in messages. LL_ERROR_IO, LL_ERROR_INVALID_ARGUMENT
 * (a dtype other than the three, a size that overflows, a float16 field's
 * value that is not finite or beyond its range, named with the field). */
LL_INTERNAL ll_status ll_tensor_write(const char *path, const char *fn,
                                      const ll_tensor_out_field *fields, size_t n_fields);

#endif /* LL_BSDF_WRITE_TENSOR_H */
