/*
 * What tests/test_convergence.c and bench/convergence.c share: points
 * along the lobes of an interface or a medium, the worst relative
 * difference between two layers there (where the reference is above 1% of
 * its lobe's peak), layers evaluated "lean" (without building them:
 * interfaces through the resolution search's own evaluation, media order
 * by order as they are made), and the check of one interface word at the
 * resolution the tolerance chooses against twice it. The test runs the CI
 * subset of the grid with these, the benchmark the whole grid and the
 * research scans (docs/method.md).
 *
 * Header-only (static inline), like test_util.h, so that both programs
 * build from one source file each. Failures are cmocka assertions, and
 * both programs call these helpers inside cmocka's runner: outside it a
 * failed assertion ends the program with status 255 and its message
 * unprinted. A library call is checked with assert_ll_ok, which names the
 * call and the library's message. LL_CONVERGENCE_VERBOSE=1 prints every
 * case.
 */
#ifndef LL_CONVERGENCE_UTIL_H
#define LL_CONVERGENCE_UTIL_H

#include "test_util.h"

#include "search/probe.h"
#include "words/heuristics.h"
#include "words/media.h"
#include "material/word_table.h"
#include "numerics/spline.h"

#define MAX_POINTS 4096

/* A layerlab call returns LL_OK, or the check fails with the call's text,
 * its status and ll_last_error_message() (an unknown metal's message names
 * the folders its spectra were looked for in), which an assert_int_equal
 * against LL_OK would reduce to two numbers. */
#define assert_ll_ok(call)                                                               \
    do {                                                                                 \
        ll_status assert_ll_ok_status = (call);                                          \
        if (assert_ll_ok_status != LL_OK)                                                \
            fail_msg("%s: %s: %s", #call, ll_status_string(assert_ll_ok_status),         \
                     ll_last_error_message());                                           \
    } while (0)

typedef struct point {
    double mu_o, mu_i, phi;
    size_t group;
} point;

typedef struct point_set {
    point p[MAX_POINTS];
    size_t count, groups;
} point_set;

