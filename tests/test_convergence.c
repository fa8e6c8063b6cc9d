/*
 * The resolution chosen by a tolerance (issue 14): a layer built at the
 * resolution that ll_material_resolution chooses agrees with the same
 * layer at twice its nodes and twice its orders within the tolerance, at
 * grazing (mu 0.1, 0.15, 0.2) and pseudo-random directions, mirror and
 * off-mirror azimuths, reflection and transmission, wherever the BSDF is
 * above 1% of the peak of its lobe. The layers are built with the public
 * API alone (the material language, energy compensation on), at points
 * other than the search's own probes (words/probe_set.c), so the test
 * checks the method and not the probes against themselves.
 *
 * The grid of the issue (dielectrics eta 1.1, 1.33, 1.5, 2.0, 1/1.5 and
 * gold, aluminium, copper at alpha 0.02 .. 0.8) takes minutes at 2n, 2m
 * for the small roughnesses (n ~ 1000, m ~ 2000); CI runs the subset
 * below (and HG g = 0.8 alone), LL_CONVERGENCE_FULL=1 (make bench) the
 * whole grid and g = 0.5, 0.8, 0.95, -0.9.
 * LL_CONVERGENCE_VERBOSE=1 prints every case.
 */
#include "test_util.h"

#include "words/probe.h"
#include "words/media.h"
#include "material/word_table.h"
#include "numerics/spline.h"

#include <pthread.h>
#include <time.h>
#include <unistd.h>

#define MAX_POINTS 4096

typedef struct point {
    double mu_o, mu_i, phi;
    size_t group;
} point;

typedef struct point_set {
    point p[MAX_POINTS];
    size_t count, groups;
} point_set;

static double next_uniform(uint64_t *state)
{
    *state = *state * 2862933555777941757ULL + 3037000493ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* Whether the environment variable `name` is set to something but 0. */
static int env_flag(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

static int verbose(void)
{
    return env_flag("LL_CONVERGENCE_VERBOSE");
}

static int full_grid(void)
{
    return env_flag("LL_CONVERGENCE_FULL");
}

/* LL_CONVERGENCE_CASES=TEXT: the full grid's cases whose word contains
 * TEXT alone (e.g. "conductor"). */
static int selected(const char *text)
{
    const char *v = getenv("LL_CONVERGENCE_CASES");
    return !v || !*v || strstr(text, v) != NULL;
}

/* The full grid's build at twice the resolution, as ll_material_estimate
 * puts its peak: beyond this the case is reported and skipped (four
 * builds share the machine). */
#define FULL_GRID_BYTES 4e9

/* The estimated peak of building mat at n x m, bytes. */
static double peak_bytes(const ll_material *mat, size_t n, size_t m)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    o.n_nodes = n;
    o.n_orders = m;
    o.n_channels = 1;
    assert_int_equal(ll_material_estimate(mat, &o, &e, NULL), LL_OK);
    return e.peak_bytes;
}

/* The azimuths of every outgoing cosine of a lobe (and one pseudo-random
 * one each). */
#define LOBE_PHIS 8
static const double lobe_phis[LOBE_PHIS] = { 0.0, 0.02, 0.07, 0.2, 0.5, 1.2, 2.0,
                                             3.14159265358979 };

/* One lobe (group): around outgoing cosine `centre` (signed), incident
 * mu_i; mirror and off-mirror azimuths. */
static void add_lobe(point_set *s, double mu_i, double centre, uint64_t *rng)
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
 * reflection, outside the tolerance: words/probe_set.c) and transmission
 * where it exists. Their count. */
static size_t lobe_centres(double eta, int conductor, int side, double mu, double centre[2])
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
static void interface_points_of(point_set *s, double eta, int conductor, size_t n_incident)
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

static void interface_points(point_set *s, double eta, int conductor)
{
    interface_points_of(s, eta, conductor, 7);
}

/* The worst relative difference of a against b (values at the points of
 * s) where b is above 1% of its group's peak. */
