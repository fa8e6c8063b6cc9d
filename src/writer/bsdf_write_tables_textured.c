/*
 * ll_tables_write_from_bsdf for a textured file: a table set per basis in
 * one extended container (reader/tables_textured.c describes its fields).
 * Each basis is made into an untextured handle (ll_tables_basis_view) and
 * written by the untextured writer, with its own grid chosen by the same
 * tolerance, to a scratch file beside path; the scratch files are read
 * back and their fields copied under the prefix "basis<k>." into path,
 * which is written once at the end (atomically, as every table file), so
 * a failed or cancelled run leaves it untouched.
 *
 * Nothing but the parameter block is shared between bases: every set
 * keeps the format's complete field list, so that one set read alone is a
 * valid `measured` file, and the fields besides the three grids (vndf,
 * luminance, rgb or spectra) are a few kilobytes.
 *
 * The three grids are stored as float16, which halves the file: only
 * layerlab reads a textured file, and float16's rounding (relative 2^-11,
 * 0.049%) is far inside the tables' aims (albedo 0.3%, f's median 0.2%).
 * Each basis is written by the untextured writer with its grids rounded to
 * float16 where they are made (ll_tables_write_half: the VNDF before its
 * warp is built, and the tolerance measured on the rounded tables), so
 * the conversion here is exact; the small fields stay float32.
 *
 * A spectral file takes the values of basis k at each wavelength from the
 * caller's source (a textured file per wavelength) through the same view.
 */
#include "writer/bsdf_write_tables.h"
#include "writer/bsdf_write_tensor.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#define FN "ll_tables_write_from_bsdf"

/* One basis' scratch file, read back. */
typedef struct basis_set {
    unsigned char *bytes;
    size_t size;
    ll_tensor_file t;
} basis_set;

/* Fields of a set stored as float16 (the three grids). */
static int is_grid(const char *name)
{
    return strcmp(name, "vndf") == 0 || strcmp(name, "luminance") == 0 ||
           strcmp(name, "rgb") == 0 || strcmp(name, "spectra") == 0;
}

/* One field of the output copied from a basis' set. */
typedef struct copied {
    char name[LL_TENSOR_MAX_NAME + 1];
    const ll_tensor_field *f;
    float *decoded;          /* rank-1 float32 fields, decoded            */
} copied;

/* The caller's spectrum source seen through basis k. */
typedef struct basis_source {
    ll_tables_spectrum_fn source;
    void *user;
    size_t k;
} basis_source;

static ll_status source_basis(void *user, size_t index, double wavelength_nm, ll_bsdf **out)
{
    const basis_source *bs = user;
    ll_bsdf *whole = NULL;
    ll_status s = bs->source(bs->user, index, wavelength_nm, &whole);
    *out = NULL;
    if (s != LL_OK)
        return s;
    if (!whole || whole->measured || whole->n_bases <= bs->k)
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                    FN ": the spectrum source's file at %g nm has no basis %zu (a textured "
                    ".bsdf of the same parameters is needed)",
                    wavelength_nm, bs->k);
    else
        s = ll_tables_basis_view(whole, bs->k, out);
    ll_bsdf_release(whole);
    return s;
}

static ll_status read_back(const char *path, basis_set *set)
{
    FILE *f = fopen(path, "rb");
    long len;
    ll_status s;
    if (!f)
        return ll_fail(LL_ERROR_IO, FN ": cannot read back the scratch file %s", path);
    if (fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return ll_fail(LL_ERROR_IO, FN ": cannot size the scratch file %s", path);
    }
    set->size = (size_t)len;
    set->bytes = ll_malloc(set->size ? set->size : 1);
    if (!set->bytes) {
        fclose(f);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory (%zu bytes of tables)",
                       set->size);
    }
    if (fread(set->bytes, 1, set->size, f) != set->size) {
        fclose(f);
        return ll_fail(LL_ERROR_IO, FN ": cannot read back the scratch file %s", path);
    }
    fclose(f);
    s = ll_tensor_parse(set->bytes, set->size, path, &set->t);
    return s;
}