static inline double next_uniform(uint64_t *state)
{
    *state = *state * 2862933555777941757ULL + 3037000493ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* Whether the environment variable `name` is set to something but 0. */
static inline int env_flag(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

static inline int verbose(void)
{
    return env_flag("LL_CONVERGENCE_VERBOSE");
}

/* LL_CONVERGENCE_CASES=TEXT: the full grid's cases whose word contains
 * TEXT alone (e.g. "conductor"). */
static inline int selected(const char *text)
{
    const char *v = getenv("LL_CONVERGENCE_CASES");
    return !v || !*v || strstr(text, v) != NULL;
}

/* The full grid's build at twice the resolution, as ll_material_estimate
 * puts its peak: beyond this the case is reported and skipped (four
 * builds share the machine). */
#define FULL_GRID_BYTES 4e9

/* The estimated peak of building mat at n x m, bytes. */
static inline double peak_bytes(const ll_material *mat, size_t n, size_t m)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    o.n_nodes = n;
    o.n_orders = m;
    o.n_channels = 1;
    assert_ll_ok(ll_material_estimate(mat, &o, &e, NULL));
    return e.peak_bytes;
}

/* The azimuths of every outgoing cosine of a lobe (and one pseudo-random
 * one each). */
#define LOBE_PHIS 8
static const double lobe_phis[LOBE_PHIS] = { 0.0, 0.02, 0.07, 0.2, 0.5, 1.2, 2.0,
                                             3.14159265358979 };

/* One lobe (group): around outgoing cosine `centre` (signed), incident
 * mu_i; mirror and off-mirror azimuths. */
static inline void add_lobe(point_set *s, double mu_i, double centre, uint64_t *rng)
{
    static const double offsets[] = { 0.0, -0.02, 0.02, -0.05, 0.05, -0.15, 0.15 };
    const double *phis = lobe_phis;
    double sign = centre < 0.0 ? -1.0 : 1.0, c = fabs(centre);
    size_t k, j;
    for (k = 0; k < sizeof offsets / sizeof offsets[0] + 2; ++k) {
        double mu = k < sizeof offsets / sizeof offsets[0] ? c + offsets[k]
                                                           : 0.1 + 0.9 * next_uniform(rng);
        if (mu < 0.1 || mu > 1.0)
            continue;
        for (j = 0; j < LOBE_PHIS + 1 && s->count < MAX_POINTS; ++j) {
            point *p = &s->p[s->count++];
            p->mu_o = sign * mu;
            p->mu_i = mu_i;
            p->phi = j < LOBE_PHIS ? phis[j] : 3.14159 * next_uniform(rng);
            p->group = s->groups;
        }
    }
    ++s->groups;
}

/* The centres (signed outgoing cosines) of the lobes of incident cosine mu
 * from above (side 0) or below (side 1): reflection where the index ahead
 * is above 1 (the dense side holds the Fresnel edge of total internal
 * reflection, outside the tolerance: search/probe_set.c) and transmission
 * where it exists. Their count. */
static inline size_t lobe_centres(double eta, int conductor, int side, double mu, double centre[2])
{
    double sign = side ? -1.0 : 1.0, e = side ? 1.0 / eta : eta;
    double sin_t = sqrt(1.0 - mu * mu) / e;
    size_t lobes = 0;
    if (conductor || e > 1.0)
        centre[lobes++] = -sign * mu;
    if (!conductor && sin_t < 1.0)
        centre[lobes++] = sign * sqrt(1.0 - sin_t * sin_t);
    return lobes;
}

/* Interface points: incident 0.1, 0.15, 0.2 and four random cosines (the
 * first n_incident of them), from above and (dielectric) from below:
 * reflection and transmission. */
static inline void interface_points_of(point_set *s, double eta, int conductor, size_t n_incident)
{
    uint64_t rng = 2014;
    double incident[7] = { 0.1, 0.15, 0.2, 0, 0, 0, 0 };
    size_t k;
    int side;
    s->count = s->groups = 0;
    for (k = 3; k < 7; ++k)
        incident[k] = 0.1 + 0.9 * next_uniform(&rng);
    for (side = 0; side < (conductor ? 1 : 2); ++side)
        for (k = 0; k < n_incident; ++k) {
            double centre[2], sign = side ? -1.0 : 1.0;
            size_t b, lobes = lobe_centres(eta, conductor, side, incident[k], centre);
            for (b = 0; b < lobes; ++b)
                add_lobe(s, sign * incident[k], centre[b], &rng);
        }
}

static inline void interface_points(point_set *s, double eta, int conductor)
{
    interface_points_of(s, eta, conductor, 7);
}

/* The worst relative difference of a against b (values at the points of
 * s) where b is above 1% of its group's peak. */
static inline double worst_of_values(const point_set *s, const double *va, const double *vb,
                              size_t *where)
{
    double peak[256] = { 0 }, worst = 0.0;
    size_t k;
    assert_true(s->groups <= 256);
    for (k = 0; k < s->count; ++k)
        peak[s->p[k].group] = fmax(peak[s->p[k].group], vb[k]);
    *where = 0;
    for (k = 0; k < s->count; ++k)
        if (vb[k] > 0.01 * peak[s->p[k].group] && vb[k] > 0.0 &&
            fabs(va[k] - vb[k]) / vb[k] > worst) {
            worst = fabs(va[k] - vb[k]) / vb[k];
            *where = k;
        }
    return worst;
}

/* The values of layer l at the points of s (count of them). */
static inline double *layer_values(const point_set *s, const ll_layer *l)
{
    double *v = malloc((s->count + 1) * sizeof *v);
    size_t k;
    assert_non_null(v);
    for (k = 0; k < s->count; ++k)
        v[k] = ll_test_layer_eval(l, s->p[k].mu_i, s->p[k].mu_o, s->p[k].phi);
    return v;
}

/* The worst relative difference of a against b where b is above 1% of
 * its group's peak; *where the point. */
static inline double worst_difference(const point_set *s, const ll_layer *a, const ll_layer *b,
                               size_t *where)
{
    double *va = layer_values(s, a), *vb = layer_values(s, b);
    double worst = worst_of_values(s, va, vb, where);
    free(va);
    free(vb);
    return worst;
}

/* An interface word's layer at n nodes, without building it (for the
 * builds of the full grid too large for the machine, and the dense scan):
 * what ll_layer_eval gives, from the 16 series of each point's spline
 * stencil and the energy compensation made at n (search/interface_probe.c,
 * the resolution search's own evaluation). probes_are_the_layer shows it
 * is the layer to 1e-9, and check_interface shows it again at the
 * chosen resolution wherever it builds the layers. */
typedef struct lean_interface {
    ll_microfacet_model *mf;
    ll_probe_compensation compensation;
    size_t n;
} lean_interface;

/* The monochrome parameters of the material's one interface word. */
static inline void interface_params(const ll_material *mat, int conductor, double *eta_re,
                             double *eta_im, double *alpha)
{
    ll_word_params p;
    ll_word_params_above(mat, 0, 0, 1, 1.0, &p);
    *eta_re = conductor ? p.v[LL_CONDUCTOR_ETA] : p.v[LL_DIELECTRIC_ETA];
    *eta_im = conductor ? p.v[LL_CONDUCTOR_K] : 0.0;
    *alpha = conductor ? p.v[LL_CONDUCTOR_ALPHA] : p.v[LL_DIELECTRIC_ALPHA];
}

/* The distribution (LL_DISTRIBUTION_*) of the material's one interface word. */
static inline int interface_distribution(const ll_material *mat)
{
    ll_word_params p;
    ll_word_params_above(mat, 0, 0, 1, 1.0, &p);
    return p.choice;
}

static inline void lean_interface_of_distribution(double eta_re, double eta_im, double alpha,
                                                  int distribution, size_t n,
                                                  lean_interface *out)
{
    ll_microfacet_model *mf0 = NULL;
    out->n = n;
    assert_ll_ok(
        ll_probe_interface_model_distribution(eta_re, eta_im, alpha, distribution, &out->mf));
    assert_ll_ok(
        ll_probe_compensation_model_distribution(eta_re, eta_im, alpha, distribution, &mf0));
    assert_ll_ok(ll_probe_compensation_make(mf0, eta_re, eta_im, n, NULL, &out->compensation));
    ll_microfacet_destroy(mf0);
}

/* The same for a Beckmann interface. */
static inline void lean_interface_of(double eta_re, double eta_im, double alpha, size_t n,
                              lean_interface *out)
{
    lean_interface_of_distribution(eta_re, eta_im, alpha, LL_DISTRIBUTION_BECKMANN, n, out);
}

static inline void lean_interface_free(lean_interface *li)
{
    ll_probe_compensation_free(&li->compensation);
    ll_microfacet_destroy(li->mf);
}

/* The lean layer of the material's one interface word. */
static inline void lean_interface_make(const ll_material *mat, int conductor, size_t n,
                                lean_interface *out)
{
    double eta_re, eta_im, alpha;
    interface_params(mat, conductor, &eta_re, &eta_im, &alpha);
    lean_interface_of_distribution(eta_re, eta_im, alpha, interface_distribution(mat), n, out);
}

/* The lean layer at m orders on a probe set (values pair-major). */
static inline void lean_interface_eval(lean_interface *li, size_t m, const ll_probe_set *set,
                                       double *v)
{
    assert_ll_ok(ll_probe_interface_eval(li->mf, &li->compensation, li->n, m, set, NULL, v));
}

/* The lean layer at m orders on the points of s: the runs of points of one
 * direction pair at the azimuths of add_lobe as one probe set, the others
 * (one pseudo-random azimuth each) LL_PROBE_MAX_PHI pairs at a time, the
 * diagonal of their values. */
static inline double *lean_point_values(lean_interface *li, size_t m, const point_set *s)
{
    const double *fixed = lobe_phis;
    ll_probe_set set;
    size_t *pair_of = malloc((s->count + 1) * sizeof *pair_of), k, j, p;
    double *v = malloc((s->count + 1) * sizeof *v), *values, *chunk;
    memset(&set, 0, sizeof set);
    set.pairs = malloc((s->count + 1) * sizeof *set.pairs);
    assert_true(pair_of && v && set.pairs);
    for (k = 0; k < s->count; ++k) {
        if (set.n_pairs == 0 || set.pairs[set.n_pairs - 1].mu_o != s->p[k].mu_o ||
            set.pairs[set.n_pairs - 1].mu_i != s->p[k].mu_i) {
            set.pairs[set.n_pairs].mu_o = s->p[k].mu_o;
            set.pairs[set.n_pairs].mu_i = s->p[k].mu_i;
            set.pairs[set.n_pairs].group = 0;
            ++set.n_pairs;
        }
        pair_of[k] = set.n_pairs - 1;
    }
    set.cap_pairs = set.n_pairs;
    set.n_phi = LOBE_PHIS;
    set.n_groups = 1;
    for (j = 0; j < LOBE_PHIS; ++j)
        set.phi[j] = fixed[j];
    values = malloc((LL_PROBE_VALUES(&set) + 1) * sizeof *values);
    assert_non_null(values);
    lean_interface_eval(li, m, &set, values);
    /* Points off the fixed azimuths, a chunk at a time. */
    {
        ll_probe_set c;
        size_t idx[LL_PROBE_MAX_PHI], count = 0;
        memset(&c, 0, sizeof c);
        c.pairs = malloc(LL_PROBE_MAX_PHI * sizeof *c.pairs);
        chunk = malloc(LL_PROBE_MAX_PHI * LL_PROBE_MAX_PHI * sizeof *chunk);
        assert_true(c.pairs && chunk);
        c.cap_pairs = LL_PROBE_MAX_PHI;
        c.n_groups = 1;
        for (k = 0; k <= s->count; ++k) {
            int fixed_phi = 0;
            if (k < s->count)
                for (j = 0; j < LOBE_PHIS; ++j)
                    if (s->p[k].phi == fixed[j]) {
                        v[k] = values[pair_of[k] * LOBE_PHIS + j];
                        fixed_phi = 1;
                    }
            if (k < s->count && !fixed_phi) {
                c.pairs[count].mu_o = s->p[k].mu_o;
                c.pairs[count].mu_i = s->p[k].mu_i;
                c.pairs[count].group = 0;
                c.phi[count] = s->p[k].phi;
                idx[count++] = k;
            }
            if (count == LL_PROBE_MAX_PHI || (k == s->count && count > 0)) {
                c.n_pairs = c.n_phi = count;
                lean_interface_eval(li, m, &c, chunk);
                for (p = 0; p < count; ++p)
                    v[idx[p]] = chunk[p * count + p];
                count = 0;
            }
        }
        free(c.pairs);
        free(chunk);
    }
    free(values);
    free(set.pairs);
    free(pair_of);
    return v;
}

static inline ll_layer *build_one(const ll_material *mat, size_t n, size_t m)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t channels = 0;
    o.n_nodes = n;
    o.n_orders = m;
    o.n_channels = 1;
    assert_ll_ok(ll_material_build_layers(mat, &o, NULL, layers, &channels, NULL));
    assert_int_equal(channels, 1);
    return layers[0];
}

