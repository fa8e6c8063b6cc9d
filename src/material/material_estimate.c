/*
 * The cost of a build, from counts alone: the resolution, the words and
 * the channels, with no quadrature and no allocation that grows with the
 * resolution, so that an estimate is instant for any input and the memory
 * budget can refuse a build before it allocates anything.
 *
 * The model follows the build of material_build.c step by step (the same
 * sharing between channels): each word's layer (its descriptor's cost),
 * each adding step, each doubling of a medium, the writing. The rates
 * below were measured stage by stage on the development machine (x86-64,
 * 2 cores, OpenBLAS; docs/material-language.md, "Estimates", has the
 * measurements and the model's error on every example).
 */
#include "material/word_table.h"
#include "grammar/grammar.h"

#include <math.h>
#include <stdio.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* Adding (and each doubling): per Fourier order that holds anything, the
 * adding equations' products and solves of h x h blocks, about
 * ADD_FLOPS h^3 floating-point operations at RATE_FLOPS per thread. */
#define ADD_FLOPS 14.0
#define RATE_FLOPS 4e9
/* Orders that hold nothing cost a pass over their storage. */
#define RATE_ADD_EMPTY 4e8   /* (order, column) pairs per second */
/* A rough interface: (mu_o, mu_i, order) triples per second, one thread,
 * over the orders its lobe fills. */
#define RATE_INTERFACE 1.5e8
/* Writing: coefficients per second (spline fits and float conversion). */
#define RATE_WRITE 1e8

/* Memory: what a process of the library holds before any layer (code,
 * OpenBLAS's and OpenMP's buffers), per-order bookkeeping of a stored
 * order, and the adding's dense workspace per thread (h x h blocks). */
#define PROCESS_BYTES (7.0 * 1048576.0)
#define ORDER_BYTES(n) (16.0 * (2.0 * (double)(n) + 1.0) + 64.0)
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

void ll_interface_cost(double alpha, double eta_re, double eta_im, size_t n, size_t m,
                       ll_word_cost *out)
{
    size_t hn, hm;
    double used = (double)m;
    /* The lobe fills about the orders its heuristic asks for; a build at
     * more orders leaves the rest empty. */
    if (ll_heuristic_microfacet(alpha, eta_re, eta_im, &hn, &hm) == LL_OK && hm < m)
        used = (double)hm;
    out->parallel_seconds = (double)n * (double)n * used / RATE_INTERFACE;
    out->items = n;
    out->orders_used = used;
    out->fill = eta_im > 0.0 ? 0.25 : 1.0; /* a conductor reflects from above only */
}

/* Seconds (CPU, one thread) of one adding step between layers that fill
 * `used` of the m orders. */
static double add_cpu(size_t n, double used, size_t m)
{
    double h = (double)(n / 2);
    return used * ADD_FLOPS * h * h * h / RATE_FLOPS +
           ((double)m - used) * (double)n / RATE_ADD_EMPTY;
}

double ll_cost_add(size_t n, size_t m, size_t threads)
{
    return parallel(add_cpu(n, (double)m, m), m, threads);
}

static void word_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *c)
{
    memset(c, 0, sizeof *c);
    c->items = 1;
    p->desc->cost(p, n, m, c);
    if (c->orders_used > (double)m)
        c->orders_used = (double)m;
}

double ll_cost_word(const ll_word_params *p, size_t n, size_t m, size_t threads)
{
    ll_word_cost c;
    word_cost(p, n, m, &c);
    return parallel(c.parallel_seconds, c.items, threads) + c.serial_seconds +
           (double)c.doublings * parallel(add_cpu(n, c.orders_used, m),
                                          (size_t)c.orders_used, threads);
}

double ll_cost_write(size_t n, size_t m, size_t n_channels)
{
    return (double)n * (double)n * (double)m * (double)n_channels / RATE_WRITE;
}

size_t ll_same_word_as(const ll_word_params (*params)[3], size_t w, size_t c)
{
    size_t d;
    for (d = 0; d < c; ++d)
        if (ll_word_params_equal(&params[w][d], &params[w][c]))
            return d;
    return c;
}

void ll_stack_owners(const ll_word_params (*params)[3], size_t w, size_t nch,
                     const size_t *below, size_t *owner)
{
    size_t c, d;
    for (c = 0; c < nch; ++c) {
        owner[c] = c;
        for (d = 0; d < c; ++d)
            if ((!below || below[d] == below[c]) &&
                ll_word_params_equal(&params[w][d], &params[w][c])) {
                owner[c] = d;
                break;
            }
    }
}

/* Bytes a layer keeps: its filled orders' runs and every order's
 * bookkeeping. */
static double layer_bytes(size_t n, size_t m, double used, double fill)
{
    return 8.0 * (double)n * (double)n * used * fill + (double)m * ORDER_BYTES(n);
}

