/*
 * Building a material: one layer per word and channel, stacked bottom-up
 * with the adding equations, then written as a .bsdf file.
 *
 * RGB builds share what is the same across channels: a word whose
 * parameters are equal in two channels (a clear coat) is built once, and two
 * channels whose stacks agree from the bottom up to some word share that
 * partial stack (a clone, whose Fourier orders are shared copy-on-write)
 * until a word differs. A grey stack built as RGB costs one channel.
 */
#include "material/material.h"
#include "layer/layer.h"
#include "words/merl.h"
#include "layerlab/ll_quad.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Memory model of ll_material_estimate (fitted on the examples). */
#define STORED_FRACTION 0.08
#define PROCESS_BYTES (8.0 * 1048576.0)

typedef struct build {
    const ll_material *m;
    ll_build_options o;
    size_t n, orders, nch;
    double *nodes, *weights;
    ll_word_params (*params)[3]; /* [word][channel] */
    double total, done;          /* estimated seconds: all, finished  */
    ll_monitor_fn monitor_fn;    /* the caller's ll_monitor (nullable) */
    void *monitor_user;
    int stopped;                 /* the caller's monitor asked to stop */
    double shown;                /* the last fraction reported         */
    ll_monitor call;             /* passed to every layer call         */
    double call_start, call_cost;
    const char *call_stage;
    int call_ends_build;         /* its 1 is the build's 1 (the writing) */
} build;

static int cancel_raised(const build *b)
{
    return b->stopped || (b->o.cancel && *b->o.cancel);
}

/* The build's progress to opts->progress and the caller's monitor (whose
 * non-zero return stops the build); fractions never go back. */
static void report(build *b, const char *stage)
{
    double f = b->total > 0.0 ? b->done / b->total : 0.0;
    f = f < 1.0 ? f : 1.0;
    if (f < b->shown)
        f = b->shown;
    b->shown = f;
    if (b->o.progress)
        b->o.progress(f, stage, b->o.progress_user);
    if (b->monitor_fn && b->monitor_fn(b->monitor_user, f, stage) != 0)
        b->stopped = 1;
}

static ll_status check_cancel(const build *b)
{
    if (cancel_raised(b))
        return ll_fail(LL_ERROR_CANCELLED, "%s: the build was cancelled", b->m->source);
    return LL_OK;
}

/* The monitor of every layer call: its fraction is the share call_cost of
 * the build from call_start on; it stops the call when the build's cancel
 * flag (polled here on the calling thread, and so seen by the call's
 * workers at their next poll) or the caller's monitor says so. */
static int on_call_progress(void *user, double fraction, const char *stage)
{
    build *b = user;
    double done = b->call_start + fraction * b->call_cost;
    if (fraction >= 1.0 && b->call_ends_build)
        done = b->total; /* exactly 1, without rounding */
    if (done > b->done)
        b->done = done;
    report(b, b->call_stage ? b->call_stage : stage);
    return cancel_raised(b);
}

/* Point the call monitor at the next layer call. */
static const ll_monitor *next_call(build *b, const char *stage, double cost)
{
    b->call_start = b->done;
    b->call_cost = cost;
    b->call_stage = stage;
    return &b->call;
}

/* The smallest c' <= c whose word parameters equal channel c's. */
static size_t same_word_as(const build *b, size_t w, size_t c)
{
    size_t d;
    for (d = 0; d < c; ++d)
        if (ll_word_params_equal(&b->params[w][d], &b->params[w][c]))
            return d;
    return c;
}

/* Stack owners at word w, given those of the level below (NULL at the
 * bottom): the smallest channel with the same parameters all the way down. */
static void stack_owners(const build *b, size_t w, const size_t *below, size_t *owner)
{
    size_t c, d;
    for (c = 0; c < b->nch; ++c) {
        owner[c] = c;
        for (d = 0; d < c; ++d)
            if ((!below || below[d] == below[c]) &&
                ll_word_params_equal(&b->params[w][d], &b->params[w][c])) {
                owner[c] = d;
                break;
            }
    }
}