static double worst_of_values(const point_set *s, const double *va, const double *vb,
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
static double *layer_values(const point_set *s, const ll_layer *l)
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
static double worst_difference(const point_set *s, const ll_layer *a, const ll_layer *b,
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
 * stencil and the energy compensation made at n (words/interface_probe.c,
 * the resolution search's own evaluation). probes_are_the_layer shows it
 * is the layer to 1e-9, and check_interface shows it again at the
 * chosen resolution wherever it builds the layers. */
typedef struct lean_interface {
    ll_microfacet_model *mf;
    ll_probe_compensation compensation;
    size_t n;
} lean_interface;

/* The monochrome parameters of the material's one interface word. */
static void interface_params(const ll_material *mat, int conductor, double *eta_re,
                             double *eta_im, double *alpha)
{
    ll_word_params p;
    ll_word_params_above(mat, 0, 0, 1, 1.0, &p);
    *eta_re = conductor ? p.v[LL_CONDUCTOR_ETA] : p.v[LL_DIELECTRIC_ETA];
    *eta_im = conductor ? p.v[LL_CONDUCTOR_K] : 0.0;
    *alpha = conductor ? p.v[LL_CONDUCTOR_ALPHA] : p.v[LL_DIELECTRIC_ALPHA];
}

static void lean_interface_of(double eta_re, double eta_im, double alpha, size_t n,
                              lean_interface *out)
{
    ll_microfacet_model *mf0 = NULL;
    out->n = n;
    assert_int_equal(ll_probe_interface_model(eta_re, eta_im, alpha, &out->mf), LL_OK);
    assert_int_equal(ll_probe_compensation_model(eta_re, eta_im, alpha, &mf0), LL_OK);
    assert_int_equal(ll_probe_compensation_make(mf0, eta_re, eta_im, n, NULL, &out->compensation),
                     LL_OK);
    ll_microfacet_destroy(mf0);
}

static void lean_interface_free(lean_interface *li)
{
    ll_probe_compensation_free(&li->compensation);
    ll_microfacet_destroy(li->mf);
}

/* The lean layer of the material's one interface word. */
static void lean_interface_make(const ll_material *mat, int conductor, size_t n,
                                lean_interface *out)
{
    double eta_re, eta_im, alpha;
    interface_params(mat, conductor, &eta_re, &eta_im, &alpha);
    lean_interface_of(eta_re, eta_im, alpha, n, out);
}

/* The lean layer at m orders on a probe set (values pair-major). */
static void lean_interface_eval(lean_interface *li, size_t m, const ll_probe_set *set, double *v)
{
    assert_int_equal(ll_probe_interface_eval(li->mf, &li->compensation, li->n, m, set, NULL, v),
                     LL_OK);
}

/* The lean layer at m orders on the points of s: the runs of points of one
 * direction pair at the azimuths of add_lobe as one probe set, the others
 * (one pseudo-random azimuth each) LL_PROBE_MAX_PHI pairs at a time, the
 * diagonal of their values. */
static double *lean_point_values(lean_interface *li, size_t m, const point_set *s)
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

static ll_layer *build_one(const ll_material *mat, size_t n, size_t m)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t channels = 0;
    o.n_nodes = n;
    o.n_orders = m;
    o.n_channels = 1;
    assert_int_equal(ll_material_build_layers(mat, &o, NULL, layers, &channels, NULL), LL_OK);
    assert_int_equal(channels, 1);
    return layers[0];
}

/* The largest relative difference of the lean layer from the built one at
 * the points (the lean one's check wherever both are made). */
static double lean_against_layer(const point_set *s, const double *lean, const ll_layer *l)
{
    double *v = layer_values(s, l), worst = 0.0;
    size_t k;
    for (k = 0; k < s->count; ++k)
        worst = fmax(worst, fabs(lean[k] - v[k]) / fmax(fabs(v[k]), 1e-3));
    free(v);
    return worst;
}

static int dense(void)
{
    return env_flag("LL_CONVERGENCE_DENSE");
}

/* LL_CONVERGENCE_DENSE=1 (instead of the checks; LL_CONVERGENCE_CASES
 * selects): the worst difference at a
 * dense scan of the lobes, not only at the test's points: incident cosines
 * every 0.002 from 0.1 to 1, each side and block as interface_points, the
 * outgoing cosines of add_lobe's offsets and 0.01, 0.03, 0.08 either side,
 * add_lobe's azimuths. Printed, not checked: it shows how far the probes
 * and the test's points, both samples, are from the worst (docs/method.md,
 * "Between the probes"). */
static void dense_scan(lean_interface *la, lean_interface *lb, size_t m, double eta,
                       int conductor)
{
    static const double offsets[] = { 0.0,   -0.01, 0.01, -0.02, 0.02, -0.03, 0.03,
                                      -0.05, 0.05,  -0.08, 0.08, -0.15, 0.15 };
    ll_probe_set set;
    double *va, *vb, *peak, worst = 0.0, at_o = 0.0, at_i = 0.0, at_phi = 0.0, at_ratio = 0.0;
    size_t cap = 60000, k, p, j;
    int side;
    memset(&set, 0, sizeof set);
    set.pairs = malloc(cap * sizeof *set.pairs);
    assert_non_null(set.pairs);
    set.cap_pairs = cap;
    set.n_phi = LOBE_PHIS;
    for (j = 0; j < LOBE_PHIS; ++j)
        set.phi[j] = lobe_phis[j];
    for (side = 0; side < (conductor ? 1 : 2); ++side)
        for (k = 0; k <= 450; ++k) {
            double sign = side ? -1.0 : 1.0, mu = fmin(0.1 + 0.002 * (double)k, 1.0);
            double centre[2];
            size_t b, lobes = lobe_centres(eta, conductor, side, mu, centre);
            for (b = 0; b < lobes; ++b) {
                for (j = 0; j < sizeof offsets / sizeof offsets[0]; ++j) {
                    double c = fabs(centre[b]) + offsets[j];
                    if (c < 0.1 || c > 1.0)
                        continue;
                    assert_true(set.n_pairs < cap);
                    set.pairs[set.n_pairs].mu_o = centre[b] < 0.0 ? -c : c;
                    set.pairs[set.n_pairs].mu_i = sign * mu;
                    set.pairs[set.n_pairs].group = set.n_groups;
                    ++set.n_pairs;
                }
                ++set.n_groups;
            }
        }
    va = malloc(LL_PROBE_VALUES(&set) * sizeof *va);
    vb = malloc(LL_PROBE_VALUES(&set) * sizeof *vb);
    peak = calloc(set.n_groups, sizeof *peak);
    assert_true(va && vb && peak);
    lean_interface_eval(la, m, &set, va);
    lean_interface_eval(lb, 2 * m, &set, vb);
    for (p = 0; p < set.n_pairs; ++p)
        for (j = 0; j < LOBE_PHIS; ++j)
            peak[set.pairs[p].group] = fmax(peak[set.pairs[p].group], vb[p * LOBE_PHIS + j]);
    for (p = 0; p < set.n_pairs; ++p)
        for (j = 0; j < LOBE_PHIS; ++j) {
            double b = vb[p * LOBE_PHIS + j], top = peak[set.pairs[p].group];
            if (b > 0.01 * top && b > 0.0 && fabs(va[p * LOBE_PHIS + j] - b) / b > worst) {
                worst = fabs(va[p * LOBE_PHIS + j] - b) / b;
                at_o = set.pairs[p].mu_o;
                at_i = set.pairs[p].mu_i;
                at_phi = set.phi[j];
                at_ratio = b / top;
            }
        }
    printf(" dense scan (%zu pairs): worst %.4f at mu_o %.4f mu_i %.4f phi %.3f, %.4f of its "
           "lobe's peak\n",
           set.n_pairs, worst, at_o, at_i, at_phi, at_ratio);
    free(va);
    free(vb);
    free(peak);
    free(set.pairs);
}

/* The dense scan of one case at the resolution the search chooses. */
static void dense_case(const char *text, double eta, int conductor)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    lean_interface la, lb;
    size_t n, m;
    assert_int_equal(ll_material_parse(text, "convergence", &mat), LL_OK);
    o.n_channels = 1;
    assert_int_equal(ll_material_resolution(mat, &o, NULL, &n, &m, NULL), LL_OK);
    lean_interface_make(mat, conductor, n, &la);
    lean_interface_make(mat, conductor, 2 * n, &lb);
    printf("  %.*s at n %zu m %zu:", (int)strcspn(text, "\n"), text, n, m);
    dense_scan(&la, &lb, m, eta, conductor);
    fflush(stdout);
    lean_interface_free(&la);
    lean_interface_free(&lb);
    ll_material_destroy(mat);
}

/* The interface word `text` (one line), monochrome, at tolerance t:
 * whether it meets it (the full grid goes on past a failure, to report
 * every case). Where the build at twice the resolution would not fit
 * (FULL_GRID_BYTES), both resolutions are evaluated lean (lean_interface),
 * which is checked against the built layer at the chosen resolution
 * wherever that one is built. */
static int check_interface(const char *text, double eta, int conductor, double tolerance)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    lean_interface la, lb;
    point_set *s = malloc(sizeof *s);
    double *va, *vb, e, twice;
    size_t n, m, where;
    int lean;
    assert_non_null(s);
    assert_int_equal(ll_material_parse(text, "convergence", &mat), LL_OK);
    o.n_channels = 1;
    o.tolerance = tolerance;
    assert_int_equal(ll_material_resolution(mat, &o, NULL, &n, &m, NULL), LL_OK);
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
            printf("  %-40s lean against the layer: %.2g\n", text, d);
        assert_true(d <= 1e-9);
        free(va);
        va = layer_values(s, a);
        vb = layer_values(s, b);
        ll_layer_destroy(a);
        ll_layer_destroy(b);
    }
    e = worst_of_values(s, va, vb, &where);
    if (verbose() || e > tolerance)
        printf("  %-40s n %5zu m %5zu: worst %.4f at mu_o %.3f mu_i %.3f phi %.3f%s\n", text,
               n, m, e, s->p[where].mu_o, s->p[where].mu_i, s->p[where].phi,
               lean ? " (lean)" : "");
    if (lean && (verbose() || e > tolerance))
        printf("  %-40s (lean: building twice it would take %.1f GB)\n", text, twice / 1e9);
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