/* Block b of a copied float32 field (its last two extents). */
static ll_status fill_copied(void *ctx, size_t block, float *out)
{
    const copied *c = ctx;
    size_t plane = c->f->shape[c->f->rank - 1] * c->f->shape[c->f->rank - 2], i;
    for (i = 0; i < plane; ++i)
        out[i] = ll_tensor_f32(c->f, block * plane + i);
    return LL_OK;
}

/* The output: the extended fields, then every basis' fields renamed. */
static ll_status write_all(const ll_bsdf *b, const char *path, const basis_set *sets,
                           const char *description)
{
    static const char layout[] = "textured";
    size_t nb = b->n_bases, n_copied = 0, k, i, n_out;
    float *counts = NULL;
    copied *cp = NULL;
    ll_tensor_out_field *out = NULL;
    ll_status s = LL_OK;
    for (k = 0; k < nb; ++k)
        n_copied += sets[k].t.n_fields;
    n_out = n_copied + 5;
    if (n_out > LL_TENSOR_MAX_FIELDS)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": %zu bases make %zu fields, more than a table file may have (%d)",
                       nb, n_out, LL_TENSOR_MAX_FIELDS);
    counts = ll_alloc_array(b->n_parameters, sizeof *counts);
    cp = ll_calloc_array(n_copied, sizeof *cp);
    out = ll_calloc_array(n_out, sizeof *out);
    if (!counts || !cp || !out) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
        goto done;
    }
    for (k = 0; k < b->n_parameters; ++k)
        counts[k] = (float)b->param_counts[k];
    {
        ll_tensor_out_field head[5] = {
            { "description", LL_TENSOR_U8, 1, { strlen(description) }, description, NULL, NULL },
            { "layerlab_layout", LL_TENSOR_U8, 1, { sizeof layout - 1 }, layout, NULL, NULL },
            { "layerlab_parameter_counts", LL_TENSOR_F32, 1, { b->n_parameters }, counts, NULL,
              NULL },
            { "layerlab_parameter_positions", LL_TENSOR_F32, 1, { b->n_parameter_values },
              b->param_positions, NULL, NULL },
            { "layerlab_metadata", LL_TENSOR_U8, 1, { b->metadata_size }, b->metadata, NULL,
              NULL },
        };
        memcpy(out, head, sizeof head);
    }
    for (k = 0, i = 0; k < nb; ++k) {
        size_t j;
        for (j = 0; j < sets[k].t.n_fields; ++j, ++i) {
            const ll_tensor_field *f = &sets[k].t.fields[j];
            ll_tensor_out_field *o = &out[5 + i];
            copied *c = &cp[i];
            size_t r;
            if ((size_t)snprintf(c->name, sizeof c->name, "basis%zu.%s", k, f->name) >=
                sizeof c->name) {
                s = ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": field name basis%zu.%s too long",
                            k, f->name);
                goto done;
            }
            c->f = f;
            o->name = c->name;
            o->dtype = f->dtype;
            o->rank = f->rank;
            for (r = 0; r < f->rank; ++r)
                o->shape[r] = f->shape[r];
            if (f->dtype == LL_TENSOR_U8) {
                o->data = f->data;
            } else if (f->dtype != LL_TENSOR_F32) {
                s = ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": field %s has dtype %d", f->name,
                            f->dtype);
                goto done;
            } else if (f->rank >= 2) {
                o->fill = fill_copied;
                o->fill_ctx = c;
                if (is_grid(f->name))
                    o->dtype = LL_TENSOR_F16;
            } else {
                size_t e;
                c->decoded = ll_alloc_array(f->count, sizeof(float));
                if (!c->decoded) {
                    s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
                    goto done;
                }
                for (e = 0; e < f->count; ++e)
                    c->decoded[e] = ll_tensor_f32(f, e);
                o->data = c->decoded;
            }
        }
    }
    s = ll_tensor_write(path, FN, out, n_out);