static const char *stage_of(ll_word_kind kind)
{
    switch (kind) {
    case LL_WORD_DIELECTRIC: return "dielectric interface";
    case LL_WORD_CONDUCTOR: return "conductor interface";
    case LL_WORD_MEDIUM: return "medium";
    case LL_WORD_DIFFUSE: return "diffuse";
    default: return "measured";
    }
}

/* Prefix the message of a failed word call with where the word is. */
static ll_status word_failed(const build *b, size_t w, ll_status s)
{
    const ll_word *word = &b->m->words[w];
    char detail[700];
    if (s == LL_ERROR_CANCELLED)
        return s;
    snprintf(detail, sizeof detail, "%s", ll_last_error_message());
    return ll_fail(s, "%s:%zu:%zu: building this %s failed: %s", b->m->source, word->line,
                   word->column, ll_word_kind_name(word->kind), detail);
}

/* ll_layer_expand_ex, its progress the share of the medium's estimated
 * cost that the doubling steps represent. */
static ll_status expand_medium(build *b, ll_layer *l, double tau)
{
    double cost = (double)ll_doubling_count(tau, 1.0) *
                  ll_cost_add(b->n, b->orders, ll_get_thread_count());
    return ll_layer_expand_ex(l, tau, next_call(b, "medium", cost));
}

/* A MERL channel through the public call; the luminance mix of a mono
 * build has none and goes through the internal setter (same monitor). */
static ll_status set_measured(build *b, ll_layer *l, const char *path, const double weights[3],
                              const ll_monitor *monitor)
{
    ll_merl *merl = NULL;
    ll_status s;
    int c;
    (void)b;
    for (c = 0; c < 3; ++c)
        if (weights[c] == 1.0 && weights[(c + 1) % 3] == 0.0 && weights[(c + 2) % 3] == 0.0)
            return ll_layer_set_matusik_ex(l, path, c, 0, monitor);
    s = ll_merl_load(path, &merl);
    if (s == LL_OK)
        s = ll_merl_set_layer_ex(l, merl, weights, 0, monitor);
    ll_merl_free(merl);
    return s;
}

static ll_status build_word(build *b, size_t w, const ll_word_params *p, ll_layer **out)
{
    ll_layer *l = NULL;
    double done_before = b->done;
    double cost = ll_cost_word(p, b->n, b->orders, ll_get_thread_count());
    const char *stage = stage_of(p->kind);
    ll_status s;

    *out = NULL;
    report(b, stage);
    s = ll_layer_create(b->nodes, b->weights, b->n, b->orders, &l);
    if (s != LL_OK)
        return s;
    switch (p->kind) {
    case LL_WORD_DIFFUSE:
        s = ll_layer_set_diffuse_ex(l, p->albedo, next_call(b, stage, cost));
        break;
    case LL_WORD_DIELECTRIC:
        s = ll_layer_set_microfacet_ex(l, p->eta_re, 0.0, p->alpha, !p->uncompensated, 0,
                                       next_call(b, stage, cost));
        break;
    case LL_WORD_CONDUCTOR:
        s = ll_layer_set_microfacet_ex(l, p->eta_re, p->eta_im, p->alpha, !p->uncompensated, 0,
                                       next_call(b, stage, cost));
        break;
    case LL_WORD_MEDIUM:
        /* (The doublings below carry the medium's cost; the phase matrices
         * show as their own stage, "phase function".) */
        if (p->phase == LL_PHASE_HG)
            s = ll_layer_set_henyey_greenstein_ex(l, p->albedo, p->shape,
                                                  next_call(b, NULL, 0.0));
        else if (p->phase == LL_PHASE_VMF)
            s = ll_layer_set_von_mises_fisher_ex(l, p->albedo, p->shape,
                                                 next_call(b, NULL, 0.0));
        else
            s = ll_layer_set_isotropic_ex(l, p->albedo, next_call(b, NULL, 0.0));
        if (s == LL_OK)
            s = expand_medium(b, l, p->tau);
        break;
    case LL_WORD_MEASURED:
        s = set_measured(b, l, b->m->words[w].file, p->weights, next_call(b, stage, cost));
        break;
    }
    if (s != LL_OK) {
        ll_layer_destroy(l);
        return word_failed(b, w, s);
    }
    /* (The doublings counted their share as they went.) */
    b->done = done_before + ll_cost_word(p, b->n, b->orders, ll_get_thread_count());
    *out = l;
    return check_cancel(b);
}