/* The largest relative difference of the lean layer from the built one at
 * the points (the lean one's check wherever both are made). */
static inline double lean_against_layer(const point_set *s, const double *lean, const ll_layer *l)
{
    double *v = layer_values(s, l), worst = 0.0;
    size_t k;
    for (k = 0; k < s->count; ++k)
        worst = fmax(worst, fabs(lean[k] - v[k]) / fmax(fabs(v[k]), 1e-3));
    free(v);
    return worst;
}

/* A GGX dielectric's transmission jumps where the refraction half vector
 * turns horizontal (search/probe_jump.c): the points whose spline stencils
 * at n or at 2n nodes hold nodes on both sides of that line are left out
 * (NaN in both value arrays, which worst_of_values skips), as the search
 * leaves out such probes: within one node interval of the jump the file
 * smears it, and the tolerance covers the lobe away from it. Their count. */
static inline size_t leave_out_jump(const point_set *s, double eta, size_t n, double *va,
                                    double *vb)
{
    double *x = malloc(2 * n * sizeof *x), *w = malloc(2 * n * sizeof *w);
    double *x2 = malloc(4 * n * sizeof *x2), *w2 = malloc(4 * n * sizeof *w2);
    size_t k, count = 0;
    assert_true(x && w && x2 && w2);
    assert_ll_ok(ll_quad_gauss_lobatto(n, x, w, NULL));
    assert_ll_ok(ll_quad_gauss_lobatto(2 * n, x2, w2, NULL));
    for (k = 0; k < s->count; ++k)
        if (ll_probe_jump_straddles(x + n / 2, n / 2, eta, s->p[k].mu_o, s->p[k].mu_i) ||
            ll_probe_jump_straddles(x2 + n, n, eta, s->p[k].mu_o, s->p[k].mu_i)) {
            va[k] = vb[k] = NAN;
            ++count;
        }
    free(x);
    free(w);
    free(x2);
    free(w2);
    return count;
}

