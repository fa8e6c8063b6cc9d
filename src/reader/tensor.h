/*
 * The tensor container of the `measured` BRDF format (docs/formats.md):
 * a little-endian file of named, typed, dense arrays. Reader side: parsing
 * validates the whole field table against the real size before anything it
 * sizes is allocated; the fields then point into the caller's bytes.
 */
#ifndef LL_TENSOR_H
#define LL_TENSOR_H

#include "support/support.h"

/* "tensor_file" and its NUL, then version 1.0. */
#define LL_TENSOR_MAGIC "tensor_file"
#define LL_TENSOR_MAGIC_SIZE 12
#define LL_TENSOR_HEADER_SIZE 18 /* magic, 2 version bytes, uint32 field count */

/* dtype codes of the format. */
enum {
    LL_TENSOR_U8 = 1, LL_TENSOR_I8, LL_TENSOR_U16, LL_TENSOR_I16, LL_TENSOR_U32,
    LL_TENSOR_I32, LL_TENSOR_U64, LL_TENSOR_I64, LL_TENSOR_F16, LL_TENSOR_F32, LL_TENSOR_F64
};

/* Ranks and name lengths beyond these are refused (the format itself
 * allows 65535 of each; no file of the format uses more than 5 and a few
 * dozen bytes), which keeps a field's description fixed-size. */
#define LL_TENSOR_MAX_RANK 8
#define LL_TENSOR_MAX_NAME 255
/* Fields a file may have (the format's files have about ten; a textured
 * table file ten per basis, up to 1024 bases). */
#define LL_TENSOR_MAX_FIELDS 16384

typedef struct ll_tensor_field {
    char name[LL_TENSOR_MAX_NAME + 1];
    int dtype;
    size_t rank;
    size_t shape[LL_TENSOR_MAX_RANK];
    size_t count;                /* product of the shape                     */
    size_t offset;               /* absolute, inside the file                */
    size_t bytes;                /* count * element size, inside the file    */
    const unsigned char *data;   /* the file's bytes at offset               */
} ll_tensor_field;

typedef struct ll_tensor_file {
    size_t n_fields;
    ll_tensor_field *fields;     /* owned: ll_tensor_file_free               */
} ll_tensor_file;

/* 1 if the bytes start with the container's magic. */
LL_INTERNAL int ll_tensor_is_tensor(const void *data, size_t size);

/* Bytes of one element of dtype (0 for an unknown code). */
LL_INTERNAL size_t ll_tensor_dtype_size(int dtype);

/* Parse the header and field table of data[0 .. size): magic, version 1.0,
 * field count, every entry (name length, rank, dtype, offset, extents with
 * overflow-checked products), every data block inside the file, names
 * unique. file names the source in messages ("ll_bsdf_open: <file>: ...").
 * LL_ERROR_FORMAT naming the field; LL_ERROR_OUT_OF_MEMORY. */
LL_INTERNAL ll_status ll_tensor_parse(const unsigned char *data, size_t size, const char *file,
                                      ll_tensor_file *out);
LL_INTERNAL void ll_tensor_file_free(ll_tensor_file *t);

/* The field called name, or NULL. */
LL_INTERNAL const ll_tensor_field *ll_tensor_find(const ll_tensor_file *t, const char *name);

/* Element i of a float32 field, decoded from little-endian bytes. */
LL_INTERNAL float ll_tensor_f32(const ll_tensor_field *f, size_t i);

/* Element i of a float32 or float16 field, as a float. */
LL_INTERNAL float ll_tensor_value(const ll_tensor_field *f, size_t i);

/* IEEE 754 binary16 (tensor_half.c): to float (exact), from float
 * (round to nearest, ties to even; from 65520 on an infinity, NaN a
 * NaN), and v rounded to the nearest binary16 as a float. */
LL_INTERNAL float ll_half_to_float(uint16_t h);
LL_INTERNAL uint16_t ll_half_from_float(float v);
LL_INTERNAL float ll_half_round(float v);
/* The largest finite binary16. */
#define LL_HALF_MAX 65504.0f

#endif /* LL_TENSOR_H */