/* One level of the stack: word w on top of acc (bottom-up). */
static ll_status add_level(build *b, size_t w, ll_layer *acc[3], size_t below[3],
                           int bottom)
{
    ll_layer *word[3] = { NULL, NULL, NULL };
    size_t owner[3], c;
    ll_status s = LL_OK;

    stack_owners(b, w, bottom ? NULL : below, owner);
    for (c = 0; c < b->nch && s == LL_OK; ++c) {
        size_t same = same_word_as(b, w, c);
        if (owner[c] != c)
            continue; /* this channel's stack is another's */
        if (same != c && word[same])
            word[c] = word[same];
        else
            s = build_word(b, w, &b->params[w][c], &word[c]);
    }
    /* Channels that part from a shared stack here start from a copy of it
     * as it was below this word; copy all before adding to any. */
    for (c = 0; c < b->nch && s == LL_OK; ++c)
        if (owner[c] == c && !bottom && below[c] != c)
            s = ll_layer_clone(acc[below[c]], &acc[c]);
    for (c = 0; c < b->nch && s == LL_OK; ++c) {
        if (owner[c] != c)
            continue;
        if (bottom) {
            s = ll_layer_clone(word[c], &acc[c]);
        } else {
            double cost = ll_cost_add(b->n, b->orders, ll_get_thread_count()), start;
            report(b, "adding");
            start = b->done;
            s = ll_layer_add_ex(word[c], acc[c], acc[c], 0, next_call(b, "adding", cost));
            if (s != LL_OK)
                s = word_failed(b, w, s);
            b->done = start + cost;
            if (s == LL_OK)
                s = check_cancel(b);
        }
    }
    for (c = 0; c < b->nch; ++c) {
        if (word[c] && same_word_as(b, w, c) == c)
            ll_layer_destroy(word[c]);
        below[c] = owner[c];
    }
    return s;
}

/* Estimated seconds of the whole build (for progress fractions). */
static double total_cost(const build *b)
{
    size_t below[3] = { 0, 0, 0 }, owner[3], w, c, threads = ll_get_thread_count();
    double t = 0.0;
    for (w = b->m->count; w-- > 0;) {
        int bottom = w + 1 == b->m->count;
        stack_owners(b, w, bottom ? NULL : below, owner);
        for (c = 0; c < b->nch; ++c) {
            if (owner[c] != c)
                continue;
            if (same_word_as(b, w, c) == c)
                t += ll_cost_word(&b->params[w][c], b->n, b->orders, threads);
            if (!bottom)
                t += ll_cost_add(b->n, b->orders, threads);
        }
        memcpy(below, owner, sizeof below);
    }
    return t;
}

static void build_free(build *b)
{
    free(b->nodes);
    free(b->weights);
    free(b->params);
}

/* The options and the monitors of a build. monitor: the caller's
 * (nullable), read up to its struct_size. */
static ll_status build_start(build *b, const ll_material *m, const ll_build_options *opts,
                             const ll_monitor *monitor, const char *fn)
{
    ll_monitor call = LL_MONITOR_INIT;
    memset(b, 0, sizeof *b);
    b->m = m;
    call.progress = on_call_progress;
    call.user = b;
    b->call = call;
    if (!m)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: material is NULL", fn);
    if (monitor && monitor->struct_size < sizeof(size_t))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: monitor->struct_size is %zu; initialise the monitor with "
                       "LL_MONITOR_INIT",
                       fn, monitor->struct_size);
#define COVERS(field) (monitor->struct_size >= offsetof(ll_monitor, field) + sizeof monitor->field)
    if (monitor && COVERS(progress))
        b->monitor_fn = monitor->progress;
    if (monitor && COVERS(user))
        b->monitor_user = monitor->user;
#undef COVERS
    return ll_build_options_read(opts, &b->o, fn);
}

