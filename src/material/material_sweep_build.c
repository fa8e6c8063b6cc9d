/*
 * Building a swept material (ll_material_builder_*, ll_material.h): one
 * basis at a time, each basis a plain material (the sweep's values of that
 * basis in its words, ll_material_basis_view) built by material_build.c at
 * the resolution common to all bases, its word layers shared through the
 * cache of material_sweep_cache.c, keyed by (word, resolved parameters).
 * Two words with equal parameters build identical layers (the sharing
 * between channels relies on it too), so a hit is exact: the bases come out
 * bit-identical to separate builds at that resolution.
 *
 * ll_material_build_textured drives a builder and the streaming writer
 * (ll_bsdf_writer_*): bases go to the writer's spill as they are made, so
 * the build never holds more than one basis's stack.
 */
#include "material/word_table.h"

#include <stdio.h>
#include <string.h>

/* Share of the progress bar of ll_material_build_textured that the
 * writer's commit takes (llbuild gives writing the same). */
#define LL_TEXTURED_WRITE_SHARE 0.03

struct ll_material_builder {
    const ll_material *m;
    ll_build_options o;           /* the caller's, read                 */
    ll_monitor_fn monitor_fn;     /* the caller's monitor (nullable)    */
    void *monitor_user;
    size_t n, orders, nch, bases;
    ll_bsdf_write_options header; /* the file's: basis 0's eta, alpha   */
    ll_word *words;               /* [m->count] scratch of a basis view */
    ll_word_cache *cache;
    double start, span;           /* the share of the caller's progress */
    size_t basis;                 /* the basis being built              */
    char stage[96];
};

/* ----------------------------------------------------------- the builder */

/* Every basis's file header must have one eta (the format stores one). */
static ll_status check_headers(ll_material_builder *b)
{
    size_t k;
    double eta0 = 0.0;
    for (k = 0; k < b->bases; ++k) {
        ll_material view;
        double eta, alpha[2];
        ll_material_basis_view(b->m, k, b->words, &view);
        ll_material_header(&view, b->nch, &eta, alpha);
        if (k == 0) {
            eta0 = eta;
            b->header.eta = eta;
            b->header.alpha[0] = alpha[0];
            b->header.alpha[1] = alpha[1];
        } else if (eta != eta0) {
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: basis %zu has eta(bottom)/eta(top) = %g, basis 0 %g: a .bsdf "
                           "file holds one relative index, so sweep indices of refraction "
                           "only where the stack is opaque or the ratio stays the same",
                           b->m->source, k, eta, eta0);
        }
    }
    return LL_OK;
}

/* The caller's monitor while the builder chooses the resolution: polled
 * for a cancel at the start of the builder's share (the searches' own
 * fractions would run ahead of the bases' that follow). */
static int on_plan_progress(void *user, double fraction, const char *stage)
{
    const ll_material_builder *b = user;
    (void)fraction;
    (void)stage;
    return b->monitor_fn ? b->monitor_fn(b->monitor_user, b->start, "resolution") != 0 : 0;
}

ll_status ll_material_builder_create(const ll_material *m, const ll_build_options *opts,
                                     const ll_monitor *monitor, ll_material_builder **out)
{
    static const char *const fn = "ll_material_builder_create";
    ll_material_builder *b = NULL;
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_status s;
    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: out is NULL", fn);
    *out = NULL;
    if (!m)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: material is NULL", fn);
    b = ll_calloc(1, sizeof *b);
    if (!b)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    b->m = m;
    b->span = 1.0;
    b->bases = ll_material_basis_count(m);
    b->header = header;
    if (monitor) {
        ll_monitor caller = LL_MONITOR_INIT;
        if ((s = ll_struct_read(&caller, sizeof caller, monitor, fn, "ll_monitor")) != LL_OK)
            goto fail;
        b->monitor_fn = caller.progress;
        b->monitor_user = caller.user;
    }
    if ((s = ll_build_options_read(opts, &b->o, fn)) != LL_OK)
        goto fail;
    {
        ll_watch watch;
        ll_watch_begin_raw(&watch, b->monitor_fn ? on_plan_progress : NULL, b, NULL);
        s = ll_material_plan_bases(m, &b->o, &watch, &b->n, &b->orders, &b->nch, NULL);
        if (s != LL_OK)
            goto fail;
    }
    b->words = ll_alloc_array(m->count, sizeof *b->words);
    b->cache = ll_word_cache_create();
    if (!b->words || !b->cache) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
        goto fail;
    }
    if ((s = check_headers(b)) != LL_OK)
        goto fail;
    if (m->n_axes > 0) {
        /* The budget, on the estimate of the whole textured build (a few
         * word layers and one basis at a time), before anything grows. */
        ll_cost_plan plan;
        size_t threads = b->o.threads ? b->o.threads : ll_get_thread_count();
        if ((s = ll_material_cost_bases(m, b->n, b->orders, b->nch, threads, &plan)) != LL_OK ||
            (s = ll_check_budget(m, &plan, b->o.max_memory_bytes, fn)) != LL_OK)
            goto fail;
    }
    b->header.metadata = m->metadata;
    b->header.error_goal = b->o.error_goal > 0.0 ? b->o.error_goal
                           : m->error_goal > 0.0 ? m->error_goal
                                                 : 1e-3;
    *out = b;
    return LL_OK;
fail:
    ll_material_builder_destroy(b);
    return s;
}

/* The monitor of one basis's build: the caller's monitor, with the
 * fraction mapped to the builder's share and the stage named by the
 * basis. */
