/*
 * One basis of a textured .bsdf as an untextured handle of its own, so
 * that the whole table writer (the NDF, the warps, the tolerance search,
 * the figures) makes the tables of each basis exactly as it makes those of
 * an untextured file. The view copies the basis' coefficients and per-row
 * tables out of the textured layout (channel c, basis k of a pair at
 * offset + (c * n_bases + k) * length) and shares nothing with b.
 */
#include "writer/bsdf_write_tables.h"

#include <string.h>

ll_status ll_tables_basis_view(const ll_bsdf *b, size_t k, ll_bsdf **out)
{
    size_t n = b->n_nodes, n2 = n * n, nb = b->n_bases, nc = b->n_channels, p, c, total = 0;
    ll_bsdf *v;
    *out = NULL;
    if (k >= nb)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_tables_basis_view: basis %zu of %zu", k,
                       nb);
    for (p = 0; p < n2; ++p)
        total += nc * b->pairs[p].length; /* within b->n_coeffs */
    v = ll_calloc(1, sizeof *v);
    if (!v)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_tables_basis_view: out of memory");
    v->refcount = 1;
    v->n_nodes = n;
    v->max_order = b->max_order;
    v->n_channels = nc;
    v->n_bases = 1;
    v->n_coeffs = total;
    /* Its share of the file: the search's size cap reads it. */
    v->file_size = b->file_size / nb;
    v->flags = b->flags;
    v->eta = b->eta;
    v->alpha[0] = b->alpha[0];
    v->alpha[1] = b->alpha[1];
    v->nodes_f = ll_alloc_array(n, sizeof *v->nodes_f);
    v->nodes = ll_alloc_array(n, sizeof *v->nodes);
    v->cdf = ll_alloc_array(n2, sizeof *v->cdf);
    v->a0 = ll_alloc_array(n2, sizeof *v->a0);
    v->pairs = ll_alloc_array(n2, sizeof *v->pairs);
    v->coeffs = ll_calloc_array(total + 4, sizeof *v->coeffs);
    v->recip = ll_alloc_array(b->max_order + 4, sizeof *v->recip);
    v->metadata = ll_calloc(1, 1);
    v->n_buckets = b->n_buckets;
    v->bucket_scale = b->bucket_scale;
    v->bucket_first = ll_alloc_array(b->n_buckets, sizeof *v->bucket_first);
    v->intervals = ll_alloc_array(n - 1, sizeof *v->intervals);
    if (b->cdf_flat)
        v->cdf_flat = ll_alloc_array(n * (n - 1), 1);
    if (!v->nodes_f || !v->nodes || !v->cdf || !v->a0 || !v->pairs || !v->coeffs ||
        !v->recip || !v->metadata || !v->bucket_first || !v->intervals ||
        (b->cdf_flat && !v->cdf_flat)) {
        ll_bsdf_free(v);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_tables_basis_view: out of memory");
    }
    memcpy(v->nodes_f, b->nodes_f, n * sizeof *v->nodes_f);
    memcpy(v->nodes, b->nodes, n * sizeof *v->nodes);
    memcpy(v->recip, b->recip, (b->max_order + 4) * sizeof *v->recip);
    memcpy(v->bucket_first, b->bucket_first, b->n_buckets * sizeof *v->bucket_first);
    memcpy(v->intervals, b->intervals, (n - 1) * sizeof *v->intervals);
    /* The flattened segments of any basis: a superset of this one's, which
     * only makes the sampler treat a few more segments as flat. */
    if (b->cdf_flat)
        memcpy(v->cdf_flat, b->cdf_flat, n * (n - 1));
    for (p = 0, total = 0; p < n2; ++p) {
        uint32_t len = b->pairs[p].length;
        v->cdf[p] = b->cdf[p * nb + k];
        v->a0[p] = b->a0[p * nb + k];
        v->pairs[p].offset = (uint32_t)total;
        v->pairs[p].length = len;
        for (c = 0; c < nc; ++c)
            memcpy(v->coeffs + total + c * len,
                   b->coeffs + b->pairs[p].offset + (c * nb + k) * len, len * sizeof(float));
        total += nc * len;
    }
    *out = v;
    return LL_OK;
}
