/*
 * Building a material: one layer per word and channel, stacked bottom-up
 * with the adding equations, then written as a .bsdf file.
 *
 * RGB builds share what is the same across channels: a word whose
 * parameters are equal in two channels (a clear coat) is built once, and two
 * channels whose stacks agree from the bottom up to some word share that
 * partial stack (a clone, whose Fourier orders are shared copy-on-write)
 * until a word differs. A grey stack built as RGB costs one channel. The
 * levels and their sharing are material_sharing.c's walk, the one the cost
 * model and the progress weights follow too.
 */
#include "material/word_table.h"
#include "layer/layer.h"
#include "writer/bsdf_write_channels.h"
#include "layerlab/ll_quad.h"
#include "distribution/share.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct build {
    const ll_material *m;
    ll_build_options o;
    size_t n, orders, nch;
    double *nodes, *weights;
    ll_word_params (*params)[3]; /* [word][channel] */
    ll_level_walk *levels;       /* the sharing walk, bottom-up (count) */
    ll_bsdf_write_options header; /* the file's, from the stack (in full) */
    double total, done;          /* estimated seconds: all, finished  */
    ll_build_weights cost;       /* the steps' estimated seconds        */
    double word_cost;            /* estimated seconds of the word being built */
    const char *word_stage;      /* its progress stage                  */
    ll_monitor_fn monitor_fn;    /* the caller's ll_monitor (nullable) */
    void *monitor_user;
    int stopped;                 /* the caller's monitor asked to stop */
    double shown;                /* the last fraction reported         */
    ll_monitor call;             /* passed to every layer call         */
    double call_start, call_cost;
    const char *call_stage;
    int call_ends_build;         /* its 1 is the build's 1 (the writing) */
    ll_share *share;             /* a distributed build's (NULL: one process) */
    ll_word_cache *cache;        /* a builder's word layers (nullable)  */
    ll_channel_writer *sink;     /* the file, fed each finished channel (nullable) */
    int pending;                 /* the bottom word is built when first needed */
    size_t pending_word;
} build;

static int cancel_raised(const build *b)
{
    return b->stopped;
}

/* The build's progress to the caller's monitor (whose non-zero return
 * stops the build); fractions never go back. */
