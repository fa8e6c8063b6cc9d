/*
 * How big a build is: the build options as the caller's struct size allows
 * (with the memory budget's default), and the resolution (nodes, Fourier
 * orders) and channel count.
 *
 * Resolution: an explicit option wins, then the material's `set` line, then
 * the largest that any word's heuristic asks for (its descriptor's
 * resolution: the searches of ll_resolution_search_microfacet /
 * ll_resolution_search_henyey_greenstein at the build's tolerance and mu_min, capped by the words; each distinct
 * word is probed once, however many channels share it). Below
 * LL_MATERIAL_MIN_NODES nodes the quadrature itself is too coarse: the
 * albedo of `diffuse albedo=0.5` computed with n Gauss-Lobatto nodes was
 * measured as 1.0000 (n = 2), 0.5393 (4), 0.5145 (6), 0.5076 (8), 0.5047
 * (10), 0.5017 (16): an error that falls like 1/n^2 and is below 1% from
 * 10 nodes on, which the heuristics never go below either.
 */
/* sysconf(_SC_PHYS_PAGES) is a common extension, outside POSIX. */
#define _DEFAULT_SOURCE 1

#include "material/word_table.h"
#include "search/probe.h"

#include <stddef.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* Half of the physical memory, or 4 GiB where it cannot be found. */
static size_t default_budget(void)
{
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGESIZE)
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    size_t bytes;
    if (pages > 0 && page > 0 &&
        ll_size_mul((size_t)pages, (size_t)page, &bytes))
        return bytes / 2;
#endif
    return (size_t)4 << 30;
}