static int on_basis_progress(void *user, double fraction, const char *stage)
{
    ll_material_builder *b = user;
    double f = b->start + b->span * (b->basis + fraction) / (double)b->bases;
    snprintf(b->stage, sizeof b->stage, "basis %zu/%zu: %s", b->basis + 1, b->bases,
             stage ? stage : "");
    return b->monitor_fn ? b->monitor_fn(b->monitor_user, f, b->stage) != 0 : 0;
}

ll_status ll_material_builder_build_basis(ll_material_builder *b, size_t basis,
                                          ll_layer *layers[3], size_t *n_channels,
                                          ll_bsdf_write_options *header)
{
    static const char *const fn = "ll_material_builder_build_basis";
    ll_material view;
    ll_build_options o;
    ll_monitor monitor = LL_MONITOR_INIT;
    ll_status s;
    if (!layers || !n_channels)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers or n_channels is NULL", fn);
    layers[0] = layers[1] = layers[2] = NULL;
    *n_channels = 0;
    if (!b)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: builder is NULL", fn);
    if (basis >= b->bases)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: basis %zu, but %s has %zu", fn, basis,
                       b->m->source, b->bases);
    if (header && (s = ll_struct_check(header, fn, "ll_bsdf_write_options")) != LL_OK)
        return s;
    ll_material_basis_view(b->m, basis, b->words, &view);
    /* Every basis at the common resolution; progress and cancel through
     * the basis monitor. */
    o = b->o;
    o.n_nodes = b->n;
    o.n_orders = b->orders;
    o.n_channels = b->nch;
    monitor.progress = on_basis_progress;
    monitor.user = b;
    b->basis = basis;
    s = ll_material_build_layers_cached(&view, &o, &monitor, b->cache, layers, n_channels,
                                        NULL);
    if (s == LL_OK && header)
        s = ll_struct_write(header, &b->header, sizeof b->header, fn, "ll_bsdf_write_options");
    if (s != LL_OK) {
        size_t c;
        for (c = 0; c < 3; ++c) {
            ll_layer_destroy(layers[c]);
            layers[c] = NULL;
        }
        *n_channels = 0;
    }
    return s;
}

size_t ll_material_builder_layers_built(const ll_material_builder *b)
{
    return ll_word_cache_built(b ? b->cache : NULL);
}

size_t ll_material_builder_additions(const ll_material_builder *b)
{
    return ll_word_cache_additions(b ? b->cache : NULL);
}

void ll_material_builder_destroy(ll_material_builder *b)
{
    if (!b)
        return;
    ll_word_cache_destroy(b->cache);
    ll_free(b->words);
    ll_free(b);
}

/* ------------------------------------------------------ the whole file */

/* The writer's commit: the last share of the progress, and cancel. */
static int on_write_progress(void *user, double fraction, const char *stage)
{
    ll_material_builder *b = user;
    double f = 1.0 - LL_TEXTURED_WRITE_SHARE + LL_TEXTURED_WRITE_SHARE * fraction;
    (void)stage;
    return b->monitor_fn ? b->monitor_fn(b->monitor_user, f, "writing") != 0 : 0;
}

static ll_status write_bases(ll_material_builder *b, const char *out_path)
{
    const ll_material *m = b->m;
    size_t counts[LL_MATERIAL_MAX_AXES], values = 0, a, k, basis, nch, c;
    double *positions = NULL;
    ll_bsdf_writer *writer = NULL;
    ll_monitor monitor = LL_MONITOR_INIT;
    ll_status s;

    for (a = 0; a < m->n_axes; ++a) {
        counts[a] = m->axes[a].count;
        values += counts[a];
    }
    positions = ll_alloc_array(values, sizeof *positions);
    if (!positions)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_material_build: out of memory");
    for (a = 0, k = 0; a < m->n_axes; ++a) {
        memcpy(positions + k, m->axes[a].positions, counts[a] * sizeof *positions);
        k += counts[a];
    }
    s = ll_bsdf_writer_open(out_path, b->nch, m->n_axes, counts, positions, &b->header,
                            &writer);
    ll_free(positions);
    b->start = 0.0;
    b->span = 1.0 - LL_TEXTURED_WRITE_SHARE;
    for (basis = 0; basis < b->bases && s == LL_OK; ++basis) {
        ll_layer *layers[3] = { NULL, NULL, NULL };
        s = ll_material_builder_build_basis(b, basis, layers, &nch, NULL);
        if (s == LL_OK)
            s = ll_bsdf_writer_add_basis(writer, (const ll_layer *const *)layers);
        for (c = 0; c < 3; ++c)
            ll_layer_destroy(layers[c]);
    }
    if (s != LL_OK) {
        ll_bsdf_writer_abort(writer);
        return s;
    }
    monitor.progress = on_write_progress;
    monitor.user = b;
    s = ll_bsdf_writer_commit(writer, &monitor);
    if (s == LL_ERROR_CANCELLED)
        s = ll_fail(LL_ERROR_CANCELLED, "%s: the build was cancelled", m->source);
    return s;
}

ll_status ll_material_build_textured(const ll_material *m, const ll_build_options *opts,
                                     const ll_monitor *monitor, const char *out_path)
{
    ll_material_builder *b = NULL;
    size_t saved_threads = ll_get_thread_count();
    ll_status s = ll_material_builder_create(m, opts, monitor, &b);
    if (s != LL_OK)
        return s;
    if (b->o.threads)
        s = ll_set_thread_count(b->o.threads);
    if (s == LL_OK)
        s = write_bases(b, out_path);
    if (b->o.threads)
        ll_set_thread_count(saved_threads);
    ll_material_builder_destroy(b);
    return s;
}
