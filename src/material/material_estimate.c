/*
 * The cost of a build, from counts alone: the resolution, the words and
 * the channels, with no quadrature and no allocation that grows with the
 * resolution, so that an estimate is instant for any input and the memory
 * budget can refuse a build before it allocates anything.
 *
 * The model follows the build of material_build.c step by step (the same
 * sharing between channels: the walk of material_sharing.c): each word's layer (its descriptor's cost),
 * each adding step, each doubling of a medium, the writing. It gives the
 * peak memory (an upper bound, which the budget is checked against) and
 * the work by kind (ll_work): counts, not seconds. The rates below were
 * measured stage by stage (x86-64, 2 cores,
 * OpenBLAS; docs/material-language.md, "Estimates") and serve only as the
 * relative weights of the build's progress; the time a build takes is
 * llbuild's model (tools/llbuild/time_model.c), from the counts.
 */
#include "material/word_table.h"
#include "grammar/grammar.h"
#include "grammar/slab.h"
#include "words/microfacet.h"

#include <math.h>
#include <stdio.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* A rough interface, measured at n = 40 to 300 and m = 20 to 600: the
 * pairs (mu_o, mu_i) dominate (the Chebyshev samples, Filon's rule where a
 * kink is), a dielectric's growing with its roughness, plus a little per
 * order and pair (less per pair at more nodes: 1.5e-9 (200 / n) s; the
 * coated-diffuse recipe's 1098 x 2103 coat took 2.1 s). Its stored values
 * come to about 14 + 5.7 ln(1/alpha) dense orders for a dielectric (measured
 * 34, 31, 24, 19 at alpha = 0.02, 0.05, 0.1, 0.3; since, 26.75 at 0.1 with
 * (442, 278) and 19.15 at 0.3 with (318, 101)) and 8.6 ln(1/alpha) - 3.3
 * for a conductor (25, 23, 15, 9, 6 at 0.02, 0.05, 0.1, 0.2, 0.3; since,
 * 23.9 at 0.02 with (400, 800), 16.25 at 0.1 with (442, 328), 9.29 at 0.2
 * with (174, 190)), whatever n and m: an upper bound of what the layer
 * holds, as the memory budget needs (the constants were 12 and -4.8, below
 * the later measurements); each thread
 * keeps a column of every order, 12 doubles deep. About half of the time
 * does not gain from more threads (coated-gold, mostly interfaces: 0.66 s
 * on one thread, 0.50 s on two; plastic 0.16 s on both). */
#define COST_PAIR_DIELECTRIC 2.9e-6 /* s per pair at alpha = 0.1, n = 200;
                                       about like alpha n^(1/3) */
#define COST_PAIR_CONDUCTOR 9e-7
#define COST_PAIR_ORDER 1.5e-9

/* Writing: seconds per stored value (spline fits, float conversion). */
#define COST_WRITE 3e-8
/* A process: the resident memory of the library before any layer. */
#define PROCESS_BYTES (7.5 * 1048576.0)
/* Per stored order: its segment table. */
#define ORDER_BYTES(n) (16.0 * (2.0 * (double)(n) + 1.0) + 64.0)
/* The adding's dense h x h blocks per thread (a medium's slab scratch is
 * the medium word's thread_bytes). */
#define ADD_WORKSPACE_BLOCKS 12.0

static double parallel(double seconds, size_t items, size_t threads)
{
    size_t t = threads < items ? threads : items;
    return seconds / (double)(t ? t : 1);
}

size_t ll_doubling_count(double tau, double min_mu)
{
    double tau0;
    size_t k;
    ll_expand_schedule(tau, min_mu, &tau0, &k);
    return k;
}

/* A GGX interface's time over a Beckmann one's at the same (n, m), as
 * measured at the fits' resolutions for alpha 0.05 .. 0.8 (one thread):
 * every pair scatters (GGX's tails reach every azimuth), and a kink
 * anywhere on the circle takes the Filon path; the dielectric's kinks
 * (the end of refraction) are the most (23, 11, 2.5, 1.7 and 1.3 times at
 * alpha 0.05, 0.1, 0.3, 0.5 and 0.8; the conductor's 5.4, 5.9, 2.2, 1.9
 * and 1.25). */
static double ggx_factor(double alpha, int conductor)
{
    return conductor ? 1.0 + 0.25 / alpha : 1.0 + 0.212 * pow(alpha, -1.55);
}

void ll_interface_cost(double alpha, double eta_re, double eta_im, int distribution, size_t n,
                       size_t m, ll_word_cost *out)
{
    double pairs = (double)n * (double)n, a = alpha > 0.0 ? alpha : 1.0;
    double per_pair = eta_im > 0.0 ? COST_PAIR_CONDUCTOR
                                   : COST_PAIR_DIELECTRIC * pow((double)n / 200.0, 0.33) *
                                         (a / 0.1);
    (void)eta_re;
    out->work.dielectric_pairs = eta_im > 0.0 ? 0.0 : 0.5 * pairs * (a / 0.1);
    out->work.conductor_pairs = eta_im > 0.0 ? 0.5 * pairs : 0.0;
    out->work.pair_orders = 0.5 * pairs * (double)m;
    out->parallel_seconds =
        0.5 * pairs * (per_pair + COST_PAIR_ORDER * (200.0 / (double)n) * (double)m);
    if (distribution == LL_DISTRIBUTION_GGX)
        out->parallel_seconds *= ggx_factor(a, eta_im > 0.0);
    out->serial_seconds = out->parallel_seconds;
    out->items = n;
    out->orders_nonzero = (double)m;
    out->dense_orders = eta_im > 0.0 ? fmax(2.0, 8.6 * log(1.0 / a) - 3.3)
                                     : 14.0 + 5.7 * log(1.0 / fmin(a, 1.0));
    if (out->dense_orders > (double)m)
        out->dense_orders = (double)m;
    out->thread_bytes = 12.0 * 8.0 * (double)n * (double)m;
}

void ll_work_add(ll_work *acc, const ll_work *w, double times)
{
    acc->dielectric_pairs += times * w->dielectric_pairs;
    acc->conductor_pairs += times * w->conductor_pairs;
    acc->pair_orders += times * w->pair_orders;
    acc->measured_lookups += times * w->measured_lookups;
    acc->measured_files += times * w->measured_files;
    acc->phase_entries += times * w->phase_entries;
    acc->diffuse_entries += times * w->diffuse_entries;
    acc->add_entries += times * w->add_entries;
    acc->add_empty_entries += times * w->add_empty_entries;
}

/* The work of `steps` adding steps between layers holding a_orders and
 * b_orders of the m orders. */
static void add_work(ll_work *w, size_t n, double a_orders, double b_orders, size_t m,
                     double steps)
{
    double both = fmin(a_orders, b_orders), pairs = (double)n * (double)n;
    w->add_entries += steps * pairs * both;
    w->add_empty_entries += steps * pairs * ((double)m - both);
}

/* CPU seconds (one thread) of one adding step between layers holding
 * a_orders and b_orders of the m orders. */
static double add_cpu(size_t n, double a_orders, double b_orders, size_t m)
{
    double both = fmin(a_orders, b_orders), pairs = (double)n * (double)n;
    return pairs * (both * LL_COST_ADD_ORDER + ((double)m - both) * LL_COST_ADD_EMPTY);
}

/* Bytes a layer keeps: its stored values and every order's segments. */
static double layer_bytes(size_t n, size_t m, double dense_orders)
{
    return 8.0 * (double)n * (double)n * dense_orders + (double)m * ORDER_BYTES(n);
}

static double cost_add(size_t n, size_t m, size_t threads)
{
    return parallel(add_cpu(n, (double)m, (double)m, m), m, threads);
}

static void word_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *c)
{
    memset(c, 0, sizeof *c);
    c->items = 1;
    p->desc->cost(p, n, m, c);
    if (c->orders_nonzero > (double)m)
        c->orders_nonzero = (double)m;
}