/* The subset CI runs (index into cases, alpha): the issue's own failure
 * (eta 1.5, alpha 0.5), eta 1.5, alpha 0.8, which the full grid found
 * 1.04% off at phi 0.5 (transmission at mu_i 0.1) while the probes'
 * azimuths stepped from 0.3 to 0.6 (probe_set.c), and three metals:
 * copper, alpha 0.8 is the case that the compensation's term left out of
 * the probes made 1.32% off. The search probes the compensation now, which
 * costs O(n^2) per node count (a dielectric's 3 to 6 s of CPU), so eta
 * 1/1.5, alpha 0.8 and eta 2, alpha 0.5 are the full grid's: the whole
 * test is 19 s of CPU (69 s wall at load 9 on 2 cores). */
static const struct {
    size_t c;
    double alpha;
} ci_subset[] = { { 2, 0.5 }, { 2, 0.8 }, { 5, 0.3 }, { 7, 0.5 }, { 7, 0.8 } };

static void interfaces_meet_the_tolerance(void **state)
{
    char text[128];
    size_t c, a, failed = 0;
    (void)state;
    if (dense()) {
        for (c = 0; c < sizeof cases / sizeof cases[0]; ++c)
            for (a = 0; a < sizeof alphas / sizeof alphas[0]; ++a) {
                snprintf(text, sizeof text, "%s alpha=%g\n", cases[c].name, alphas[a]);
                if (selected(text))
                    dense_case(text, cases[c].eta, cases[c].conductor);
            }
        return;
    }
    if (full_grid()) {
        for (c = 0; c < sizeof cases / sizeof cases[0]; ++c)
            for (a = 0; a < sizeof alphas / sizeof alphas[0]; ++a) {
                snprintf(text, sizeof text, "%s alpha=%g\n", cases[c].name, alphas[a]);
                if (selected(text) && !check_interface(text, cases[c].eta, cases[c].conductor,
                                                       0.01))
                    ++failed;
            }
        assert_int_equal(failed, 0);
        return;
    }
    for (c = 0; c < sizeof ci_subset / sizeof ci_subset[0]; ++c) {
        const interface_case *ic = &cases[ci_subset[c].c];
        snprintf(text, sizeof text, "%s alpha=%g\n", ic->name, ci_subset[c].alpha);
        assert_true(check_interface(text, ic->eta, ic->conductor, 0.01));
    }
}

