/*
 * The life of an opened .bsdf file: reference counting (an opened file is
 * immutable, so sharing it between materials and threads needs nothing but
 * an atomic count) and the read-only queries.
 */
#include "reader/bsdf_internal.h"
#include "reader/tables_internal.h"

#include <stdlib.h>
#include <string.h>

const float ll_bsdf_unit_basis[1] = { 1.0f };

void ll_bsdf_free(ll_bsdf *b)
{
    if (!b)
        return;
    if (b->measured_bases) {
        size_t k;
        for (k = 0; k < b->n_bases; ++k)
            ll_measured_free(b->measured_bases[k]);
        ll_free(b->measured_bases);
    } else {
        ll_measured_free(b->measured);
    }
    ll_free(b->nodes_f);
    ll_free(b->nodes);
    ll_free(b->param_counts);
    ll_free(b->param_first);
    ll_free(b->param_positions);
    ll_free(b->cdf);
    ll_free(b->cdf_flat);
    ll_free(b->a0);
    ll_free(b->pairs);
    ll_free(b->coeffs);
    ll_free(b->recip);
    ll_free(b->bucket_first);
    ll_free(b->intervals);
    ll_free(b->metadata);
    ll_free(b->param_names);
    ll_free(b);
}

ll_bsdf *ll_bsdf_retain(ll_bsdf *b)
{
    if (b)
        __atomic_add_fetch(&b->refcount, 1, __ATOMIC_RELAXED);
    return b;
}

void ll_bsdf_release(ll_bsdf *b)
{
    /* Acquire-release: the thread that frees sees every other thread's
     * last use of the object completed. */
    if (b && __atomic_sub_fetch(&b->refcount, 1, __ATOMIC_ACQ_REL) == 0)
        ll_bsdf_free(b);
}

ll_status ll_bsdf_get_info(const ll_bsdf *b, ll_bsdf_info *info)
{
    ll_bsdf_info full;
    if (!b || !info)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_get_info: bsdf or info is NULL");
    memset(&full, 0, sizeof full);
    full.struct_size = sizeof full;
    full.n_nodes = b->n_nodes;
    full.max_order = b->max_order;
    full.n_channels = b->n_channels;
    full.n_bases = b->n_bases;
    full.n_parameters = b->n_parameters;
    full.n_coeffs = b->n_coeffs;
    full.eta = b->eta;
    full.alpha[0] = b->alpha[0];
    full.alpha[1] = b->alpha[1];
    full.metadata = b->metadata;
    full.metadata_size = b->metadata_size;
    full.file_size = b->file_size;
    full.flags = b->flags;
    full.format = b->measured ? LL_BSDF_FORMAT_TABLES : LL_BSDF_FORMAT_FOURIER;
    full.n_wavelengths = b->measured ? b->measured->n_wavelengths : 0;
    /* Write only the fields the caller's (possibly older, smaller) struct has. */
    return ll_struct_write(info, &full, sizeof full, "ll_bsdf_get_info", "ll_bsdf_info");
}

ll_status ll_bsdf_get_parameter(const ll_bsdf *b, size_t p, size_t *count,
                                const float **positions)
{
    if (!b || !count || !positions)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_get_parameter: bsdf, count or positions is NULL");
    if (p >= b->n_parameters)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_get_parameter: parameter %zu does not exist (the file has %zu)",
                       p, b->n_parameters);
    *count = b->param_counts[p];
    *positions = b->param_positions + b->param_first[p];
    return LL_OK;
}

const float *ll_bsdf_nodes(const ll_bsdf *b) { return b ? b->nodes_f : NULL; }

ll_status ll_bsdf_check_basis(const ll_bsdf *b, const float *basis_coeffs, const char *fn,
                              const float **basis)
{
    size_t k;
    if (!basis_coeffs) {
        if (b->n_bases != 1)
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: the file is textured (%zu basis functions); basis_coeffs "
                           "must give their weights",
                           fn, b->n_bases);
        *basis = ll_bsdf_unit_basis;
        return LL_OK;
    }
    for (k = 0; k < b->n_bases; ++k)
        if (!ll_is_finite(basis_coeffs[k]))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: basis_coeffs[%zu] = %g is not finite",
                           fn, k, (double)basis_coeffs[k]);
    *basis = basis_coeffs;
    return LL_OK;
}