/* CPU and wall seconds of one word's layer with its thickness: per dense
 * order the doublings' adding steps, or the slab's equivalent where
 * ll_layer_expand takes the slab (grammar/slab.h). */
static void word_seconds(const ll_word_cost *c, size_t n, size_t m, size_t threads,
                         double *cpu, double *wall)
{
    double d = ll_expand_order_steps(n / 2, c->doublings) *
               add_cpu(n, c->orders_nonzero, c->orders_nonzero, m);
    *cpu = c->parallel_seconds + c->serial_seconds + d;
    *wall = parallel(c->parallel_seconds, c->items, threads) + c->serial_seconds +
            parallel(d, (size_t)c->orders_nonzero, threads);
}

/* One word's work with its thickness (as word_seconds). */
static void word_work(const ll_word_cost *c, size_t n, size_t m, ll_work *out)
{
    *out = c->work;
    add_work(out, n, c->orders_nonzero, c->orders_nonzero, m,
             ll_expand_order_steps(n / 2, c->doublings));
}

double ll_cost_process_bytes(void)
{
    return PROCESS_BYTES;
}

void ll_cost_word_detail(const ll_word_params *p, size_t n, size_t m, ll_work *work,
                         size_t *doublings, double *bytes)
{
    ll_word_cost c;
    word_cost(p, n, m, &c);
    word_work(&c, n, m, work);
    *doublings = c.doublings;
    *bytes = layer_bytes(n, m, c.dense_orders);
}