/* The interface word `text` (one line), monochrome, at tolerance t:
 * whether it meets it (the full grid goes on past a failure, to report
 * every case). Where the build at twice the resolution would not fit
 * (FULL_GRID_BYTES), both resolutions are evaluated lean (lean_interface),
 * which is checked against the built layer at the chosen resolution
 * wherever that one is built. */
static inline int check_interface(const char *text, double eta, int conductor, double tolerance)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    lean_interface la, lb;
    point_set *s = malloc(sizeof *s);
    double *va, *vb, e, twice;
    size_t n, m, where, left_out = 0;
    int lean, len = (int)strcspn(text, "\n"); /* the word without its newline */
    assert_non_null(s);
    assert_ll_ok(ll_material_parse(text, "convergence", &mat));
    o.n_channels = 1;
    o.tolerance = tolerance;
    assert_ll_ok(ll_material_resolution(mat, &o, NULL, &n, &m, NULL));
    twice = peak_bytes(mat, 2 * n, 2 * m);
    lean = twice > FULL_GRID_BYTES;
    interface_points(s, eta, conductor);
    lean_interface_make(mat, conductor, n, &la);
    if (lean)
        lean_interface_make(mat, conductor, 2 * n, &lb);
    va = lean_point_values(&la, m, s);
    if (lean) {
        vb = lean_point_values(&lb, 2 * m, s);
    } else {
        ll_layer *a = build_one(mat, n, m), *b = build_one(mat, 2 * n, 2 * m);
        double d = lean_against_layer(s, va, a);
        if (verbose() || d > 1e-9)
            printf("  %-40.*s lean against the layer: %.2g\n", len, text, d);
        assert_true(d <= 1e-9);
        free(va);
        va = layer_values(s, a);
        vb = layer_values(s, b);
        ll_layer_destroy(a);
        ll_layer_destroy(b);
    }
    if (!conductor && interface_distribution(mat) == LL_DISTRIBUTION_GGX)
        left_out = leave_out_jump(s, eta, n, va, vb);
    e = worst_of_values(s, va, vb, &where);
    if (verbose() || e > tolerance)
        printf("  %-40.*s n %5zu m %5zu: worst %.4f at mu_o %.3f mu_i %.3f phi %.3f%s (%zu of "
               "%zu points at the jump left out)\n",
               len, text, n, m, e, s->p[where].mu_o, s->p[where].mu_i, s->p[where].phi,
               lean ? " (lean)" : "", left_out, s->count);
    if (lean && (verbose() || e > tolerance))
        printf("  %-40.*s (lean: building twice it would take %.1f GB)\n", len, text,
               twice / 1e9);
    fflush(stdout);
    free(va);
    free(vb);
    lean_interface_free(&la);
    if (lean)
        lean_interface_free(&lb);
    ll_material_destroy(mat);
    free(s);
    return e <= tolerance;
}