/* LL_CONVERGENCE_TABLE=1: docs/method.md's resolution table, before (the
 * original's fit, ll_fit_microfacet) and after (the tolerance 1%), each
 * against the layer at twice the chosen n and m, at the grazing incident
 * cosines 0.1, 0.15, 0.2 alone (mirror and off-mirror, reflection and
 * transmission), compensation on. Prints markdown rows. */
static void resolution_table(void **state)
{
    static const struct {
        const char *text, *label;
        double eta;
        int conductor;
    } rows[] = {
        { "dielectric eta=1.33 alpha=0.3\n", "eta 1.33, alpha 0.3", 1.33, 0 },
        { "dielectric eta=1.5 alpha=0.3\n", "eta 1.5, alpha 0.3", 1.5, 0 },
        { "dielectric eta=1.5 alpha=0.5\n", "eta 1.5, alpha 0.5", 1.5, 0 },
        { "dielectric eta=1.5 alpha=0.8\n", "eta 1.5, alpha 0.8", 1.5, 0 },
        { "dielectric eta=2.0 alpha=0.5\n", "eta 2.0, alpha 0.5", 2.0, 0 },
        { "dielectric eta=0.6666666666666666 alpha=0.8\n", "eta 1/1.5, alpha 0.8", 1.0 / 1.5,
          0 },
        { "conductor eta=Au alpha=0.3\n", "gold, alpha 0.3", 0.0, 1 },
        { "conductor eta=Au alpha=0.5\n", "gold, alpha 0.5", 0.0, 1 },
    };
    const char *v = getenv("LL_CONVERGENCE_TABLE");
    point_set *s = malloc(sizeof *s);
    size_t r;
    (void)state;
    assert_non_null(s);
    if (!v || !*v || strcmp(v, "0") == 0) {
        free(s);
        return;
    }
    printf("| interface | before: n x m, worst | after: n x m, worst |\n|---|---|---|\n");
    for (r = 0; r < sizeof rows / sizeof rows[0]; ++r) {
        ll_material *mat = NULL;
        ll_build_options o = LL_BUILD_OPTIONS_INIT;
        ll_layer *fit, *chosen, *ref;
        size_t n, m, fn, fm, where;
        double eta_re, eta_im, alpha, ef, ec;
        if (!selected(rows[r].text))
            continue;
        assert_int_equal(ll_material_parse(rows[r].text, "table", &mat), LL_OK);
        o.n_channels = 1;
        assert_int_equal(ll_material_resolution(mat, &o, NULL, &n, &m, NULL), LL_OK);
        /* The fit of the layer's own index (gold: its monochrome channel). */
        interface_params(mat, rows[r].conductor, &eta_re, &eta_im, &alpha);
        assert_int_equal(ll_fit_microfacet(alpha, eta_re, eta_im, &fn, &fm), LL_OK);
        fit = build_one(mat, fn, fm);
        chosen = build_one(mat, n, m);
        ref = build_one(mat, 2 * n, 2 * m);
        interface_points_of(s, rows[r].eta, rows[r].conductor, 3);
        ef = worst_difference(s, fit, ref, &where);
        ec = worst_difference(s, chosen, ref, &where);
        printf("| %s | %zu x %zu, %.3g%% | %zu x %zu, %.2f%% |\n", rows[r].label, fn, fm,
               100.0 * ef, n, m, 100.0 * ec);
        fflush(stdout);
        ll_layer_destroy(fit);
        ll_layer_destroy(chosen);
        ll_layer_destroy(ref);
        ll_material_destroy(mat);
    }
    free(s);
}

/* LL_CONVERGENCE_SWEEP="ETA K ALPHA M N0 N1": the resolution search's own
 * error (its probes, ll_probe_error against twice the resolution, the
 * compensation on) of the interface ETA + i K, ALPHA at M orders for node
 * counts from N0 to N1 in steps of 10%. Printed, not checked: how the
 * criterion the search sees moves with n (docs/method.md, "Between the
 * probes"). */