static double cost_word(const ll_word_params *p, size_t n, size_t m, size_t threads)
{
    ll_word_cost c;
    double cpu, wall;
    word_cost(p, n, m, &c);
    word_seconds(&c, n, m, threads, &cpu, &wall);
    return wall;
}

static double cost_write(size_t n, size_t m, size_t n_channels)
{
    /* (Progress shares only: about 17 dense orders per channel.) */
    double dense = 17.0 < (double)m ? 17.0 : (double)m;
    return (double)n * (double)n * dense * (double)n_channels * COST_WRITE;
}

/*
 * The peak of a streamed build (ll_material_build, material_build.c),
 * replayed step by step in the order the build makes and frees
 * things, the bytes alive after each step and the transient ones during it:
 *
 * - The bottom word is not made with its level: each channel's is built
 *   when the level above first needs it (ensure_bottom), so one channel's
 *   (one gold layer) is alive at a time where the channels differ there.
 * - A level's words are all built before its first adding (one layer per
 *   distinct word, shared by the channels whose parameters agree) and are
 *   freed after its last; a word under construction holds its builder's
 *   scratch per thread and its table once (thread_bytes, build_bytes).
 * - An adding holds the stack, the word and the whole result (the stack's
 *   orders are replaced at the one commit point, ll_layer_commit_orders),
 *   and per thread 17 h x h doubles (grammar/adding.c's workspace).
 * - Channels that part from a shared stack start from a clone sharing its
 *   orders: the old orders go only once the last holder has replaced them.
 * - At the top, each channel's finished stack goes to the channel writer
 *   and is freed: the writer keeps only n x n tables in memory (per channel
 *   its order 0 and extents, 12 n^2 bytes; shared the lengths, offsets and
 *   a channel's scratch lengths, 8 (n + 2)^2 + 12 n^2 bytes; a 1 MiB spill
 *   buffer) and spills the stored values to disk beside the output; while
 *   it takes a channel it stages one column of every order (8 n m bytes).
 *   Its commit adds the CDF (4 (n + 2)^2 bytes) and one column per channel
 *   read back from the spill (at most 8 n m bytes each).
 * - A one-word material's words are its stacks (clones), so they stay
 *   until that level ends.
 *
 * The layers' own sizes are layer_bytes of the words' modelled dense
 * orders, as in the held model above; what is not modelled (the C heap's
 * fragmentation, OpenBLAS's and OpenMP's per-thread buffers) is the
 * allowance STREAM_FIXED_BYTES + STREAM_THREAD_BYTES per thread, the least
 * that kept every measured build under its estimate
 * (docs/material-language.md, "Estimates": estimate / peak RSS on the
 * examples and the dust on gold, 1 and 2 threads; frosted glass at one
 * thread needed the fixed part).
 */
