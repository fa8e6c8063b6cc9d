/*
 * The resolution chosen by a tolerance: a layer built at the resolution
 * that ll_material_resolution chooses agrees with the same layer at twice
 * its nodes and twice its orders within the tolerance, at grazing (mu 0.1,
 * 0.15, 0.2) and pseudo-random directions, mirror and off-mirror azimuths,
 * reflection and transmission, wherever the BSDF is above 1% of the peak
 * of its lobe. The layers are built with the public API alone (the
 * material language, energy compensation on), at points other than the
 * search's own probes (search/probe_set.c), so the test checks the method
 * and not the probes against themselves.
 *
 * The grid (dielectrics eta 1.1, 1.33, 1.5, 2.0, 1/1.5 and gold,
 * aluminium, copper at alpha 0.02 .. 0.8) takes minutes at 2n, 2m for the
 * small roughnesses (n ~ 1000, m ~ 2000); this test runs the subset below
 * (and HG g = 0.8 alone). The whole grid, the slabs, docs/method.md's
 * resolution table and the research scans are bench/convergence.c's
 * (`make bench-full`); both share tests/convergence_util.h.
 * LL_CONVERGENCE_VERBOSE=1 prints every case.
 */
#include "convergence_util.h"

#include "material/material.h"
#include "support/watch.h"

#include <time.h>
#include <unistd.h>

/* The subset CI runs (index into cases, alpha): the issue's own failure
 * (eta 1.5, alpha 0.5), eta 1.5, alpha 0.8, which the full grid found
 * 1.04% off at phi 0.5 (transmission at mu_i 0.1) while the probes'
 * azimuths stepped from 0.3 to 0.6 (probe_set.c), and three metals:
 * copper, alpha 0.8 is the case that the compensation's term left out of
 * the probes made 1.32% off. The search probes the compensation now, which
 * costs O(n^2) per node count (seconds of CPU for a dielectric), so eta
 * 1/1.5, alpha 0.8 and eta 2, alpha 0.5 are left to the full grid, which
 * keeps this subset short. */
static const struct {
    size_t c;
    double alpha;
} ci_subset[] = { { 2, 0.5 }, { 2, 0.8 }, { 5, 0.3 }, { 7, 0.5 }, { 7, 0.8 } };

static void interfaces_meet_the_tolerance(void **state)
{
    char text[128];
    size_t c;
    (void)state;
    for (c = 0; c < sizeof ci_subset / sizeof ci_subset[0]; ++c) {
        const interface_case *ic = &cases[ci_subset[c].c];
        snprintf(text, sizeof text, "%s alpha=%g\n", ic->name, ci_subset[c].alpha);
        assert_true(check_interface(text, ic->eta, ic->conductor, 0.01));
    }
}

/* A GGX dielectric (eta 1.5, alpha 0.1: its search is about a second of
 * CPU, twice its resolution is evaluated lean) meets the tolerance at the
 * points whose spline stencils do not straddle its transmission jump: the
 * search leaves the straddling probes out (search/probe_jump.c), and so
 * does the check (leave_out_jump), since within one node interval of the
 * jump the file smears it at any node count. */
static void ggx_meets_the_tolerance_away_from_the_jump(void **state)
{
    (void)state;
    assert_true(check_interface("dielectric eta=1.5 dist=ggx alpha=0.1\n", 1.5, 0, 0.01));
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
    /* The search's probes of a medium (search/medium_probe.c), the same. */
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
/* Media: the phase function's layer at the chosen resolution against
 * twice it, evaluated lean (convergence_util.h), for HG g = 0.8 (forward
 * and backward lobes; bench/convergence.c runs g up to 0.95 and -0.95,
 * whose search is 19 s of CPU). */
static void media_meet_the_tolerance(void **state)
{
    point_set *s = malloc(sizeof *s);
    (void)state;
    assert_non_null(s);
    medium_points(s);
    assert_true(media_case(0.8, s) <= 0.01);
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
 * (ll_material_*: "resolution K/COUNT", the K-th search; the search runs for
 * seconds and reports while it runs). */
typedef struct search_watcher {
    size_t at, reports, resolution_reports;
    double last, cancelled_at;
    int monotone, other_stage_before;
} search_watcher;

static int watch_search(void *user, double fraction, const char *stage)
{
    search_watcher *w = user;
    int resolution = stage && strncmp(stage, "resolution", 10) == 0;
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

/* The estimate runs the same searches and polls its monitor the same way:
 * cancelled at the fourth "resolution" report it returns LL_ERROR_CANCELLED
 * with no report after that one and nothing left allocated. */
static void estimate_search_is_cancelled_by_the_monitor(void **state)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_monitor monitor = LL_MONITOR_INIT;
    search_watcher w;
    ll_status s;
    (void)state;
    memset(&w, 0, sizeof w);
    w.at = 4;
    w.monotone = 1;
    monitor.progress = watch_search;
    monitor.user = &w;
    assert_int_equal(ll_material_parse("conductor eta=Cu alpha=0.8\n", "cancel", &mat), LL_OK);
    ll_alloc_fail_after(0); /* (counts the blocks alive, fails none) */
    s = ll_material_estimate(mat, &o, &e, &monitor);
    assert_int_equal(ll_alloc_live(), 0);
    ll_alloc_hook_off();
    assert_int_equal(s, LL_ERROR_CANCELLED);
    assert_int_equal(w.resolution_reports, w.at); /* none after the cancel's */
    assert_true(w.monotone);
    if (verbose())
        printf("  estimate cancelled at report %zu (%s)\n", w.at, ll_last_error_message());
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
        cmocka_unit_test(ggx_meets_the_tolerance_away_from_the_jump),
        cmocka_unit_test(lean_media_evaluation_is_the_layer),
        cmocka_unit_test(media_meet_the_tolerance),
        cmocka_unit_test(search_is_cancelled_by_the_monitor),
        cmocka_unit_test(estimate_search_is_cancelled_by_the_monitor),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