void ll_material_cost(const ll_material *mat, const ll_word_params (*params)[3], size_t n,
                      size_t m, size_t nch, size_t threads, ll_cost_plan *out)
{
    size_t below[3] = { 0, 0, 0 }, owner[3], w, c;
    double acc_used[3] = { 0, 0, 0 }, acc_bytes[3] = { 0, 0, 0 }, peak = 0.0;
    double h = (double)(n / 2), workspace;

    memset(out, 0, sizeof *out);
    out->n = n;
    out->m = m;
    out->channels = nch;
    out->threads = threads;
    workspace = ADD_WORKSPACE_BLOCKS * 8.0 * h * h * (double)(threads < m ? threads : m);
    for (w = mat->count; w-- > 0;) {
        int bottom = w + 1 == mat->count;
        double word_bytes = 0.0, live = 0.0;
        double new_used[3], new_bytes[3];
        ll_stack_owners(params, w, nch, bottom ? NULL : below, owner);
        for (c = 0; c < nch; ++c) {
            ll_word_cost wc;
            const ll_word_params *p = &params[w][c];
            double used;
            new_used[c] = acc_used[c];
            new_bytes[c] = 0.0;
            if (owner[c] != c)
                continue;
            word_cost(p, n, m, &wc);
            if (ll_same_word_as(params, w, c) == c) {
                double cpu = wc.parallel_seconds + wc.serial_seconds +
                             (double)wc.doublings * add_cpu(n, wc.orders_used, m);
                ++out->layers_built;
                out->doublings += wc.doublings;
                out->cpu_seconds += cpu;
                out->seconds += ll_cost_word(p, n, m, threads);
                word_bytes += layer_bytes(n, m, wc.orders_used, wc.doublings ? 1.0 : wc.fill);
            }
            /* The stack below and this word together fill the larger of
             * their orders; the stack's blocks are dense once added. */
            used = bottom ? wc.orders_used
                          : fmax(wc.orders_used, acc_used[below[c]]);
            new_used[c] = used;
            new_bytes[c] = bottom ? layer_bytes(n, m, used, wc.doublings ? 1.0 : wc.fill)
                                  : layer_bytes(n, m, used, 1.0);
            if (!bottom) {
                double cpu = add_cpu(n, used, m);
                ++out->additions;
                out->cpu_seconds += cpu;
                out->seconds += parallel(cpu, (size_t)used, threads);
            }
        }
        /* Live at once: the stacks below, this level's word layers, the
         * results being made and the workspace. */
        for (c = 0; c < nch; ++c)
            live += acc_bytes[c] + new_bytes[c];
        if (live + word_bytes + workspace > peak)
            peak = live + word_bytes + workspace;
        for (c = 0; c < nch; ++c) {
            acc_used[c] = new_used[c];
            acc_bytes[c] = new_bytes[c];
        }
        memcpy(below, owner, sizeof below);
    }
    /* Writing: the finished layers and the file's float32 coefficients. */
    {
        double kept = 0.0, file = 0.0;
        for (c = 0; c < nch; ++c) {
            kept += acc_bytes[below[c]];
            file += 4.0 * (double)n * (double)n * acc_used[below[c]];
        }
        if (kept + file > peak)
            peak = kept + file;
        out->cpu_seconds += ll_cost_write(n, m, nch);
        out->seconds += ll_cost_write(n, m, nch);
    }
    out->peak_bytes = peak + PROCESS_BYTES;
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

/* The worker threads a build with these options would run on. */
static size_t build_threads(const ll_build_options *o)
{
    return o->threads ? o->threads : ll_get_thread_count();
}

ll_status ll_material_estimate(const ll_material *material, const ll_build_options *opts,
                               ll_build_estimate *estimate)
{
    ll_build_options o;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_word_params(*params)[3] = NULL;
    ll_cost_plan plan;
    size_t n, m, nch, w, c, size;
    ll_status s;

    /* An older, smaller struct ends at `seconds`: the fields past it are
     * then not written. */
    if (!estimate || estimate->struct_size < offsetof(ll_build_estimate, seconds) +
                                                 sizeof estimate->seconds)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_material_estimate: estimate is NULL or its struct_size is smaller "
                       "than the first version of ll_build_estimate (LL_BUILD_ESTIMATE_INIT "
                       "sets it)");
    if (!material)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_estimate: material is NULL");
    s = ll_build_options_read(opts, &o, "ll_material_estimate");
    if (s == LL_OK)
        s = ll_material_plan(material, &o, &n, &m, &nch);
    if (s != LL_OK)
        return s;
    params = ll_calloc_array(material->count, sizeof *params);
    if (!params)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_material_estimate: out of memory");
    for (w = 0; w < material->count; ++w)
        for (c = 0; c < nch; ++c)
            ll_word_params_get(material, w, c, nch, &params[w][c]);
    ll_material_cost(material, (const ll_word_params(*)[3])params, n, m, nch,
                     build_threads(&o), &plan);
    free(params);
    e.n_nodes = n;
    e.n_orders = m;
    e.n_channels = nch;
    e.layers_built = plan.layers_built;
    e.additions = plan.additions;
    e.doublings = plan.doublings;
    e.peak_bytes = plan.peak_bytes;
    e.seconds = plan.seconds;
    e.cpu_seconds = plan.cpu_seconds;
    e.max_memory_bytes = o.max_memory_bytes;
    e.over_budget = plan.peak_bytes > (double)o.max_memory_bytes;
    size = estimate->struct_size < sizeof e ? estimate->struct_size : sizeof e;
    e.struct_size = estimate->struct_size;
    memcpy(estimate, &e, size);
    return LL_OK;
}