#define WRITER_SPILL_BUFFER 1048576.0
#define ADD_THREAD_BLOCKS 17.0
#define STREAM_FIXED_BYTES (8.0 * 1048576.0)
#define STREAM_THREAD_BYTES (4.0 * 1048576.0)

/* Sets of orders alive (a stack's, shared by its clones): at most one per
 * channel, and the one an adding is making. */
#define STREAM_SETS 4

typedef struct stream_state {
    size_t n, m, t;
    double alive;              /* bytes held between steps (layers, the writer) */
    double peak;               /* the largest alive + transient seen            */
    double set_bytes[STREAM_SETS];
    int set_holders[STREAM_SETS]; /* stacks holding the set (0: free)          */
    int set_of[3];             /* channel c's stack's set, -1: none             */
    int writer_open;           /* a channel went to the writer                  */
} stream_state;

static void stream_need(stream_state *st, double transient)
{
    if (st->alive + transient > st->peak)
        st->peak = st->alive + transient;
}

/* A word's layer is built: its scratch while it grows, its bytes after. */
static double stream_word(stream_state *st, const ll_word_params *p)
{
    ll_word_cost wc;
    double bytes;
    word_cost(p, st->n, st->m, &wc);
    bytes = layer_bytes(st->n, st->m, wc.dense_orders);
    stream_need(st, bytes + (double)st->t * wc.thread_bytes + wc.build_bytes);
    st->alive += bytes;
    return bytes;
}

/* Channel c's stack lets go of its orders (freed once no clone shares
 * them) and, with bytes > 0, holds new ones of that size (counted alive
 * already when counted is set: a word layer that became the stack). */
static void stream_replace(stream_state *st, size_t c, double bytes, int counted)
{
    int id = st->set_of[c], k;
    if (id >= 0 && --st->set_holders[id] == 0)
        st->alive -= st->set_bytes[id];
    st->set_of[c] = -1;
    if (bytes <= 0.0)
        return;
    for (k = 0; k < STREAM_SETS && st->set_holders[k] > 0; ++k)
        ;
    /* (Three stacks hold at most three sets: a free one is left.) */
    st->set_of[c] = k;
    st->set_holders[k] = 1;
    st->set_bytes[k] = bytes;
    if (!counted)
        st->alive += bytes;
}

/* The bottom word of channel c, made when first needed (ensure_bottom). */
static void stream_bottom(stream_state *st, const ll_word_params *p, size_t c, int pending)
{
    if (pending && st->set_of[c] < 0)
        stream_replace(st, c, stream_word(st, p), 1);
}

/* A channel goes to the writer: its tables, those shared with the first. */
static void stream_write_channel(stream_state *st)
{
    double n2 = (double)st->n * (double)st->n, nn = (double)st->n + 2.0;
    double channel = 12.0 * n2;
    if (!st->writer_open) {
        st->alive += 8.0 * nn * nn + 12.0 * n2 + WRITER_SPILL_BUFFER;
        st->writer_open = 1;
    }
    stream_need(st, channel + 8.0 * (double)st->n * (double)st->m);
    st->alive += channel;
}