static void probe_error_against_nodes(void **state)
{
    const char *v = getenv("LL_CONVERGENCE_SWEEP");
    double eta_re, eta_im, alpha, x, lo, hi, *a, *b;
    ll_probe_set set;
    size_t m;
    (void)state;
    if (!v || !*v)
        return;
    assert_int_equal(sscanf(v, "%lf %lf %lf %zu %lf %lf", &eta_re, &eta_im, &alpha, &m, &lo, &hi),
                     6);
    assert_int_equal(ll_probe_interface(eta_re, eta_im, 0.1, &set), LL_OK);
    a = malloc(LL_PROBE_VALUES(&set) * sizeof *a);
    b = malloc(LL_PROBE_VALUES(&set) * sizeof *b);
    assert_true(a && b);
    for (x = lo; x <= hi * 1.0001; x *= 1.1) {
        size_t n = (size_t)ceil(x), k;
        n += n % 2;
        for (k = 0; k < 2; ++k) {
            lean_interface li;
            lean_interface_of(eta_re, eta_im, alpha, (k + 1) * n, &li);
            lean_interface_eval(&li, (k + 1) * m, &set, k ? b : a);
            lean_interface_free(&li);
        }
        printf("  eta %g%+gi alpha %g: n %5zu m %5zu: the probes' error %.4f\n", eta_re, eta_im,
               alpha, n, m, ll_probe_error(&set, a, b));
        fflush(stdout);
    }
    free(a);
    free(b);
    ll_probe_free(&set);
}

/* The issue's failure itself: eta 1.5, alpha 0.5 at mu_i 0.1 in the
 * mirror direction was 2.5 at the fit's 78 x 37 against 4.76 converged. */
static void grazing_mirror_of_the_issue_is_fixed(void **state)
{
    size_t n, m, fn, fm;
    ll_layer *chosen, *fit;
    double e;
    (void)state;
    assert_int_equal(ll_fit_microfacet(0.5, 1.5, 0.0, &fn, &fm), LL_OK);
    assert_int_equal(fn, 78);
    assert_int_equal(fm, 37);
    assert_int_equal(ll_test_search_microfacet(0.5, 1.5, 0.0, 0.0, 0.0, &n, &m, &e), LL_OK);
    assert_true(e <= 0.01);
    chosen = ll_test_layer(n, m);
    fit = ll_test_layer(fn, fm);
    assert_int_equal(ll_test_set_microfacet(chosen, 1.5, 0.0, 0.5, 1, 0, NULL), LL_OK);
    assert_int_equal(ll_test_set_microfacet(fit, 1.5, 0.0, 0.5, 1, 0, NULL), LL_OK);
    {
        /* Converged: 4.7689 (256 nodes with 118 to 472 orders, and 512 x
         * 118, all agree to 1e-4; the issue: 4.76). The comparison with
         * twice the chosen resolution is interfaces_meet_the_tolerance's. */
        const double converged = 4.7689;
        double vc = ll_test_layer_eval(chosen, 0.1, -0.1, 0.0), vf = ll_test_layer_eval(fit, 0.1, -0.1, 0.0);
        if (verbose())
            printf("  mirror at mu 0.1: fit %zu x %zu %.4f, chosen %zu x %zu %.4f\n", fn, fm, vf,
                   n, m, vc);
        assert_true(fabs(vf - converged) > 0.3 * converged); /* the fit's failure */
        assert_true(fabs(vc - converged) <= 0.01 * converged);
    }
    ll_layer_destroy(chosen);
    ll_layer_destroy(fit);
}

/* The probe of an interface reproduces what ll_layer_eval of the built
 * layer gives, with and without the energy compensation, for a dielectric
 * and a conductor: the search measures the layer the build makes. */
static void probe_matches_layer(double eta_re, double eta_im, double alpha, int compensate)
{
    ll_probe_set set;
    ll_probe_compensation c;
    ll_microfacet_model *mf = NULL, *mf0 = NULL;
    ll_layer *l = ll_test_layer(64, 40);
    double *v, worst = 0.0;
    size_t p, k;
    assert_int_equal(ll_probe_interface(eta_re, eta_im, 0.1, &set), LL_OK);
    assert_true(set.n_pairs > 50);
    v = malloc(LL_PROBE_VALUES(&set) * sizeof *v);
    assert_non_null(v);
    assert_int_equal(ll_probe_interface_model(eta_re, eta_im, alpha, &mf), LL_OK);
    if (compensate) {
        assert_int_equal(ll_probe_compensation_model(eta_re, eta_im, alpha, &mf0), LL_OK);
        assert_int_equal(ll_probe_compensation_make(mf0, eta_re, eta_im, 64, NULL, &c), LL_OK);
        ll_microfacet_destroy(mf0);
    }
    assert_int_equal(ll_probe_interface_eval(mf, compensate ? &c : NULL, 64, 40, &set, NULL, v),
                     LL_OK);
    if (compensate)
        ll_probe_compensation_free(&c);
    assert_int_equal(ll_test_set_microfacet(l, eta_re, eta_im, alpha, compensate, 0, NULL), LL_OK);
    for (p = 0; p < set.n_pairs; ++p)
        for (k = 0; k < set.n_phi; ++k) {
            double e = ll_test_layer_eval(l, set.pairs[p].mu_i, set.pairs[p].mu_o, set.phi[k]);
            double d = fabs(e - v[p * set.n_phi + k]) / fmax(fabs(e), 1e-3);
            worst = fmax(worst, d);
        }
    if (verbose())
        printf("  probes against the layer, eta %g%+gi alpha %g compensate %d: %.2g\n", eta_re,
               eta_im, alpha, compensate, worst);
    assert_true(worst <= 1e-9);
    free(v);
    ll_microfacet_destroy(mf);
    ll_probe_free(&set);
    ll_layer_destroy(l);
}