typedef struct interface_case {
    const char *name; /* the word's parameters before alpha=            */
    double eta;       /* relative index (dielectrics)                    */
    int conductor;
} interface_case;

static const interface_case cases[] = {
    { "dielectric eta=1.1", 1.1, 0 },       { "dielectric eta=1.33", 1.33, 0 },
    { "dielectric eta=1.5", 1.5, 0 },       { "dielectric eta=2.0", 2.0, 0 },
    { "dielectric eta=0.6666666666666666", 1.0 / 1.5, 0 },
    { "conductor eta=Au", 0.0, 1 },        { "conductor eta=Al", 0.0, 1 },
    { "conductor eta=Cu", 0.0, 1 },
};
static const double alphas[] = { 0.02, 0.05, 0.1, 0.3, 0.5, 0.8 };

/* ------------------------------------------------------------- media
 *
 * The phase function's layer at twice the resolution of g = 0.95 (1376 x
 * 724) is 11 GB of dense orders. So the layer is evaluated at the points
 * as its orders are made (ll_layer_set_medium_finished hands each over and
 * keeps none): each order's 4 x 4 spline stencils of ll_layer_eval
 * (layer/layer.c eval_point), summed over the orders afterwards in order
 * (the same for any thread count). One order's n x n matrix per thread.
 * The comparison leaves out the delta-M forward term f I (the moments
 * beyond the kept ones as exactly forward scattering: a delta, shown by
 * ll_layer_eval near mu_o = mu_i as f over a node's weight, which changes
 * with n without converging; search/medium_probe.c). */