/* Resolution, quadrature and per-channel parameters. silent: no progress
 * reports (ll_material_estimate has none), though a cancel still works. */
static ll_status build_init(build *b, const ll_material *m, const ll_build_options *opts,
                            const ll_monitor *monitor, int silent, const char *fn)
{
    size_t w, c;
    ll_status s = build_start(b, m, opts, monitor, fn);
    if (silent)
        b->o.progress = NULL;
    if (s == LL_OK)
        s = ll_material_plan(m, &b->o, &b->n, &b->orders, &b->nch);
    if (s != LL_OK)
        return s;
    b->nodes = ll_alloc_array(b->n, sizeof(double));
    b->weights = ll_alloc_array(b->n, sizeof(double));
    b->params = ll_calloc_array(m->count, sizeof *b->params);
    if (!b->nodes || !b->weights || !b->params) {
        build_free(b);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    }
    for (w = 0; w < m->count; ++w)
        for (c = 0; c < b->nch; ++c)
            ll_word_params_get(m, w, c, b->nch, &b->params[w][c]);
    /* Gauss-Lobatto nodes, as the original recipes use (O(n^2): seconds at
     * n = 30000, so polled like every other stage). */
    s = ll_quad_gauss_lobatto_ex(b->n, b->nodes, b->weights, next_call(b, "quadrature", 0.0));
    if (s != LL_OK)
        build_free(b);
    return s;
}

/* The header a file of this material carries (fields that header's
 * struct_size covers). */
static void fill_header(const ll_material *m, const ll_build_options *o, size_t n_channels,
                        ll_bsdf_write_options *header)
{
    double eta, alpha[2];
    size_t size = header->struct_size;
    ll_material_header(m, n_channels, &eta, alpha);
#define COVERS(field) \
    (size >= offsetof(ll_bsdf_write_options, field) + sizeof header->field)
    if (COVERS(eta))
        header->eta = eta;
    if (COVERS(alpha)) {
        header->alpha[0] = alpha[0];
        header->alpha[1] = alpha[1];
    }
    if (COVERS(metadata))
        header->metadata = m->metadata;
    if (COVERS(error_goal))
        header->error_goal = o->error_goal > 0.0   ? o->error_goal
                             : m->error_goal > 0.0 ? m->error_goal
                                                   : 1e-3;
#undef COVERS
}

/* The build proper, on an initialised state; restores the thread count. */
static ll_status run_build(build *b, ll_layer *layers[3], double extra_cost)
{
    ll_layer *acc[3] = { NULL, NULL, NULL };
    size_t below[3] = { 0, 0, 0 }, w, c, saved_threads = ll_get_thread_count();
    ll_status s = LL_OK;

    if (b->o.threads)
        s = ll_set_thread_count(b->o.threads);
    b->total = total_cost(b) + extra_cost;
    for (w = b->m->count; w-- > 0 && s == LL_OK;)
        s = add_level(b, w, acc, below, w + 1 == b->m->count);
    for (c = 0; c < b->nch && s == LL_OK; ++c)
        if (below[c] != c)
            s = ll_layer_clone(acc[below[c]], &layers[c]);
    if (s == LL_OK)
        for (c = 0; c < b->nch; ++c)
            if (below[c] == c) {
                layers[c] = acc[c];
                acc[c] = NULL;
            }
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(acc[c]);
    if (s != LL_OK)
        for (c = 0; c < 3; ++c) {
            ll_layer_destroy(layers[c]);
            layers[c] = NULL;
        }
    if (b->o.threads)
        ll_set_thread_count(saved_threads);
    return s;
}

ll_status ll_material_build_layers(const ll_material *material, const ll_build_options *opts,
                                   ll_layer *layers[3], size_t *n_channels,
                                   ll_bsdf_write_options *header)
{
    return ll_material_build_layers_ex(material, opts, NULL, layers, n_channels, header);
}