static void probes_are_the_layer(void **state)
{
    (void)state;
    probe_matches_layer(1.5, 0.0, 0.4, 0);
    probe_matches_layer(1.5, 0.0, 0.4, 1);
    probe_matches_layer(1.0 / 1.5, 0.0, 0.8, 1);
    /* Copper (the full grid's failure before the term was probed). */
    probe_matches_layer(0.27, 3.41, 0.8, 0);
    probe_matches_layer(0.27, 3.41, 0.8, 1);
}

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
 * with n without converging; words/medium_probe.c). */

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
static ptrdiff_t lean_stencil(const ll_layer *l, double mu, double w[4])
{
    size_t h = l->n / 2;
    ptrdiff_t offset = 0;
    assert_true(h >= 2 && mu != 0.0);
    ll_spline_weights(l->nodes + h, h, fabs(mu), &offset, w, 1);
    return mu < 0.0 ? offset : offset + (ptrdiff_t)h;
}

static ll_status lean_order(void *user, size_t l, double *P, double forward, ll_order **out)
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
static void lean_hg(double g, size_t n, size_t m, int with_forward, const point_set *s,
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
        assert_int_equal(ll_layer_set_medium_finished(layer, LL_MEDIUM_HG, 1.0, g, &finish, NULL),
                         LL_OK);
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
static void medium_points(point_set *s)
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

/* The lean evaluation is ll_layer_eval of the built layer. */
static void lean_media_evaluation_is_the_layer(void **state)
{
    point_set *s = malloc(sizeof *s);
    double *lean, worst = 0.0;
    ll_layer *l = ll_test_layer(60, 30);
    size_t k;
    (void)state;
    assert_non_null(s);
    medium_points(s);
    lean = malloc(s->count * sizeof *lean);
    assert_non_null(lean);
    lean_hg(0.8, 60, 30, 1, s, lean);
    assert_int_equal(ll_layer_set_henyey_greenstein(l, 1.0, 0.8, NULL), LL_OK);
    for (k = 0; k < s->count; ++k) {
        double v = ll_test_layer_eval(l, s->p[k].mu_i, s->p[k].mu_o, s->p[k].phi);
        worst = fmax(worst, fabs(v - lean[k]) / fmax(fabs(v), 1e-6));
    }
    if (verbose())
        printf("  lean HG evaluation against ll_layer_eval: %.2g\n", worst);
    assert_true(worst <= 1e-12);
    /* The search's probes of a medium (words/medium_probe.c), the same. */
    {
        ll_probe_set set;
        double *v, w2 = 0.0;
        size_t p, j;
        assert_int_equal(ll_probe_medium(0.1, &set), LL_OK);
        v = malloc(LL_PROBE_VALUES(&set) * sizeof *v);
        assert_non_null(v);
        assert_int_equal(ll_probe_medium_eval(LL_MEDIUM_HG, 0.8, 1, 60, 30, &set, NULL, v), LL_OK);
        for (p = 0; p < set.n_pairs; ++p)
            for (j = 0; j < set.n_phi; ++j) {
                double e = ll_test_layer_eval(l, set.pairs[p].mu_i, set.pairs[p].mu_o, set.phi[j]);
                w2 = fmax(w2, fabs(e - v[p * set.n_phi + j]) / fmax(fabs(e), 1e-6));
            }
        if (verbose())
            printf("  medium probes against ll_layer_eval: %.2g\n", w2);
        assert_true(w2 <= 1e-12);
        free(v);
        ll_probe_free(&set);
    }
    free(lean);
    free(s);
    ll_layer_destroy(l);
}

/* Media: the phase function's layer at the chosen resolution against
 * twice it, for HG up to g = 0.95 (forward and backward lobes), evaluated
 * lean (above). CI: g = 0.8 alone. */
static void media_meet_the_tolerance(void **state)
{
    static const double gs[] = { 0.5, 0.8, 0.9, 0.95, -0.9, -0.95 };
    point_set *s = malloc(sizeof *s);
    double *va, *vb;
    size_t gi, n, m, where, failed = 0;
    (void)state;
    assert_non_null(s);
    medium_points(s);
    va = malloc(s->count * sizeof *va);
    vb = malloc(s->count * sizeof *vb);
    assert_non_null(va);
    assert_non_null(vb);
    for (gi = 0; gi < sizeof gs / sizeof gs[0]; ++gi) {
        double e, err;
        if (!full_grid() && gs[gi] != 0.8)
            continue; /* CI: g = 0.8 alone (0.95's search is 19 s of CPU) */
        assert_int_equal(ll_resolution_search_henyey_greenstein(gs[gi], 0.0, 0.0, NULL, &n, &m, &err),
                         LL_OK);
        lean_hg(gs[gi], n, m, 0, s, va);
        lean_hg(gs[gi], 2 * n, 2 * m, 0, s, vb);
        e = worst_of_values(s, va, vb, &where);
        if (verbose() || e > 0.01)
            printf("  hg g=%g n %zu m %zu (probes %.4f): worst %.4f at mu_o %.3f mu_i %.3f "
                   "phi %.3f\n",
                   gs[gi], n, m, err, e, s->p[where].mu_o, s->p[where].mu_i, s->p[where].phi);
        fflush(stdout);
        if (e > 0.01)
            ++failed;
    }
    assert_int_equal(failed, 0);
    free(va);
    free(vb);
    free(s);
}

/* A slab of the medium (what a build makes of `medium ... tau=`: the
 * phase layer doubled to its thickness) at the resolution the material
 * chooses against twice it, reflection lobes (the transmission holds the
 * unscattered beam, a diagonal spike that grows with n in ll_layer_eval
 * and is not a lobe). Full grid only; skipped where twice it needs more
 * than FULL_GRID_BYTES. */
static void slabs_meet_the_tolerance(void **state)
{
    static const double gs[] = { 0.5, 0.8, 0.9, 0.95 };
    point_set *all = malloc(sizeof *all), *s = malloc(sizeof *s);
    size_t gi, k, n, m, where, failed = 0;
    (void)state;
    assert_non_null(all);
    assert_non_null(s);
    medium_points(all);
    s->count = 0;
    s->groups = all->groups;
    for (k = 0; k < all->count; ++k)
        if (all->p[k].mu_o < 0.0)
            s->p[s->count++] = all->p[k];
    for (gi = 0; gi < sizeof gs / sizeof gs[0] && full_grid(); ++gi) {
        char text[128];
        ll_material *mat = NULL;
        ll_build_options o = LL_BUILD_OPTIONS_INIT;
        ll_layer *a, *b;
        double e;
        snprintf(text, sizeof text, "medium albedo=0.95 g=%g tau=1\n", gs[gi]);
        assert_int_equal(ll_material_parse(text, "slab", &mat), LL_OK);
        o.n_channels = 1;
        assert_int_equal(ll_material_resolution(mat, &o, NULL, &n, &m, NULL), LL_OK);
        if (peak_bytes(mat, 2 * n, 2 * m) > FULL_GRID_BYTES) {
            printf("  slab g=%g n %zu m %zu: skipped (twice it needs %.1f GB)\n", gs[gi], n, m,
                   peak_bytes(mat, 2 * n, 2 * m) / 1e9);
            ll_material_destroy(mat);
            continue;
        }
        a = build_one(mat, n, m);
        b = build_one(mat, 2 * n, 2 * m);
        e = worst_difference(s, a, b, &where);
        printf("  slab g=%g tau 1 n %zu m %zu: worst %.4f at mu_o %.3f mu_i %.3f phi %.3f\n",
               gs[gi], n, m, e, s->p[where].mu_o, s->p[where].mu_i, s->p[where].phi);
        fflush(stdout);
        if (e > 0.01)
            ++failed;
        ll_layer_destroy(a);
        ll_layer_destroy(b);
        ll_material_destroy(mat);
    }
    assert_int_equal(failed, 0);
    free(all);
    free(s);
}

/* ------------------------------------------------------- cancellation */

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A monitor that cancels at its `at`-th report of the stage "resolution"
 * (the search runs for seconds and reports while it runs). */
typedef struct search_watcher {
    size_t at, reports, resolution_reports;
    double last, cancelled_at;
    int monotone, other_stage_before;
} search_watcher;

static int watch_search(void *user, double fraction, const char *stage)
{
    search_watcher *w = user;
    int resolution = stage && strcmp(stage, "resolution") == 0;
    if (w->reports++ > 0 && fraction < w->last)
        w->monotone = 0;
    w->last = fraction;
    if (!resolution && w->resolution_reports == 0)
        w->other_stage_before = 1;
    if (resolution && ++w->resolution_reports == w->at) {
        w->cancelled_at = now_seconds();
        return 1;
    }
    return w->cancelled_at > 0.0; /* (stays cancelled) */
}

/* A build whose resolution search is cancelled by its monitor in the
 * middle of the search: LL_ERROR_CANCELLED, no file (nor a temporary one),
 * nothing left allocated. */
static void search_is_cancelled_by_the_monitor(void **state)
{
    ll_material *mat = NULL;
    ll_monitor monitor = LL_MONITOR_INIT;
    search_watcher w;
    char out[600];
    double end;
    size_t entries;
    ll_status s;
    (void)state;
    memset(&w, 0, sizeof w);
    w.at = 4;
    w.monotone = 1;
    monitor.progress = watch_search;
    monitor.user = &w;
    snprintf(out, sizeof out, "%s/cancelled.bsdf", ll_test_dir());
    entries = ll_test_count_entries(ll_test_dir());
    assert_int_equal(ll_material_parse("dielectric eta=1.5 alpha=0.5\n", "cancel", &mat), LL_OK);
    ll_alloc_fail_after(0); /* (counts the blocks alive, fails none) */
    s = ll_material_build(mat, NULL, &monitor, out);
    end = now_seconds();
    assert_int_equal(ll_alloc_live(), 0);
    ll_alloc_hook_off();
    assert_int_equal(s, LL_ERROR_CANCELLED);
    assert_int_equal(w.resolution_reports, w.at); /* none after the cancel's */
    assert_true(w.monotone);
    assert_false(w.other_stage_before);
    assert_int_equal(access(out, F_OK), -1);
    assert_int_equal(ll_test_count_entries(ll_test_dir()), entries);
    if (verbose())
        printf("  search cancelled at report %zu: the build returned %.3f s later (%s)\n",
               w.at, end - w.cancelled_at, ll_last_error_message());
    ll_material_destroy(mat);
}

typedef struct raiser {
    volatile int *flag;
    double delay, raised_at;
} raiser;

static void *raise_later(void *arg)
{
    raiser *r = arg;
    struct timespec t;
    t.tv_sec = 0;
    t.tv_nsec = (long)(r->delay * 1e9);
    nanosleep(&t, NULL);
    r->raised_at = now_seconds();
    *r->flag = 1;
    return NULL;
}

/* The monitor's flag (what llbuild's monitor returns after Ctrl-C) stops
 * the estimate's search too: a flag raised from another thread while a
 * search runs gives LL_ERROR_CANCELLED with nothing left allocated. */
static int return_flag(void *user, double fraction, const char *stage)
{
    (void)fraction;
    (void)stage;
    return *(const volatile int *)user;
}

static void estimate_search_is_cancelled_by_the_flag(void **state)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_monitor monitor = LL_MONITOR_INIT;
    volatile int flag = 0;
    raiser r;
    pthread_t thread;
    double end;
    ll_status s;
    (void)state;
    monitor.progress = return_flag;
    monitor.user = (void *)(uintptr_t)&flag;
    r.flag = &flag;
    r.delay = 0.3; /* (the search takes seconds) */
    r.raised_at = 0.0;
    assert_int_equal(ll_material_parse("conductor eta=Cu alpha=0.8\n", "cancel", &mat), LL_OK);
    ll_alloc_fail_after(0);
    assert_int_equal(pthread_create(&thread, NULL, raise_later, &r), 0);
    s = ll_material_estimate(mat, &o, &e, &monitor);
    end = now_seconds();
    assert_int_equal(pthread_join(thread, NULL), 0);
    assert_int_equal(ll_alloc_live(), 0);
    ll_alloc_hook_off();
    assert_int_equal(s, LL_ERROR_CANCELLED);
    if (verbose())
        printf("  estimate cancelled by the flag: returned %.3f s after it was raised (%s)\n",
               end - r.raised_at, ll_last_error_message());
    ll_material_destroy(mat);
}

