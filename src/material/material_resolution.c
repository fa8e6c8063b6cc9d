/*
 * How big a build is: the build options as the caller's struct size allows,
 * the resolution (nodes, Fourier orders) and channel count, and a cost model
 * for progress fractions and llbuild --dry-run.
 *
 * Resolution: an explicit option wins, then the material's `set` line, then
 * the largest that any word's heuristic asks for (the original layerlab's
 * parameterHeuristicMicrofacet / parameterHeuristicHG, as
 * ll_heuristic_microfacet / ll_heuristic_henyey_greenstein).
 */
#include "material/material.h"
#include "layer/layer.h"
#include "grammar/grammar.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

/* Words without a heuristic of their own (diffuse, isotropic media) still
 * need enough nodes for multiple scattering between the layers: the HG
 * heuristic at g = 0 (10 nodes). They need one Fourier order. */
#define FLOOR_G 0.0

/* A measured BRDF: MERL tables sample theta_half on a square-root scale
 * down to (1/90)^2 of 90 degrees; their other axes in 1 or 2 degree steps.
 * 100 nodes (about 1.8 degrees between nodes near the horizon, finer near
 * the pole) and 180 orders (azimuthal detail of 1 degree) resolve the
 * tables' own step in phi_diff; sharper highlights need `set` overrides. */
#define MEASURED_NODES 100
#define MEASURED_ORDERS 180

ll_status ll_build_options_read(const ll_build_options *in, ll_build_options *out,
                                const char *fn)
{
    ll_build_options defaults = LL_BUILD_OPTIONS_INIT;
    ll_status s;
    *out = defaults;
    if (!in)
        return LL_OK;
    s = ll_struct_read(out, sizeof *out, in, fn, "ll_build_options");
    if (s != LL_OK)
        return s;
    if (out->n_nodes != 0 && (out->n_nodes < 2 || out->n_nodes % 2 != 0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_nodes = %zu; expected an even count >= 2 (or 0 for the default)",
                       fn, out->n_nodes);
    if (out->n_nodes > 100000 || out->n_orders > 100000)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: %zu nodes x %zu orders is beyond the 100000 supported", fn,
                       out->n_nodes, out->n_orders);
    if (out->n_channels != 0 && out->n_channels != 1 && out->n_channels != 3)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_channels = %zu; expected 1, 3 or 0 (from the material)", fn,
                       out->n_channels);
    if (out->error_goal != 0.0 && !(out->error_goal > 0.0 && out->error_goal < 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: error_goal = %g; expected a value in (0, 1) (or 0 for the default)",
                       fn, out->error_goal);
    if (out->threads > 4096)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu threads is more than 4096", fn,
                       out->threads);
    return LL_OK;
}

/* The von Mises-Fisher lobe's mean cosine coth(kappa) - 1/kappa: the HG
 * asymmetry of the same width, for the resolution heuristic. */
static double vmf_mean_cosine(double kappa)
{
    if (kappa < 1e-4)
        return kappa / 3.0;
    return 1.0 / tanh(kappa) - 1.0 / kappa;
}

static ll_status word_resolution(const ll_word_params *p, size_t *n, size_t *m)
{
    ll_status s;
    switch (p->kind) {
    case LL_WORD_DIELECTRIC:
    case LL_WORD_CONDUCTOR:
        return ll_heuristic_microfacet(p->alpha, p->eta_re, p->eta_im, n, m);
    case LL_WORD_MEDIUM:
        if (p->phase == LL_PHASE_ISOTROPIC) {
            s = ll_heuristic_henyey_greenstein(FLOOR_G, n, m);
            *m = 1;
            return s;
        }
        return ll_heuristic_henyey_greenstein(
            p->phase == LL_PHASE_HG ? p->shape : fmin(vmf_mean_cosine(p->shape), 0.999), n, m);
    case LL_WORD_MEASURED:
        *n = MEASURED_NODES;
        *m = MEASURED_ORDERS;
        return LL_OK;
    default:
        s = ll_heuristic_henyey_greenstein(FLOOR_G, n, m);
        *m = 1;
        return s;
    }
}