static void report(build *b, const char *stage)
{
    double f = b->total > 0.0 ? b->done / b->total : 0.0;
    f = f < 1.0 ? f : 1.0;
    if (f < b->shown)
        f = b->shown;
    b->shown = f;
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
 * the build from call_start on; it stops the call when the caller's
 * monitor says so (asked here on the calling thread, and so seen by the
 * call's workers at their next poll). */
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

/* Prefix the message of a failed word call with where the word is. */
static ll_status word_failed(const build *b, size_t w, ll_status s)
{
    const ll_word *word = &b->m->words[w];
    char detail[700];
    if (s == LL_ERROR_CANCELLED)
        return s;
    snprintf(detail, sizeof detail, "%s", ll_last_error_message());
    return ll_fail(s, "%s:%zu:%zu: building this %s failed: %s", b->m->source, word->line,
                   word->column, ll_word_name(word), detail);
}

/* The monitor of a word's next layer call, credited with share (0..1) of
 * the word's modelled cost (a word builder's ctx->monitor). A call with no
 * share of its own (the phase matrices before a medium's doublings) shows
 * under its own stage name. */
static const ll_monitor *word_monitor(void *user, double share)
{
    build *b = user;
    return next_call(b, share > 0.0 ? b->word_stage : NULL, share * b->word_cost);
}

/* ll_layer_expand for a medium (a word builder's ctx->expand): the
 * doublings are nearly all of a medium's modelled cost. */
static ll_status expand_medium(void *user, ll_layer *l, double tau)
{
    build *b = user;
    return ll_layer_expand(l, tau, next_call(b, "medium", b->word_cost));
}

static ll_status build_word(build *b, size_t w, size_t c, ll_layer **out)
{
    const ll_word_params *p = &b->params[w][c];
    ll_layer *l = NULL;
    double done_before = b->done;
    ll_word_build_ctx ctx;
    ll_status s;

    *out = NULL;
    report(b, p->desc->stage);
    s = ll_layer_create(b->nodes, b->weights, b->n, b->orders, &l);
    if (s != LL_OK)
        return s;
    ctx.monitor = word_monitor;
    ctx.expand = expand_medium;
    ctx.user = b;
    b->word_cost = b->cost.word[w][c];
    b->word_stage = p->desc->stage;
    s = p->desc->build(&ctx, &b->m->words[w], p, l);
    if (s != LL_OK) {
        ll_layer_destroy(l);
        return word_failed(b, w, s);
    }
    /* (The layer calls counted their share as they went.) */
    b->done = done_before + b->word_cost;
    *out = l;
    return check_cancel(b);
}

/* A builder's bases share word layers: a copy of the cached layer of equal
 * parameters (the copy shares its orders), else built and cached. */
static ll_status cached_word(build *b, size_t w, size_t c, ll_layer **out)
{
    const ll_word_params *p = &b->params[w][c];
    ll_status s = b->cache ? ll_word_cache_get(b->cache, w, p, out) : LL_OK;
    if (s != LL_OK || (b->cache && *out)) {
        b->done += b->cost.word[w][c];
        return s;
    }
    s = build_word(b, w, c, out);
    if (s == LL_OK && b->cache)
        s = ll_word_cache_put(b->cache, w, p, *out);
    if (s != LL_OK) {
        ll_layer_destroy(*out);
        *out = NULL;
    }
    return s;
}

/*
 * A channel's stack is final once the top word is on it: with a sink, it
 * goes to the file at once (for every channel whose stack it is) and is
 * freed, so that the next channel's adding runs without it (kept, the dust
 * on gold's three finished stacks of about 0.45 GB each were alive beside
 * the third channel's adding). The order of the calls changes no byte of the
 * file (writer/bsdf_write_channels.c).
 */
static ll_status finish_channel(build *b, size_t c, const size_t owner[3], ll_layer *acc[3])
{
    size_t d;
    ll_status s = LL_OK;
    for (d = 0; d < b->nch && s == LL_OK; ++d) {
        if (owner[d] != c)
            continue;
        if (b->o.channel_done)
            b->o.channel_done(b->o.channel_done_user, d, acc[c]);
        s = ll_channel_writer_add(b->sink, d, acc[c], next_call(b, "writing", 0.0));
    }
    ll_layer_destroy(acc[c]);
    acc[c] = NULL;
    return s == LL_OK ? check_cancel(b) : s;
}

/*
 * A streamed build makes a channel's bottom word only when the level above
 * first needs it (add_level), so that the next channel's is not alive
 * while this one's stack grows and goes to the file: the dust on gold held
 * all three gold layers beside the first channel's adding. The bottom's
 * owners never share a word (owner and same word coincide there), so each
 * is its own word layer, as the clone of it was.
 */
static ll_status ensure_bottom(build *b, size_t c, ll_layer *acc[3])
{
    if (!b->pending || acc[c])
        return LL_OK;
    return cached_word(b, b->pending_word, c, &acc[c]);
}

/* One level of the stack (lv: the sharing walk's): its word on top of acc. */
static ll_status add_level(build *b, const ll_level_walk *lv, ll_layer *acc[3])
{
    ll_layer *word[3] = { NULL, NULL, NULL };
    const size_t w = lv->word, *below = lv->below, *owner = lv->owner;
    const int bottom = lv->bottom, top = lv->top;
    size_t c;
    ll_status s = LL_OK;

    if (bottom && !top && b->sink) {
        b->pending = 1;
        b->pending_word = w;
        return LL_OK;
    }
    for (c = 0; c < b->nch && s == LL_OK; ++c) {
        size_t same = lv->same[c];
        if (owner[c] != c)
            continue; /* this channel's stack is another's */
        if (same != c && word[same])
            word[c] = word[same];
        else
            s = cached_word(b, w, c, &word[c]);
    }
    /* Channels that part from a shared stack here start from a copy of it
     * as it was below this word; copy all before adding to any. */
    for (c = 0; c < b->nch && s == LL_OK; ++c)
        if (owner[c] == c && !bottom && below[c] != c &&
            (s = ensure_bottom(b, below[c], acc)) == LL_OK)
            s = ll_layer_clone(acc[below[c]], &acc[c]);
    for (c = 0; c < b->nch && s == LL_OK; ++c) {
        if (owner[c] != c)
            continue;
        if (bottom) {
            s = ll_layer_clone(word[c], &acc[c]);
        } else {
            double cost = b->cost.add, start;
            if ((s = ensure_bottom(b, c, acc)) != LL_OK)
                break;
            report(b, "adding");
            start = b->done;
            /* word[c] on top of acc[c] (ll_layer_add_to_top, with a monitor) */
            s = ll_layer_add(word[c], acc[c], acc[c], 0, next_call(b, "adding", cost));
            if (b->cache && s == LL_OK)
                ll_word_cache_count_addition(b->cache);
            if (s != LL_OK)
                s = word_failed(b, w, s);
            b->done = start + cost;
            if (s == LL_OK)
                s = check_cancel(b);
        }
        if (s == LL_OK && top && b->sink)
            s = finish_channel(b, c, owner, acc);
    }
    for (c = 0; c < b->nch; ++c)
        if (word[c] && lv->same[c] == c)
            ll_layer_destroy(word[c]);
    if (!bottom)
        b->pending = 0; /* every stack the levels above need is made */
    return s;
}

static void build_free(build *b)
{
    ll_free(b->nodes);
    ll_free(b->weights);
    ll_free(b->params);
    ll_free(b->cost.word);
    ll_free(b->levels);
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
    if (monitor) {
        ll_monitor caller = LL_MONITOR_INIT;
        ll_status s = ll_struct_read(&caller, sizeof caller, monitor, fn, "ll_monitor");
        if (s != LL_OK)
            return s;
        b->monitor_fn = caller.progress;
        b->monitor_user = caller.user;
    }
    return ll_build_options_read(opts, &b->o, fn);
}

/* The header a file of this material carries, in full (the stack's
 * eta and roughness, the metadata, the error goal). */
static void fill_header(const ll_material *m, const ll_build_options *o, size_t n_channels,
                        ll_bsdf_write_options *header)
{
    ll_bsdf_write_options full = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_material_header(m, n_channels, &full.eta, full.alpha);
    full.metadata = m->metadata;
    full.error_goal = o->error_goal > 0.0   ? o->error_goal
                      : m->error_goal > 0.0 ? m->error_goal
                                            : 1e-3;
    *header = full;
}

/* The build's header handed to the caller (fields that header's
 * struct_size covers; checked before the build: cannot fail). */
static void give_header(const build *b, ll_bsdf_write_options *header)
{
    (void)ll_struct_write(header, &b->header, sizeof b->header, "ll_material_build_layers",
                          "ll_bsdf_write_options");
}

/* Resolution, budget, quadrature and per-channel parameters. share: a
 * distributed build's (nullable), whose ranks hold 1 / n_ranks each;
 * streamed: the budget is the streamed build's (ll_material_build). */
static ll_status build_init(build *b, const ll_material *m, const ll_build_options *opts,
                            const ll_monitor *monitor, const char *fn, ll_share *share,
                            int streamed)
{
    double peak;
    ll_status s = build_start(b, m, opts, monitor, fn);
    b->share = share;
    if (s == LL_OK)
        s = ll_material_plan(m, &b->o, next_call(b, "resolution", 0.0), &b->n, &b->orders,
                             &b->nch);
    if (s != LL_OK)
        return s;
    /* The parameters (as many as the words), then the budget: nothing
     * that grows with the resolution is allocated before it. */
    b->params = ll_calloc_array(m->count, sizeof *b->params);
    b->cost.word = ll_calloc_array(m->count, sizeof *b->cost.word);
    b->levels = ll_calloc_array(m->count, sizeof *b->levels);
    if (!b->params || !b->cost.word || !b->levels) {
        build_free(b);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    }
    ll_material_params(m, b->nch, b->params);
    ll_material_levels((const ll_word_params(*)[3])b->params, m->count, b->nch, b->levels);
    fill_header(m, &b->o, b->nch, &b->header);
    /* The cost on the threads the build runs on (run_build sets them). */
    s = ll_material_cost_build(m, (const ll_word_params(*)[3])b->params, b->levels, b->n,
                               b->orders, b->nch,
                               b->o.threads ? b->o.threads : ll_get_thread_count(), streamed,
                               share ? share->n_ranks : 1, b->o.max_memory_bytes, fn, &peak,
                               &b->cost);
    if (share)
        share->peak_bytes = peak;
    if (s != LL_OK) {
        build_free(b);
        return s;
    }
    b->nodes = ll_alloc_array(b->n, sizeof(double));
    b->weights = ll_alloc_array(b->n, sizeof(double));
    if (!b->nodes || !b->weights) {
        build_free(b);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    }
    /* Gauss-Lobatto nodes, as the original recipes use (O(n^2): seconds at
     * n = 30000, so polled like every other stage). */
    s = ll_quad_gauss_lobatto(b->n, b->nodes, b->weights, next_call(b, "quadrature", 0.0));
    if (s != LL_OK)
        build_free(b);
    return s;
}

/* The build proper, on an initialised state; restores the thread count. */
static ll_status run_build(build *b, ll_layer *layers[3], double extra_cost)
{
    static const size_t no_stack[3] = { 0, 0, 0 };
    ll_layer *acc[3] = { NULL, NULL, NULL };
    size_t k, c, saved_threads = ll_get_thread_count();
    /* After the last level: whose stack each channel's is. */
    const size_t *owner = b->m->count ? b->levels[b->m->count - 1].owner : no_stack;
    ll_status s = LL_OK;

    if (b->o.threads)
        s = ll_set_thread_count(b->o.threads);
    b->total = b->cost.total + extra_cost;
    for (k = 0; k < b->m->count && s == LL_OK; ++k)
        s = add_level(b, &b->levels[k], acc);
    for (c = 0; c < b->nch && s == LL_OK && !b->sink; ++c)
        if (owner[c] != c)
            s = ll_layer_clone(acc[owner[c]], &layers[c]);
    if (s == LL_OK && !b->sink)
        for (c = 0; c < b->nch; ++c)
            if (owner[c] == c) {
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
                                   const ll_monitor *monitor, ll_layer *layers[3],
                                   size_t *n_channels, ll_bsdf_write_options *header)
{
    if (material && material->n_axes > 0) {
        if (layers)
            layers[0] = layers[1] = layers[2] = NULL;
        if (n_channels)
            *n_channels = 0;
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_build_layers: %s has %zu swept parameters (%zu bases); "
                       "build its file with ll_material_build, or its bases one at a time "
                       "with ll_material_builder_build_basis",
                       material->source, material->n_axes, ll_material_basis_count(material));
    }
    return ll_material_build_layers_cached(material, opts, monitor, NULL, layers, n_channels,
                                           header);
}

ll_status ll_material_build_layers_cached(const ll_material *material,
                                          const ll_build_options *opts,
                                          const ll_monitor *monitor, ll_word_cache *cache,
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
    if (header) {
        s = ll_struct_check(header, "ll_material_build_layers", "ll_bsdf_write_options");
        if (s != LL_OK)
            return s;
    }
    s = build_init(&b, material, opts, monitor, "ll_material_build_layers", NULL, 0);
    if (s != LL_OK)
        return s;
    b.cache = cache;
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
            give_header(&b, header);
    } else {
        for (c = 0; c < 3; ++c) {
            ll_layer_destroy(layers[c]);
            layers[c] = NULL;
        }
    }
    build_free(&b);
    return s;
}

/* Written through the writer's own atomic write (a hidden temporary beside
 * out_path, renamed over it), the caller's monitor its monitor: its last
 * report comes before the rename, so a cancel that arrives while the writer
 * runs still leaves no file. */
ll_status ll_material_write(const ll_material *material, const ll_build_options *opts,
                            ll_layer *const *layers, size_t n_channels, const char *out_path,
                            const ll_monitor *monitor)
{
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_build_options o;
    size_t c;
    ll_status s;
    if (!material || !layers || !out_path || !*out_path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_write: material, layers or out_path is NULL or empty");
    if (n_channels != 1 && n_channels != 3)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_write: n_channels = %zu; expected 1 or 3", n_channels);
    if (material->n_axes > 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_write: %s has swept parameters: its file holds %zu bases "
                       "(ll_material_build writes it, or ll_bsdf_writer_* basis by basis)",
                       material->source, ll_material_basis_count(material));
    for (c = 0; c < n_channels; ++c)
        if (!layers[c])
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_write: layers[%zu] is NULL",
                           c);
    s = ll_build_options_read(opts, &o, "ll_material_write");
    if (s != LL_OK)
        return s;
    fill_header(material, &o, n_channels, &header);
    return ll_bsdf_write(out_path, (const ll_layer *const *)layers, n_channels, &header,
                         monitor);
}

ll_status ll_material_build(const ll_material *material, const ll_build_options *opts,
                            const ll_monitor *monitor, const char *out_path)
{
    build b;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    ll_status s;
    size_t c;

    if (!out_path || !*out_path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_build: out_path is NULL or empty");
    if (material && material->n_axes > 0)
        return ll_material_build_textured(material, opts, monitor, out_path);
    s = build_init(&b, material, opts, monitor, "ll_material_build", NULL, 1);
    if (s != LL_OK)
        return s;
    s = ll_channel_writer_open(out_path, b.nch, &b.header, &b.sink);
    if (s == LL_OK) /* with the writing's share of the progress bar */
        s = run_build(&b, layers, b.cost.write);
    if (s == LL_OK) {
        const ll_monitor *writing;
        report(&b, "writing");
        writing = next_call(&b, "writing", b.total - b.done);
        b.call_ends_build = 1;
        /* The writer's last report, before the file replaces out_path, is
         * the build's last: the caller's monitor gets no "done" after it. */
        s = ll_channel_writer_commit(b.sink, writing);
        b.sink = NULL;
    }
    ll_channel_writer_abort(b.sink);
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
    build_free(&b);
    return s;
}

/* ------------------------------------------------- distributed builds
 * (layerlab/ll_distribution.h): the same build on every rank, each word
 * layer keeping only the rank's orders (the split of layer/split.h, the
 * exchanges of distribution/share.c), and the
 * finished stack gathered on rank 0. Every path through here makes the
 * same sequence of agreements and exchanges on every rank. */

static ll_status share_read(ll_share *share, const ll_distribution *dist, const char *fn)
{
    ll_distribution d = LL_DISTRIBUTION_INIT;
    ll_status s;
    memset(share, 0, sizeof *share);
    if (!dist)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: dist is NULL", fn);
    s = ll_struct_read(&d, sizeof d, dist, fn, "ll_distribution");
    if (s != LL_OK)
        return s;
    if (d.n_ranks < 1 || d.rank < 0 || d.rank >= d.n_ranks || !d.alltoallv)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the distribution has rank %d of %d ranks and %s alltoallv; "
                       "expected 0 <= rank < n_ranks and a function",
                       fn, d.rank, d.n_ranks, d.alltoallv ? "an" : "no");
    return ll_share_begin(share, &d);
}

/* The build on every rank; s: this rank's state so far (a failure is only
 * agreed). On success rank 0 holds the layers whole, the others none. */
static ll_status build_shared(const ll_material *material, const ll_build_options *opts,
                              const ll_monitor *monitor, ll_share *share, ll_status s,
                              ll_layer *layers[3], size_t *n_channels,
                              ll_bsdf_write_options *header, const char *fn)
{
    build b;
    int initialised = 0;
    size_t c;

    if (s == LL_OK && material && material->n_axes > 0)
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                    "%s: %s is swept (%zu bases): distribute its bases instead, each "
                    "built with an ll_material_builder (llbuild-mpi does)",
                    fn, material->source, ll_material_basis_count(material));
    if (s == LL_OK)
        s = build_init(&b, material, opts, monitor, fn, share, 0);
    if (s == LL_OK) {
        /* Every layer call of the build computes this rank's orders only
         * (layer/split.h), its interfaces exchanging their columns. */
        ll_split split = ll_share_split(share);
        const ll_split *previous = ll_split_enter(&split);
        initialised = 1;
        s = run_build(&b, layers, 0.0);
        ll_split_leave(previous);
    }
    if (!share->settled)
        s = ll_share_agree(share, s);
    if (s == LL_OK)
        s = ll_share_gather_layers(share, layers, b.nch);
    if (s == LL_OK) {
        b.done = b.total;
        report(&b, "done");
        s = check_cancel(&b);
    }
    if (!share->settled)
        s = ll_share_agree(share, s);
    if (s == LL_OK) {
        *n_channels = b.nch;
        if (header && share->rank == 0)
            give_header(&b, header);
    }
    if (s != LL_OK || share->rank != 0)
        for (c = 0; c < 3; ++c) {
            ll_layer_destroy(layers[c]);
            layers[c] = NULL;
        }
    if (initialised)
        build_free(&b);
    return s;
}

