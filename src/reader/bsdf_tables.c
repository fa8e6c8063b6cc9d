/*
 * ll_bsdf_get_tables: the reader's validated tables as const views, so that
 * a renderer evaluating the format itself (the Mitsuba plugin's traced
 * path, which uploads them once as Dr.Jit arrays) reads exactly what the C
 * evaluator reads and never parses a file a second time.
 */
/* ll_bsdf_get_tables is declared for experimental use only (ll_bsdf.h);
 * the library's own build defines LL_EXPERIMENTAL for every file. */
#ifndef LL_EXPERIMENTAL
#define LL_EXPERIMENTAL
#endif
#include "reader/bsdf_internal.h"

#include <string.h>

/* The pairs are handed out as a flat uint32 array (offset, length per
 * pair): that is the struct's layout only if it has no padding. */
typedef char ll_bsdf_pair_is_two_words[sizeof(ll_bsdf_pair) == 2 * sizeof(uint32_t) ? 1 : -1];

ll_status ll_bsdf_get_tables(const ll_bsdf *b, ll_bsdf_tables *out)
{
    ll_bsdf_tables full;
    if (!b || !out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_get_tables: bsdf or out is NULL");
    if (b->measured)
        return ll_fail(LL_ERROR_UNSUPPORTED, "ll_bsdf_get_tables: the file is a table file "
                       "(format LL_BSDF_FORMAT_TABLES), which has no Fourier tables");
    memset(&full, 0, sizeof full);
    full.struct_size = sizeof full;
    full.n_nodes = b->n_nodes;
    full.n_channels = b->n_channels;
    full.n_bases = b->n_bases;
    full.max_order = b->max_order;
    full.n_coeffs = b->n_coeffs;
    full.n_parameters = b->n_parameters;
    full.n_parameter_values = b->n_parameter_values;
    full.eta = b->eta;
    full.nodes = b->nodes_f;
    full.pairs = &b->pairs[0].offset;
    full.coeffs = b->coeffs;
    full.cdf = b->cdf;
    full.a0 = b->a0;
    full.parameter_counts = b->n_parameters ? b->param_counts : NULL;
    full.parameter_positions = b->n_parameters ? b->param_positions : NULL;
    /* Only the fields the caller's (possibly older, smaller) struct has. */
    return ll_struct_write(out, &full, sizeof full, "ll_bsdf_get_tables", "ll_bsdf_tables");
}