ll_status ll_material_build_layers_ex(const ll_material *material,
                                      const ll_build_options *opts, const ll_monitor *monitor,
                                      ll_layer *layers[3], size_t *n_channels,
                                      ll_bsdf_write_options *header)
{
    build b;
    ll_status s;
    size_t c;

    if (!layers || !n_channels)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_build_layers: layers or n_channels is NULL");
    for (c = 0; c < 3; ++c)
        layers[c] = NULL;
    *n_channels = 0;
    if (header && header->struct_size < sizeof(size_t))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_build_layers: header->struct_size is %zu; initialise the "
                       "header with LL_BSDF_WRITE_OPTIONS_INIT",
                       header->struct_size);
    s = build_init(&b, material, opts, monitor, 0, "ll_material_build_layers");
    if (s != LL_OK)
        return s;
    s = run_build(&b, layers, 0.0);
    if (s == LL_OK) {
        /* The last report comes before the layers are handed over: a cancel
         * there still returns none. */
        b.done = b.total;
        report(&b, "done");
        s = check_cancel(&b);
    }
    if (s == LL_OK) {
        *n_channels = b.nch;
        if (header)
            fill_header(b.m, &b.o, b.nch, header);
    } else {
        for (c = 0; c < 3; ++c) {
            ll_layer_destroy(layers[c]);
            layers[c] = NULL;
        }
    }
    build_free(&b);
    return s;
}

/* Write atomically in two steps so that a cancel that arrives while the
 * writer runs still leaves no file: the writer's own atomic write goes to
 * a unique name beside out_path, renamed over out_path only if the build
 * was not cancelled meanwhile. */
static ll_status write_layers(const ll_material *m, const ll_build_options *o,
                              ll_layer *const *layers, size_t n_channels, const char *out_path,
                              const ll_monitor *monitor)
{
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    size_t len = strlen(out_path);
    char *tmp = malloc(len + 8);
    int fd;
    ll_status s;

    if (!tmp)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory writing %s", out_path);
    fill_header(m, o, n_channels, &header);
    memcpy(tmp, out_path, len);
    memcpy(tmp + len, ".XXXXXX", 8);
    fd = mkstemp(tmp);
    if (fd < 0) {
        s = ll_fail(LL_ERROR_IO, "cannot create a file beside %s: %s", out_path,
                    strerror(errno));
        free(tmp);
        return s;
    }
    close(fd);
    s = ll_bsdf_write_ex(tmp, (const ll_layer *const *)layers, n_channels, &header, monitor);
    if (s == LL_OK && o->cancel && *o->cancel)
        s = ll_fail(LL_ERROR_CANCELLED, "%s: the build was cancelled", m->source);
    if (s == LL_OK && rename(tmp, out_path) != 0)
        s = ll_fail(LL_ERROR_IO, "cannot rename %s to %s: %s", tmp, out_path, strerror(errno));
    if (s != LL_OK)
        unlink(tmp);
    free(tmp);
    return s;
}

ll_status ll_material_write(const ll_material *material, const ll_build_options *opts,
                            ll_layer *const *layers, size_t n_channels, const char *out_path)
{
    build b;
    size_t c;
    ll_status s;
    if (!material || !layers || !out_path || !*out_path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_write: material, layers or out_path is NULL or empty");
    if (n_channels != 1 && n_channels != 3)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_write: n_channels = %zu; expected 1 or 3", n_channels);
    for (c = 0; c < n_channels; ++c)
        if (!layers[c])
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_write: layers[%zu] is NULL",
                           c);
    s = build_start(&b, material, opts, NULL, "ll_material_write");
    if (s != LL_OK)
        return s;
    b.o.progress = NULL; /* only error_goal and cancel are read */
    return write_layers(material, &b.o, layers, n_channels, out_path,
                        next_call(&b, "writing", 0.0));
}

ll_status ll_material_build(const ll_material *material, const ll_build_options *opts,
                            const char *out_path)
{
    return ll_material_build_ex(material, opts, NULL, out_path);
}