static double streamed_peak(const ll_material *mat, const ll_word_params (*params)[3],
                            size_t n, size_t m, size_t nch, size_t t)
{
    stream_state st;
    ll_level_walk lv;
    size_t c, bottom_word = mat->count - 1;
    double acc_dense[3] = { 0, 0, 0 }, h = (double)(n / 2), nn = (double)n + 2.0;
    int pending = 0;

    memset(&st, 0, sizeof st);
    st.n = n;
    st.m = m;
    st.t = t ? t : 1;
    for (c = 0; c < 3; ++c)
        st.set_of[c] = -1;
    ll_level_walk_begin(&lv, params, mat->count, nch);
    while (ll_level_walk_next(&lv)) {
        const size_t w = lv.word, *below = lv.below, *owner = lv.owner;
        const int bottom = lv.bottom, top = lv.top;
        double words = 0.0, dense[3];
        for (c = 0; c < nch; ++c) {
            ll_word_cost wc;
            word_cost(&params[w][c], n, m, &wc);
            /* The stack keeps about the mean of what the two hold. */
            dense[c] = bottom ? wc.dense_orders
                              : 0.5 * (acc_dense[below[c]] + wc.dense_orders);
        }
        if (bottom && !top) {
            pending = 1; /* made when the level above first needs it */
        } else {
            for (c = 0; c < nch; ++c)
                if (owner[c] == c && lv.same[c] == c)
                    words += stream_word(&st, &params[w][c]);
            /* Parting channels start from a clone of the stack below. */
            for (c = 0; c < nch && !bottom; ++c)
                if (owner[c] == c && below[c] != c) {
                    size_t b = below[c];
                    stream_bottom(&st, &params[bottom_word][b], b, pending);
                    st.set_of[c] = st.set_of[b];
                    st.set_holders[st.set_of[b]]++;
                }
            for (c = 0; c < nch; ++c) {
                if (owner[c] != c)
                    continue;
                if (!bottom) {
                    double result = layer_bytes(n, m, dense[c]);
                    stream_bottom(&st, &params[bottom_word][c], c, pending);
                    stream_need(&st, result + (double)st.t * ADD_THREAD_BLOCKS * 8.0 * h * h);
                    stream_replace(&st, c, result, 0);
                }
                /* (At a one-word material's only level the stacks are
                 * clones of the words, counted with them.) */
                if (top) {
                    size_t d;
                    for (d = 0; d < nch; ++d) /* every channel whose stack it is */
                        if (owner[d] == c)
                            stream_write_channel(&st);
                    stream_replace(&st, c, 0.0, 0);
                }
            }
            st.alive -= words;
            if (!bottom)
                pending = 0;
        }
        for (c = 0; c < nch; ++c)
            acc_dense[c] = dense[c];
    }
    /* The commit: the CDF and one column per channel from the spill. */
    stream_need(&st, 4.0 * nn * nn + (double)nch * 8.0 * (double)n * (double)m);
    return st.peak + STREAM_FIXED_BYTES + (double)st.t * STREAM_THREAD_BYTES;
}