/* The goal's arguments and where it comes from. */
static void goal_is_checked_and_reported(void **state)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    double t, mu;
    int chosen;
    size_t n, m;
    (void)state;
    assert_int_equal(ll_test_search_microfacet(0.3, 1.5, 0.0, 1e-4, 0.0, &n, &m, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "tolerance"));
    assert_int_equal(ll_test_search_microfacet(0.3, 1.5, 0.0, 0.0, 1.5, &n, &m, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "mu_min"));
    assert_int_equal(ll_resolution_search_henyey_greenstein(0.5, 0.0, 0.0, NULL, NULL, &m, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_parse("set tolerance=0.05 mu_min=0.2\n"
                                       "dielectric eta=1.5 alpha=0.3\n",
                                       "goal", &mat),
                     LL_OK);
    assert_int_equal(ll_material_goal(mat, NULL, &t, &mu, &chosen), LL_OK);
    assert_true(t == 0.05 && mu == 0.2 && chosen == 1);
    o.tolerance = 0.02;
    assert_int_equal(ll_material_goal(mat, &o, &t, &mu, &chosen), LL_OK);
    assert_true(t == 0.02 && mu == 0.2);
    o.n_nodes = 100;
    o.n_orders = 50;
    assert_int_equal(ll_material_goal(mat, &o, &t, &mu, &chosen), LL_OK);
    assert_int_equal(chosen, 0);
    o = (ll_build_options)LL_BUILD_OPTIONS_INIT;
    o.tolerance = 2.0;
    assert_int_equal(ll_material_resolution(mat, &o, NULL, &n, &m, NULL), LL_ERROR_INVALID_ARGUMENT);
    ll_material_destroy(mat);
    mat = NULL;
    assert_int_equal(ll_material_parse("set tolerance=0.0001\ndielectric eta=1.5 alpha=0.3\n",
                                       "goal", &mat),
                     LL_ERROR_PARSE);
    assert_non_null(strstr(ll_last_error_message(), "goal:1:"));
    assert_int_equal(ll_material_parse("set mu_min=0.1 mu_min=0.2\n", "goal", &mat),
                     LL_ERROR_PARSE);
    assert_non_null(strstr(ll_last_error_message(), "twice"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(probes_are_the_layer),
        cmocka_unit_test(goal_is_checked_and_reported),
        cmocka_unit_test(grazing_mirror_of_the_issue_is_fixed),
        cmocka_unit_test(interfaces_meet_the_tolerance),
        cmocka_unit_test(lean_media_evaluation_is_the_layer),
        cmocka_unit_test(media_meet_the_tolerance),
        cmocka_unit_test(slabs_meet_the_tolerance),
        cmocka_unit_test(resolution_table),
        cmocka_unit_test(probe_error_against_nodes),
        cmocka_unit_test(search_is_cancelled_by_the_monitor),
        cmocka_unit_test(estimate_search_is_cancelled_by_the_flag),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