ll_status ll_material_build_ex(const ll_material *material, const ll_build_options *opts,
                               const ll_monitor *monitor, const char *out_path)
{
    build b;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    double write_cost;
    ll_status s;
    size_t c;

    if (!out_path || !*out_path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_build: out_path is NULL or empty");
    s = build_init(&b, material, opts, monitor, 0, "ll_material_build");
    if (s != LL_OK)
        return s;
    /* The writing's share of the progress bar. */
    write_cost = ll_cost_write(b.n, b.orders, b.nch);
    s = run_build(&b, layers, write_cost);
    if (s == LL_OK) {
        const ll_monitor *writing;
        report(&b, "writing");
        writing = next_call(&b, "writing", b.total - b.done);
        b.call_ends_build = 1;
        /* The writer's last report, before the file replaces out_path, is
         * the build's last: the caller's monitor gets no "done" after it. */
        s = write_layers(b.m, &b.o, layers, b.nch, out_path, writing);
    }
    if (s == LL_OK && b.o.progress)
        b.o.progress(1.0, "done", b.o.progress_user);
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
    build_free(&b);
    return s;
}

/* ------------------------------------------------------------ estimate */

ll_status ll_material_estimate(const ll_material *material, const ll_build_options *opts,
                               ll_build_estimate *e)
{
    build b;
    size_t below[3] = { 0, 0, 0 }, owner[3], w, c, threads, live_acc = 0;
    double layer_bytes, peak = 0.0, seconds = 0.0, workspace;
    size_t saved;
    ll_status s;

    if (!e || e->struct_size < sizeof *e)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_estimate: estimate is NULL or its struct_size is not "
                       "sizeof(ll_build_estimate)");
    s = build_init(&b, material, opts, NULL, 1, "ll_material_estimate");
    if (s != LL_OK)
        return s;
    saved = ll_get_thread_count();
    if (b.o.threads)
        ll_set_thread_count(b.o.threads);
    threads = ll_get_thread_count();
    if (b.o.threads)
        ll_set_thread_count(saved);
    e->n_nodes = b.n;
    e->n_orders = b.orders;
    e->n_channels = b.nch;
    e->layers_built = e->additions = e->doublings = 0;
    /* A layer stored densely: m orders of n x n doubles. The adding keeps
     * about 12 h x h blocks per thread. */
    layer_bytes = 8.0 * (double)b.n * (double)b.n * (double)b.orders;
    workspace = 12.0 * 8.0 * (double)(b.n / 2) * (double)(b.n / 2) *
                (double)(threads < b.orders ? threads : b.orders);
    for (w = b.m->count; w-- > 0;) {
        int bottom = w + 1 == b.m->count;
        size_t words = 0;
        stack_owners(&b, w, bottom ? NULL : below, owner);
        live_acc = 0;
        for (c = 0; c < b.nch; ++c) {
            if (owner[c] != c)
                continue;
            ++live_acc;
            if (same_word_as(&b, w, c) == c) {
                const ll_word_params *p = &b.params[w][c];
                ++words;
                ++e->layers_built;
                seconds += ll_cost_word(p, b.n, b.orders, threads);
                if (p->kind == LL_WORD_MEDIUM && p->tau > 0.0)
                    e->doublings += ll_doubling_count(p->tau, 1.0);
            }
            if (!bottom) {
                ++e->additions;
                seconds += ll_cost_add(b.n, b.orders, threads);
            }
        }
        /* Live at once: the stacks so far, this level's word layers, the
         * result of one addition (or expansion) in progress. */
        if ((double)(live_acc + words + 1) * layer_bytes + workspace > peak)
            peak = (double)(live_acc + words + 1) * layer_bytes + workspace;
        memcpy(below, owner, sizeof below);
    }
    /* Writing: the finished layers and the file's float32 coefficients. */
    if ((double)b.nch * layer_bytes * 1.5 > peak)
        peak = (double)b.nch * layer_bytes * 1.5;
    seconds += ll_cost_write(b.n, b.orders, b.nch);
    /* The compact storage keeps only the non-zero runs of each column and
     * no all-zero order: the six examples' builds peaked at 5% to 14% of
     * the dense bound (more for tiny ones), plus the process's own 8 MiB. */
    e->peak_bytes = STORED_FRACTION * peak + PROCESS_BYTES;
    e->seconds = seconds;
    build_free(&b);
    return LL_OK;
}