void ll_material_cost(const ll_material *mat, const ll_word_params (*params)[3], size_t n,
                      size_t m, size_t nch, size_t threads, ll_cost_plan *out)
{
    ll_level_walk lv;
    size_t c, t = threads < m ? threads : m;
    double acc_nz[3] = { 0, 0, 0 }, acc_dense[3] = { 0, 0, 0 }, peak = 0.0;
    double h = (double)(n / 2), stored = 0.0;

    memset(out, 0, sizeof *out);
    out->n = n;
    out->m = m;
    out->channels = nch;
    out->threads = threads;
    ll_level_walk_begin(&lv, params, mat->count, nch);
    while (ll_level_walk_next(&lv)) {
        const size_t w = lv.word, *below = lv.below, *owner = lv.owner;
        const int bottom = lv.bottom;
        double words = 0.0, before = 0.0, result = 0.0, scratch = 0.0, held = 0.0;
        double nz[3], dense[3];
        for (c = 0; c < nch; ++c) {
            nz[c] = dense[c] = 0.0;
            if (!bottom && owner[c] == c)
                before += layer_bytes(n, m, acc_dense[below[c]]);
        }
        for (c = 0; c < nch; ++c) {
            ll_word_cost wc;
            const ll_word_params *p = &params[w][c];
            if (owner[c] != c)
                continue;
            word_cost(p, n, m, &wc);
            if (lv.same[c] == c) {
                ll_work ww;
                word_work(&wc, n, m, &ww);
                ++out->layers_built;
                out->doublings += wc.doublings;
                ll_work_add(&out->work, &ww, 1.0);
                words += layer_bytes(n, m, wc.dense_orders);
                if (wc.thread_bytes > scratch)
                    scratch = wc.thread_bytes;
                if (wc.build_bytes > held)
                    held = wc.build_bytes;
            }
            if (bottom) {
                nz[c] = wc.orders_nonzero;
                dense[c] = wc.dense_orders;
            } else {
                double a = acc_nz[below[c]];
                ++out->additions;
                add_work(&out->work, n, a, wc.orders_nonzero, m, 1.0);
                /* The stack keeps about the mean of what the two hold. */
                nz[c] = fmax(a, wc.orders_nonzero);
                dense[c] = fmin(0.5 * (acc_dense[below[c]] + wc.dense_orders), nz[c]);
            }
            /* (The bottom stack is a clone of the word: shared orders.) */
            if (!bottom && layer_bytes(n, m, dense[c]) > result)
                result = layer_bytes(n, m, dense[c]);
        }
        /* Live at once: the stacks below, this level's word layers with
         * their builders' scratch, the one stack being made (each channel's
         * replaces its old one when done) and the adding's dense blocks, per
         * thread. */
        scratch = scratch > ADD_WORKSPACE_BLOCKS * 8.0 * h * h ? scratch
                                                               : ADD_WORKSPACE_BLOCKS * 8.0 * h * h;
        if (before + words + result + (double)t * scratch + held > peak)
            peak = before + words + result + (double)t * scratch + held;
        for (c = 0; c < nch; ++c) {
            acc_nz[c] = nz[c];
            acc_dense[c] = dense[c];
        }
    }
    /* Writing: the finished layers and the file's float32 coefficients
     * with their spline fits (about as large again). */
    for (c = 0; c < nch; ++c)
        if (lv.owner[c] == c)
            stored += (double)n * (double)n * acc_dense[c];
    if (16.0 * stored > peak)
        peak = 16.0 * stored;
    out->stored_values = stored;
    out->held_peak_bytes = peak + PROCESS_BYTES;
    out->peak_bytes = streamed_peak(mat, params, n, m, nch, t) + PROCESS_BYTES;
}

static void format_bytes(double bytes, char *buf, size_t cap)
{
    if (bytes >= 1024.0 * 1048576.0)
        snprintf(buf, cap, "%.3g GiB", bytes / (1024.0 * 1048576.0));
    else
        snprintf(buf, cap, "%.3g MiB", bytes / 1048576.0);
}

ll_status ll_check_budget(const ll_material *mat, const ll_cost_plan *plan, size_t budget,
                          const char *fn)
{
    char need[32], have[32];
    if (plan->peak_bytes <= (double)budget)
        return LL_OK;
    format_bytes(plan->peak_bytes, need, sizeof need);
    format_bytes((double)budget, have, sizeof have);
    return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                   "%s: %s: this build (%zu nodes x %zu orders, %zu channel%s) needs about %s "
                   "at its peak, more than the memory budget of %s; raise the budget "
                   "(llbuild --max-memory SIZE, ll_build_options.max_memory_bytes; the "
                   "default is half of the physical memory) or lower the resolution",
                   fn, mat->source, plan->n, plan->m, plan->channels,
                   plan->channels == 1 ? "" : "s", need, have);
}

ll_status ll_material_cost_build(const ll_material *mat, const ll_word_params (*params)[3],
                                 const ll_level_walk *levels, size_t n, size_t m, size_t nch,
                                 size_t threads, int streamed, size_t ranks, size_t budget,
                                 const char *fn, double *peak_bytes, ll_build_weights *weights)
{
    ll_cost_plan cost;
    size_t k, c;
    ll_material_cost(mat, params, n, m, nch, threads, &cost);
    if (!streamed)
        cost.peak_bytes = cost.held_peak_bytes; /* every stack kept to the end */
    cost.peak_bytes /= (double)ranks;
    *peak_bytes = cost.peak_bytes;
    /* The weights, summed in the order the build makes its steps. */
    weights->add = cost_add(n, m, threads);
    weights->write = cost_write(n, m, nch);
    weights->total = 0.0;
    for (k = 0; k < mat->count; ++k) {
        const ll_level_walk *lv = &levels[k];
        for (c = 0; c < nch; ++c) {
            if (lv->owner[c] != c)
                continue;
            if (lv->same[c] == c) {
                weights->word[lv->word][c] = cost_word(&params[lv->word][c], n, m, threads);
                weights->total += weights->word[lv->word][c];
            }
            if (!lv->bottom)
                weights->total += weights->add;
        }
    }
    return ll_check_budget(mat, &cost, budget, fn);
}