typedef struct lean_point {
    ptrdiff_t oo, oi;  /* the stencils' first internal node indices */
    double wo[4], wi[4];
} lean_point;

typedef struct lean_eval {
    const ll_layer *layer;
    const point_set *s;
    lean_point *at;
    double *per_order; /* m x points: order k's sum at each point */
    int with_forward;
} lean_eval;

/* layer/layer.c direction_weights: the stencil of mu on its half. */
static inline ptrdiff_t lean_stencil(const ll_layer *l, double mu, double w[4])
{
    size_t h = l->n / 2;
    ptrdiff_t offset = 0;
    assert_true(h >= 2 && mu != 0.0);
    ll_spline_weights(l->nodes + h, h, fabs(mu), &offset, w, 1);
    return mu < 0.0 ? offset : offset + (ptrdiff_t)h;
}

static inline ll_status lean_order(void *user, size_t l, double *P, double forward, ll_order **out)
{
    const lean_eval *e = user;
    const ll_layer *layer = e->layer;
    ptrdiff_t h = (ptrdiff_t)(layer->n / 2), n = (ptrdiff_t)layer->n;
    size_t k;
    for (k = 0; k < e->s->count; ++k) {
        const lean_point *p = &e->at[k];
        /* Rows and columns stay in the half of their direction. */
        ptrdiff_t half_o = p->oo >= h - 1 ? h : 0, half_i = p->oi >= h - 1 ? h : 0;
        double sum = 0.0;
        int a, b;
        for (b = 0; b < 4; ++b) {
            ptrdiff_t col = p->oi + b;
            double scale;
            if (p->wi[b] == 0.0 || col < half_i || col >= half_i + h)
                continue;
            scale = p->wi[b] / (fabs(layer->nodes[col]) * layer->weights[col]);
            for (a = 0; a < 4; ++a) {
                ptrdiff_t row = p->oo + a;
                double v;
                if (p->wo[a] == 0.0 || row < half_o || row >= half_o + h)
                    continue;
                v = P ? P[col * n + row] : (row == col ? forward : 0.0);
                if (!e->with_forward && row == col)
                    v -= forward;
                sum += p->wo[a] * scale * v;
            }
        }
        e->per_order[l * e->s->count + k] = sum;
    }
    *out = NULL; /* (kept by nobody) */
    return LL_OK;
}