ll_status ll_material_plan(const ll_material *m, const ll_build_options *o, size_t *n_nodes,
                           size_t *n_orders, size_t *n_channels)
{
    size_t channels, n = 0, orders = 0, w, c;
    ll_status s;

    channels = o->n_channels ? o->n_channels
             : m->channels  ? m->channels
             : ll_material_is_rgb(m) ? 3 : 1;
    if (!(o->n_nodes || m->nodes) || !(o->n_orders || m->orders)) {
        for (w = 0; w < m->count; ++w)
            for (c = 0; c < channels; ++c) {
                ll_word_params p;
                size_t wn, wm;
                ll_word_params_get(m, w, c, channels, &p);
                s = word_resolution(&p, &wn, &wm);
                if (s != LL_OK)
                    return ll_fail(s, "%s:%zu:%zu: no resolution heuristic for this %s: %s",
                                   m->source, m->words[w].line, m->words[w].column,
                                   ll_word_kind_name(p.kind), ll_last_error_message());
                if (wn > n)
                    n = wn;
                if (wm > orders)
                    orders = wm;
            }
    }
    if (n % 2)
        ++n;
    *n_nodes = o->n_nodes ? o->n_nodes : m->nodes ? m->nodes : n;
    *n_orders = o->n_orders ? o->n_orders : m->orders ? m->orders : orders;
    *n_channels = channels;
    return LL_OK;
}

ll_status ll_material_resolution(const ll_material *material, const ll_build_options *opts,
                                 size_t *n_nodes, size_t *n_orders, size_t *n_channels)
{
    ll_build_options o;
    size_t n, m, c;
    ll_status s;
    if (!material)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_material_resolution: material is NULL");
    s = ll_build_options_read(opts, &o, "ll_material_resolution");
    if (s == LL_OK)
        s = ll_material_plan(material, &o, &n, &m, &c);
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

/* ------------------------------------------------------------ costs
 * Seconds, from operation counts and rates measured on the development
 * machine (x86-64, 2 cores, OpenBLAS; see docs/material-language.md,
 * "Estimates"). Work is spread over Fourier orders (adding) or node columns
 * (interfaces), so it divides by min(threads, items). */

#define RATE_ADD 1.6e8       /* matrix entries n^2 m per second and thread in
                                one addition or doubling (high Fourier orders
                                are mostly zero or clear, so the work follows
                                the storage, not 14 (n/2)^3 flops per order) */
#define RATE_INTERFACE 1e8   /* (mu_o, mu_i, order) triples/s, one thread     */
#define RATE_PHASE 2e8       /* phase-function entries/s, one thread         */
#define RATE_MERL 4e8        /* DCT multiply-adds/s, one thread              */
#define RATE_WRITE 1e8       /* coefficients/s written                       */

static double parallel(double seconds, size_t items, size_t threads)
{
    size_t t = threads < items ? threads : items;
    return seconds / (double)(t ? t : 1);
}

double ll_cost_add(size_t n, size_t m, size_t threads)
{
    return parallel((double)n * (double)n * (double)m / RATE_ADD, m, threads);
}

size_t ll_doubling_count(double tau, double min_mu)
{
    double tau0;
    size_t k;
    ll_expand_schedule(tau, min_mu, &tau0, &k);
    return k;
}

double ll_cost_word(const ll_word_params *p, size_t n, size_t m, size_t threads)
{
    double h = (double)(n / 2), pairs = (double)n * (double)n;
    switch (p->kind) {
    case LL_WORD_DIELECTRIC:
    case LL_WORD_CONDUCTOR:
        return parallel(pairs * (double)m / RATE_INTERFACE, n, threads);
    case LL_WORD_MEDIUM: {
        /* Phase matrices, then the doublings. The smallest |mu| of an
         * n-node Gauss-Lobatto rule is about pi / (2 n), above 2^-16 for any
         * n < 50000, so the 2^-15 bound sets the initial thickness. */
        size_t doublings = p->tau > 0.0 ? ll_doubling_count(p->tau, 1.0) : 0;
        return parallel(pairs * (double)m / RATE_PHASE, m, threads) +
               (double)doublings * ll_cost_add(n, m, threads);
    }
    case LL_WORD_MEASURED:
        return parallel(h * h * 4.0 * (double)m * (double)m / RATE_MERL, n / 2, threads);
    default:
        return pairs / RATE_PHASE;
    }
}

double ll_cost_write(size_t n, size_t m, size_t n_channels)
{
    return (double)n * (double)n * (double)m * (double)n_channels / RATE_WRITE;
}