/* The worker threads a build with these options would run on. */
static size_t build_threads(const ll_build_options *o)
{
    return o->threads ? o->threads : ll_get_thread_count();
}

ll_status ll_material_estimate(const ll_material *material, const ll_build_options *opts,
                               ll_build_estimate *estimate, const ll_monitor *monitor)
{
    static const char fn[] = "ll_material_estimate";
    ll_build_options o;
    ll_watch watch;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_word_params(*params)[3] = NULL;
    ll_cost_plan plan;
    size_t n, m, nch;
    double resolution_error;
    ll_status s;

    /* Computed in full here, then written up to the caller's struct_size:
     * an older, smaller struct gets the fields it has. */
    s = ll_struct_check(estimate, "ll_material_estimate", "ll_build_estimate");
    if (s != LL_OK)
        return s;
    if (!material)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_estimate: material is NULL");
    s = ll_build_options_read(opts, &o, fn);
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, fn);
    if (s == LL_OK) {
        /* The searches run on the build's threads, as the build does. */
        size_t saved_threads = ll_get_thread_count();
        if (o.threads)
            s = ll_set_thread_count(o.threads);
        if (s == LL_OK)
            s = ll_material_plan_bases(material, &o, &watch, &n, &m, &nch, &resolution_error);
        if (o.threads)
            ll_set_thread_count(saved_threads);
    }
    s = s == LL_OK ? ll_watch_finish(&watch, s, fn) : s;
    if (s != LL_OK)
        return s;
    if (material->n_axes > 0) {
        /* A swept material: every basis, with the builder's sharing. */
        s = ll_material_cost_bases(material, n, m, nch, build_threads(&o), &plan);
        if (s != LL_OK)
            return s;
    } else {
        params = ll_calloc_array(material->count, sizeof *params);
        if (!params)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_material_estimate: out of memory");
        ll_material_params(material, nch, params);
        ll_material_cost(material, (const ll_word_params(*)[3])params, n, m, nch,
                         build_threads(&o), &plan);
        ll_free(params);
        plan.file_bytes = ll_file_bytes_estimate(n, nch, 1, 0, plan.stored_values);
    }
    e.n_bases = ll_material_basis_count(material);
    e.file_bytes = plan.file_bytes;
    e.resolution_error = resolution_error;
    e.n_nodes = n;
    e.n_orders = m;
    e.n_channels = nch;
    e.layers_built = plan.layers_built;
    e.additions = plan.additions;
    e.doublings = plan.doublings;
    e.peak_bytes = plan.peak_bytes;
    e.threads = build_threads(&o);
    e.dielectric_pairs = plan.work.dielectric_pairs;
    e.conductor_pairs = plan.work.conductor_pairs;
    e.pair_orders = plan.work.pair_orders;
    e.measured_lookups = plan.work.measured_lookups;
    e.measured_files = plan.work.measured_files;
    e.phase_entries = plan.work.phase_entries;
    e.diffuse_entries = plan.work.diffuse_entries;
    e.add_entries = plan.work.add_entries;
    e.add_empty_entries = plan.work.add_empty_entries;
    e.stored_values = plan.stored_values;
    e.max_memory_bytes = o.max_memory_bytes;
    e.over_budget = plan.peak_bytes > (double)o.max_memory_bytes;
    return ll_struct_write(estimate, &e, sizeof e, "ll_material_estimate", "ll_build_estimate");
}