/* What ll_layer_eval of the HG phase layer (albedo 1) of n x m gives at
 * the points of s, into v (without with_forward, less the forward term). */
static inline void lean_hg(double g, size_t n, size_t m, int with_forward, const point_set *s,
                    double *v)
{
    ll_layer *layer = ll_test_layer(n, m);
    lean_eval e;
    size_t k, l;
    e.layer = layer;
    e.with_forward = with_forward;
    e.s = s;
    e.at = malloc(s->count * sizeof *e.at);
    e.per_order = calloc(m * s->count, sizeof *e.per_order);
    assert_non_null(e.at);
    assert_non_null(e.per_order);
    for (k = 0; k < s->count; ++k) {
        e.at[k].oo = lean_stencil(layer, s->p[k].mu_o, e.at[k].wo);
        e.at[k].oi = lean_stencil(layer, s->p[k].mu_i, e.at[k].wi);
    }
    {
        ll_medium_finish finish;
        finish.order = lean_order;
        finish.user = &e;
        assert_ll_ok(ll_layer_set_medium_finished(layer, LL_MEDIUM_HG, 1.0, g, &finish, NULL));
    }
    for (k = 0; k < s->count; ++k) {
        double c1 = cos(s->p[k].phi), prev = c1, cur = 1.0, sum = 0.0;
        for (l = 0; l < m; ++l) {
            double next = 2.0 * c1 * cur - prev;
            sum += e.per_order[l * s->count + k] * cur * (l == 0 ? 0.5 : 1.0);
            prev = cur;
            cur = next;
        }
        sum *= 1.0 / 3.14159265358979323846;
        v[k] = sum > 0.0 ? sum : 0.0;
    }
    free(e.at);
    free(e.per_order);
    ll_layer_destroy(layer);
}

/* The medium points: incident 0.1, 0.15, 0.2 and three random cosines,
 * forward (transmission) and backward (reflection) lobes. */
static inline void medium_points(point_set *s)
{
    uint64_t rng = 7;
    size_t k;
    s->count = s->groups = 0;
    for (k = 0; k < 6; ++k) {
        double mu = k < 3 ? 0.1 + 0.05 * (double)k : 0.1 + 0.9 * next_uniform(&rng);
        add_lobe(s, mu, mu, &rng);  /* forward */
        add_lobe(s, mu, -mu, &rng); /* backward */
    }
}

/* The HG phase function of asymmetry g (a medium of albedo 1) at the
 * resolution its heuristic chooses against twice it, evaluated lean at the
 * medium points s, both without the forward term: the worst relative
 * difference where twice it is above 1% of its lobe's peak. Printed when
 * verbose or above the tolerance 0.01. */
static inline double media_case(double g, const point_set *s)
{
    double *va = malloc((s->count + 1) * sizeof *va), *vb = malloc((s->count + 1) * sizeof *vb);
    double e, err;
    size_t n, m, where;
    assert_non_null(va);
    assert_non_null(vb);
    assert_ll_ok(ll_resolution_search_henyey_greenstein(g, 0.0, 0.0, NULL, &n, &m, &err));
    lean_hg(g, n, m, 0, s, va);
    lean_hg(g, 2 * n, 2 * m, 0, s, vb);
    e = worst_of_values(s, va, vb, &where);
    if (verbose() || e > 0.01)
        printf("  hg g=%g n %zu m %zu (probes %.4f): worst %.4f at mu_o %.3f mu_i %.3f "
               "phi %.3f\n",
               g, n, m, err, e, s->p[where].mu_o, s->p[where].mu_i, s->p[where].phi);
    fflush(stdout);
    free(va);
    free(vb);
    return e;
}

#endif /* LL_CONVERGENCE_UTIL_H */