ll_status ll_build_options_read(const ll_build_options *in, ll_build_options *out,
                                const char *fn)
{
    ll_build_options defaults = LL_BUILD_OPTIONS_INIT;
    ll_status s;
    *out = defaults;
    out->max_memory_bytes = default_budget();
    if (!in)
        return LL_OK;
    s = ll_struct_read(out, sizeof *out, in, fn, "ll_build_options");
    if (s != LL_OK)
        return s;
    if (out->max_memory_bytes == 0)
        out->max_memory_bytes = default_budget();
    if (out->n_nodes != 0 && (out->n_nodes < 2 || out->n_nodes % 2 != 0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_nodes = %zu; a build needs an even count of at least %d (or 0 "
                       "for the default)",
                       fn, out->n_nodes, LL_MATERIAL_MIN_NODES);
    if (out->n_nodes > LL_MATERIAL_MAX_RESOLUTION)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_nodes = %zu is beyond the %d nodes supported", fn, out->n_nodes,
                       LL_MATERIAL_MAX_RESOLUTION);
    if (out->n_orders > LL_MATERIAL_MAX_RESOLUTION)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_orders = %zu is beyond the %d orders supported", fn,
                       out->n_orders, LL_MATERIAL_MAX_RESOLUTION);
    if (out->n_channels != 0 && out->n_channels != 1 && out->n_channels != 3)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_channels = %zu; expected 1, 3 or 0 (from the material)", fn,
                       out->n_channels);
    if (out->error_goal != 0.0 && !(out->error_goal > 0.0 && out->error_goal < 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: error_goal = %g; expected a value in (0, 1) (or 0 for the default)",
                       fn, out->error_goal);
    if (out->tolerance != 0.0 && !(out->tolerance >= LL_MIN_TOLERANCE && out->tolerance < 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: tolerance = %g; expected a relative error in [%g, 1) (or 0 for the "
                       "default)",
                       fn, out->tolerance, LL_MIN_TOLERANCE);
    if (out->mu_min != 0.0 && !(out->mu_min > 0.0 && out->mu_min <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: mu_min = %g; expected a cosine in (0, 1] (or 0 for the default)",
                       fn, out->mu_min);
    if (out->threads > 4096)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu threads is more than 4096", fn,
                       out->threads);
    return LL_OK;
}

/* The goal in effect: options, else the material's set, else defaults. */
static void goal_of(const ll_material *m, const ll_build_options *o, double *tolerance,
                    double *mu_min)
{
    *tolerance = o->tolerance > 0.0 ? o->tolerance
               : m->tolerance > 0.0 ? m->tolerance : LL_DEFAULT_TOLERANCE;
    *mu_min = o->mu_min > 0.0 ? o->mu_min : m->mu_min > 0.0 ? m->mu_min : LL_DEFAULT_MU_MIN;
}

/* Do two words ask for the same resolution? The same word and choice, and
 * equal values where the resolution hook reads them (resolution_reads: a
 * medium's heuristic reads only its phase function's shape, so media that
 * differ in albedo or tau share one search). */
static int same_resolution_key(const ll_word_params *a, const ll_word_params *b)
{
    unsigned reads = a->desc->resolution_reads;
    size_t k;
    if (a->desc != b->desc || a->choice != b->choice)
        return 0;
    if ((a->file || b->file) && (!a->file || !b->file || strcmp(a->file, b->file) != 0))
        return 0;
    if (reads == 0)
        return ll_word_params_equal(a, b);
    for (k = 0; k < LL_WORD_MAX_VALUES; ++k)
        if ((reads >> k & 1u) && a->v[k] != b->v[k])
            return 0;
    return 1;
}

void ll_resolution_memo_free(ll_resolution_memo *memo)
{
    ll_free(memo->key);
    ll_free(memo->answer);
    ll_free(memo->error);
    memo->key = NULL;
    memo->answer = NULL;
    memo->error = NULL;
    memo->count = memo->capacity = 0;
}

/* Has a word of this key been answered in this plan (memo)? */
static int memo_find(const ll_resolution_memo *memo, const ll_word_params *p, size_t *n,
                     size_t *m, double *error)
{
    size_t k;
    for (k = 0; k < memo->count; ++k)
        if (same_resolution_key(&memo->key[k], p)) {
            *n = memo->answer[k][0];
            *m = memo->answer[k][1];
            *error = memo->error[k];
            return 1;
        }
    return 0;
}

/* Remember a word's answer in this plan. */
static ll_status memo_add(ll_resolution_memo *memo, const ll_word_params *p, size_t n, size_t m,
                          double error)
{
    if (memo->count == memo->capacity) {
        size_t capacity = memo->capacity ? 2 * memo->capacity : 8;
        ll_word_params *key = ll_realloc_array(memo->key, capacity, sizeof *key);
        size_t(*answer)[2];
        double *errors;
        if (!key)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution: out of memory");
        memo->key = key;
        answer = ll_realloc_array(memo->answer, capacity, sizeof *answer);
        if (!answer)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution: out of memory");
        memo->answer = answer;
        errors = ll_realloc_array(memo->error, capacity, sizeof *errors);
        if (!errors)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution: out of memory");
        memo->error = errors;
        memo->capacity = capacity;
    }
    memo->key[memo->count] = *p;
    memo->answer[memo->count][0] = n;
    memo->answer[memo->count][1] = m;
    memo->error[memo->count] = error;
    ++memo->count;
    return LL_OK;
}

/* One word's resolution, or that of a word already probed with the same
 * key (another channel's, another basis's; or another process's, from the
 * persistent cache of cache_dir, nullable): the resolution search probes
 * layers (a second or more per word), the look-up is a comparison. start:
 * where the search starts (start_of()). */
static ll_status word_resolution(const ll_word_params *p, const size_t start[2],
                                 double tolerance, double mu_min, const char *cache_dir,
                                 ll_resolution_memo *memo, size_t *n, size_t *m, double *error)
{
    ll_status s;
    if (memo_find(memo, p, n, m, error))
        return LL_OK;
    if (!ll_resolution_cache_get(cache_dir, p, start, tolerance, mu_min, n, m, error)) {
        *error = HUGE_VAL; /* (a hook that says nothing has verified nothing) */
        *n = start[0];
        *m = start[1];
        s = p->desc->resolution(p, tolerance, mu_min, memo->watch, n, m, error);
        if (s != LL_OK)
            return s;
        ll_resolution_cache_put(cache_dir, p, start, tolerance, mu_min, *n, *m, *error);
    }
    return memo_add(memo, p, *n, *m, *error);
}

/* Where word p[i]'s search starts: a channel after the first of a word
 * whose search takes a start begins at the answer for the channel before
 * it (gold's channels at alpha 0.1 each chose 112 x 277; from the first
 * guess, 76 x 227, a channel's search took 0.09 s of CPU, from the
 * channel before 0.035 s), else at its own first guess (0, 0). Returns 0
 * while that answer is not known yet. */
static int start_of(const ll_resolution_memo *memo, const ll_word_params *p, size_t i,
                    size_t channels, size_t start[2])
{
    double unused;
    start[0] = start[1] = 0;
    if (!p[i].desc->resolution_starts || i % channels == 0)
        return 1;
    return memo_find(memo, &p[i - 1], &start[0], &start[1], &unused);
}

/* Is word i's key that of a word before it in p[0..i)? */
static int seen_before(const ll_word_params *p, size_t i)
{
    size_t k;
    for (k = 0; k < i; ++k)
        if (same_resolution_key(&p[k], &p[i]))
            return 1;
    return 0;
}

/* The largest resolution the words ask for, and the worst error it was
 * verified to. First every word's key and the answers already known (this
 * plan's memo, the persistent cache), so that the searches left are
 * counted: the progress is one stage per search, "resolution K/COUNT". */
static ll_status plan_words(const ll_material *m, size_t channels, double tolerance,
                            double mu_min, const char *cache_dir, ll_resolution_memo *memo,
                            size_t *n_out, size_t *orders_out, double *worst_out)
{
    double above[3] = { 1.0, 1.0, 1.0 }, worst = 0.0;
    size_t count = m->count * channels, w, c, i, todo = 0, searched = 0, n = 0, orders = 0;
    ll_word_params *p = ll_alloc_array(count ? count : 1, sizeof *p);
    ll_status s = LL_OK;
    if (!p)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", m->source);
    for (w = 0; w < m->count; ++w)
        for (c = 0; c < channels; ++c) {
            ll_word_params_above(m, w, c, channels, above[c], &p[w * channels + c]);
            above[c] *= ll_word_index_ratio(m, w, c, channels);
        }
    for (i = 0; i < count && s == LL_OK; ++i) {
        size_t wn, wm, start[2];
        double we;
        if (memo_find(memo, &p[i], &wn, &wm, &we) || seen_before(p, i))
            continue;
        if (start_of(memo, p, i, channels, start) &&
            ll_resolution_cache_get(cache_dir, &p[i], start, tolerance, mu_min, &wn, &wm, &we))
            s = memo_add(memo, &p[i], wn, wm, we);
        else
            ++todo; /* (or remembered under a start known later) */
    }
    for (i = 0; i < count && s == LL_OK; ++i) {
        size_t wn, wm, start[2];
        double we;
        w = i / channels;
        if (!memo_find(memo, &p[i], &wn, &wm, &we)) {
            /* A search: one part of the progress. */
            if (ll_watch_stage_of(memo->watch, "resolution", searched + 1, todo,
                                  (double)searched / (double)todo, 1.0 / (double)todo,
                                  LL_PROBE_SEARCH_UNITS)) {
                s = ll_fail(LL_ERROR_CANCELLED, "%s: cancelled while choosing the resolution",
                            m->source);
                break;
            }
            ++searched;
            (void)start_of(memo, p, i, channels, start); /* (the channel before is known) */
            s = word_resolution(&p[i], start, tolerance, mu_min, cache_dir, memo, &wn, &wm,
                                &we);
            if (s == LL_ERROR_CANCELLED)
                break; /* (its message stands: no fault of the word) */
            if (s != LL_OK) {
                char detail[700]; /* (the message is rewritten below) */
                snprintf(detail, sizeof detail, "%s", ll_last_error_message());
                s = ll_fail(s, "%s:%zu:%zu: no resolution heuristic for this %s: %s",
                            m->source, m->words[w].line, m->words[w].column, p[i].desc->name,
                            detail);
                break;
            }
        }
        if (wn > n)
            n = wn;
        if (wm > orders)
            orders = wm;
        if (!(we <= worst)) /* (HUGE_VAL and NaN stay the worst) */
            worst = we;
    }
    ll_free(p);
    *n_out = n;
    *orders_out = orders;
    *worst_out = worst;
    return s;
}

ll_status ll_material_plan_memo(const ll_material *m, const ll_build_options *o,
                                ll_resolution_memo *memo, size_t *n_nodes, size_t *n_orders,
                                size_t *n_channels, double *error)
{
    size_t channels, n = 0, orders = 0;
    double tolerance, mu_min, worst = -1.0; /* -1: given, not chosen */
    ll_status s;

    channels = o->n_channels ? o->n_channels
             : m->channels  ? m->channels
             : ll_material_is_rgb(m) ? 3 : 1;
    goal_of(m, o, &tolerance, &mu_min);
    if (!(o->n_nodes || m->nodes) || !(o->n_orders || m->orders)) {
        s = plan_words(m, channels, tolerance, mu_min, o->cache_dir, memo, &n, &orders, &worst);
        if (s != LL_OK)
            return s;
    }
    if (n % 2)
        ++n;
    if (n < LL_MATERIAL_MIN_NODES)
        n = LL_MATERIAL_MIN_NODES;
    n = o->n_nodes ? o->n_nodes : m->nodes ? m->nodes : n;
    if (n < LL_MATERIAL_MIN_NODES)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: %zu nodes is below the %d a build needs: with fewer, the "
                       "quadrature's error in an albedo is above 1%% (2 nodes: 100%%, 4: "
                       "8%%, 8: 1.5%%; docs/material-language.md, \"Settings\")",
                       m->source, n, LL_MATERIAL_MIN_NODES);
    orders = o->n_orders ? o->n_orders : m->orders ? m->orders : orders;
    if (n > LL_MATERIAL_MAX_RESOLUTION || orders > LL_MATERIAL_MAX_RESOLUTION)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the heuristics ask for %zu nodes x %zu orders, beyond the %d "
                       "supported; give the resolution with set nodes=N orders=M",
                       m->source, n, orders, LL_MATERIAL_MAX_RESOLUTION);
    /* A resolution given in part keeps the searched error of the other
     * part only when both were searched. */
    if ((o->n_nodes || m->nodes) || (o->n_orders || m->orders))
        worst = -1.0;
    *n_nodes = n;
    *n_orders = orders;
    *n_channels = channels;
    if (error)
        *error = worst;
    return LL_OK;
}