done:
    if (cp)
        for (i = 0; i < n_copied; ++i)
            ll_free(cp[i].decoded);
    ll_free(cp);
    ll_free(out);
    ll_free(counts);
    return s;
}

ll_status ll_tables_write_textured(const ll_bsdf *b, const char *path,
                                   const ll_tables_options *opts, const ll_monitor *monitor)
{
    ll_tables_options o = *opts;
    ll_monitor none = LL_MONITOR_INIT, sub = LL_MONITOR_INIT;
    basis_set *sets;
    basis_source bs;
    ll_tables_share sh;
    char *scratch;
    size_t nb = b->n_bases, k, len = strlen(path) + 64;
    ll_status s = LL_OK;
    const char *desc = o.description
                           ? o.description
                           : "layerlab: warped tables of a textured opaque layered material, "
                             "one set per basis (read by layerlab only)";
    sh.whole = none;
    if (monitor &&
        (s = ll_struct_read(&sh.whole, sizeof sh.whole, monitor, FN, "ll_monitor")) != LL_OK)
        return s;
    sets = ll_calloc_array(nb, sizeof *sets);
    scratch = ll_malloc(len);
    if (!sets || !scratch) {
        ll_free(sets);
        ll_free(scratch);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
    }
    bs.source = o.spectrum;
    bs.user = o.spectrum_user;
    if (o.format == LL_TABLES_SPECTRAL && o.spectrum) {
        o.spectrum = source_basis;
        o.spectrum_user = &bs;
    }
    snprintf(scratch, len, "%s.%ld.basis", path, (long)getpid());
    /* Every basis opaque, before any is written: a basis' tables are one
     * set of the plain names, and the reader reads a textured file's bases
     * as such (a transmissive basis would need its lobe sets). */
    for (k = 0; k < nb && s == LL_OK; ++k) {
        ll_bsdf *view = NULL;
        if ((s = ll_tables_basis_view(b, k, &view)) != LL_OK)
            break;
        if (ll_tables_transmits(view))
            s = ll_fail(LL_ERROR_UNSUPPORTED,
                        FN ": basis %zu of the textured file transmits light; this version "
                        "writes the tables of a textured opaque file or of an untextured "
                        "transmissive one",
                        k);
        ll_bsdf_release(view);
    }
    for (k = 0; k < nb && s == LL_OK; ++k) {
        ll_bsdf *view = NULL;
        sub = ll_tables_share_of(&sh, 0.95 * (double)k / (double)nb, 0.95 / (double)nb);
        bs.k = k;
        if ((s = ll_tables_basis_view(b, k, &view)) != LL_OK)
            break;
        s = ll_tables_write_half(view, scratch, &o, monitor ? &sub : NULL);
        ll_bsdf_release(view);
        if (s == LL_ERROR_INVALID_ARGUMENT) {
            /* Which basis (a value beyond float16's range names its table). */
            char why[512];
            snprintf(why, sizeof why, "%s", ll_last_error_message());
            s = ll_fail(s, FN ": basis %zu: %s", k, why);
        }
        if (s == LL_OK)
            s = read_back(scratch, &sets[k]);
        unlink(scratch);
    }
    if (s == LL_OK) {
        if (sh.whole.progress && sh.whole.progress(sh.whole.user, 0.95, "writing"))
            s = ll_fail(LL_ERROR_CANCELLED, FN ": cancelled");
        else
            s = write_all(b, path, sets, desc);
    }
    for (k = 0; k < nb; ++k) {
        ll_tensor_file_free(&sets[k].t);
        ll_free(sets[k].bytes);
    }
    ll_free(sets);
    ll_free(scratch);
    return s;
}