ll_status ll_material_build_layers_distributed(const ll_material *material,
                                               const ll_build_options *opts,
                                               const ll_monitor *monitor,
                                               const ll_distribution *dist,
                                               ll_layer *layers[3], size_t *n_channels,
                                               ll_bsdf_write_options *header)
{
    static const char fn[] = "ll_material_build_layers_distributed";
    ll_share share;
    ll_status s;
    size_t c;

    if (!layers || !n_channels)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers or n_channels is NULL", fn);
    for (c = 0; c < 3; ++c)
        layers[c] = NULL;
    *n_channels = 0;
    s = share_read(&share, dist, fn);
    if (s != LL_OK)
        return s; /* no collective to agree with */
    if (header)
        s = ll_struct_check(header, fn, "ll_bsdf_write_options");
    s = build_shared(material, opts, monitor, &share, s, layers, n_channels, header, fn);
    ll_share_end(&share);
    return s;
}

ll_status ll_material_build_distributed(const ll_material *material,
                                        const ll_build_options *opts,
                                        const ll_monitor *monitor,
                                        const ll_distribution *dist, const char *out_path)
{
    static const char fn[] = "ll_material_build_distributed";
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n_channels = 0, c;
    ll_share share;
    ll_status s = share_read(&share, dist, fn);

    if (s != LL_OK)
        return s;
    if (share.rank == 0 && (!out_path || !*out_path))
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: out_path is NULL or empty", fn);
    s = build_shared(material, opts, monitor, &share, s, layers, &n_channels, NULL, fn);
    if (s == LL_OK) {
        /* Rank 0 writes (atomically) while the others wait for the outcome.
         * (The monitor has seen the build's 1 already: the writing is not
         * watched.) */
        if (share.rank == 0)
            s = ll_material_write(material, opts, layers, n_channels, out_path, NULL);
        for (c = 0; c < 3; ++c)
            ll_layer_destroy(layers[c]);
        s = ll_share_agree(&share, s);
    }
    ll_share_end(&share);
    return s;
}