ll_status ll_material_plan(const ll_material *m, const ll_build_options *o,
                              const ll_monitor *monitor, size_t *n_nodes, size_t *n_orders,
                              size_t *n_channels)
{
    static const char fn[] = "resolution";
    ll_resolution_memo memo = LL_RESOLUTION_MEMO_INIT;
    ll_watch watch;
    ll_status s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    memo.watch = &watch;
    s = ll_material_plan_memo(m, o, &memo, n_nodes, n_orders, n_channels, NULL);
    ll_resolution_memo_free(&memo);
    return ll_watch_finish(&watch, s, fn);
}

ll_status ll_material_resolution(const ll_material *material, const ll_build_options *opts,
                                 const ll_monitor *monitor, size_t *n_nodes, size_t *n_orders,
                                 size_t *n_channels)
{
    static const char fn[] = "ll_material_resolution";
    ll_build_options o;
    ll_watch watch;
    size_t n, m, c;
    ll_status s;
    if (!material)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: material is NULL", fn);
    s = ll_build_options_read(opts, &o, fn);
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, fn);
    if (s == LL_OK)
        s = ll_material_plan_bases(material, &o, &watch, &n, &m, &c, NULL);
    s = s == LL_OK ? ll_watch_finish(&watch, s, fn) : s;
    if (s != LL_OK)
        return s;
    if (n_nodes)
        *n_nodes = n;
    if (n_orders)
        *n_orders = m;
    if (n_channels)
        *n_channels = c;
    return LL_OK;
}


ll_status ll_material_goal(const ll_material *material, const ll_build_options *opts,
                           double *tolerance, double *mu_min, int *chosen)
{
    ll_build_options o;
    double t, mu;
    ll_status s;
    if (!material)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_goal: material is NULL");
    s = ll_build_options_read(opts, &o, "ll_material_goal");
    if (s != LL_OK)
        return s;
    goal_of(material, &o, &t, &mu);
    if (tolerance)
        *tolerance = t;
    if (mu_min)
        *mu_min = mu;
    if (chosen)
        *chosen = !((o.n_nodes || material->nodes) && (o.n_orders || material->orders));
    return LL_OK;
}
