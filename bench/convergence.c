/*
 * The resolution's convergence beyond what tests/test_convergence.c checks
 * (it runs a subset of the grid): the whole grid, the media and slabs, the
 * resolution table of docs/method.md and the scans behind its section
 * "Between the probes". Run by `make bench-full` (bench/run.sh --full);
 * shares its points, lean layers and checks with the test through
 * tests/convergence_util.h. Every line names what it built: the word's
 * text (interfaces, slabs), HG's asymmetry (a phase function alone,
 * albedo 1), the table's row.
 *
 * usage: convergence full      the grid: 8 interfaces x 6 roughnesses at
 *                              the tolerance 1% against twice the chosen
 *                              resolution (lean where twice it would need
 *                              more than 4 GB), HG g = 0.5 .. 0.95, -0.9,
 *                              -0.95, and slabs of the medium; exit status
 *                              1 when a case is off by more than 1%
 *        convergence table     docs/method.md's resolution table (markdown)
 *        convergence dense     the dense scan of every interface case
 *        convergence sweep ETA K ALPHA M N0 N1
 *                              the search's own error against n
 * LL_CONVERGENCE_CASES=TEXT keeps the cases whose word contains TEXT
 * (e.g. "conductor", "none": no interface); LL_CONVERGENCE_VERBOSE=1
 * prints every case of the grid, not only those off.
 */
#include "convergence_util.h"

/* The dense scan (convergence dense; LL_CONVERGENCE_CASES selects): the
 * worst difference at a dense scan of the lobes, not only at the test's points: incident cosines
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

/* The grid's interfaces (those LL_CONVERGENCE_CASES selects): the count
 * off by more than the tolerance 1%. */
static size_t interfaces_grid(void)
{
    char text[128];
    size_t c, a, failed = 0;
    for (c = 0; c < sizeof cases / sizeof cases[0]; ++c)
        for (a = 0; a < sizeof alphas / sizeof alphas[0]; ++a) {
            snprintf(text, sizeof text, "%s alpha=%g\n", cases[c].name, alphas[a]);
            if (selected(text) && !check_interface(text, cases[c].eta, cases[c].conductor, 0.01))
                ++failed;
        }
    return failed;
}

/* Media: HG's phase layer at the chosen resolution against twice it, lean
 * (media_case); the count off by more than 1%. */
static size_t media_grid(void)
{
    static const double gs[] = { 0.5, 0.8, 0.9, 0.95, -0.9, -0.95 };
    point_set *s = malloc(sizeof *s);
    size_t gi, failed = 0;
    assert_non_null(s);
    medium_points(s);
    for (gi = 0; gi < sizeof gs / sizeof gs[0]; ++gi)
        if (media_case(gs[gi], s) > 0.01)
            ++failed;
    free(s);
    return failed;
}

/* A slab of the medium (what a build makes of `medium ... tau=`: the
 * phase layer doubled to its thickness) at the resolution the material
 * chooses against twice it, reflection lobes (the transmission holds the
 * unscattered beam, a diagonal spike that grows with n in ll_layer_eval
 * and is not a lobe); the count off by more than 1%. Skipped where twice
 * it needs more than FULL_GRID_BYTES. */
static size_t slabs_grid(void)
{
    static const double gs[] = { 0.5, 0.8, 0.9, 0.95 };
    point_set *all = malloc(sizeof *all), *s = malloc(sizeof *s);
    size_t gi, k, n, m, where, failed = 0;
    assert_non_null(all);
    assert_non_null(s);
    medium_points(all);
    s->count = 0;
    s->groups = all->groups;
    for (k = 0; k < all->count; ++k)
        if (all->p[k].mu_o < 0.0)
            s->p[s->count++] = all->p[k];
    for (gi = 0; gi < sizeof gs / sizeof gs[0]; ++gi) {
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
            printf("  %.*s n %zu m %zu: skipped (twice it needs %.1f GB)\n",
                   (int)strcspn(text, "\n"), text, n, m, peak_bytes(mat, 2 * n, 2 * m) / 1e9);
            ll_material_destroy(mat);
            continue;
        }
        a = build_one(mat, n, m);
        b = build_one(mat, 2 * n, 2 * m);
        e = worst_difference(s, a, b, &where);
        printf("  %.*s n %zu m %zu: worst %.4f at mu_o %.3f mu_i %.3f phi %.3f\n",
               (int)strcspn(text, "\n"), text, n, m, e, s->p[where].mu_o, s->p[where].mu_i,
               s->p[where].phi);
        fflush(stdout);
        if (e > 0.01)
            ++failed;
        ll_layer_destroy(a);
        ll_layer_destroy(b);
        ll_material_destroy(mat);
    }
    free(all);
    free(s);
    return failed;
}

/* convergence table: docs/method.md's resolution table, before (the
 * original's fit, ll_fit_microfacet) and after (the tolerance 1%), each
 * against the layer at twice the chosen n and m, at the grazing incident
 * cosines 0.1, 0.15, 0.2 alone (mirror and off-mirror, reflection and
 * transmission), compensation on. Prints markdown rows. */
static void resolution_table(void)
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
    point_set *s = malloc(sizeof *s);
    size_t r;
    assert_non_null(s);
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

/* convergence sweep ETA K ALPHA M N0 N1: the resolution search's own
 * error (its probes, ll_probe_error against twice the resolution, the
 * compensation on) of the interface ETA + i K, ALPHA at M orders for node
 * counts from N0 to N1 in steps of 10%. Printed, not checked: how the
 * criterion the search sees moves with n (docs/method.md, "Between the
 * probes"). */
static void probe_error_against_nodes(double eta_re, double eta_im, double alpha, size_t m,
                                      double lo, double hi)
{
    double x, *a, *b;
    ll_probe_set set;
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

static double number(const char *text, const char *what)
{
    char *end;
    double v = strtod(text, &end);
    if (end == text || *end || !isfinite(v)) {
        fprintf(stderr, "convergence: %s: not a number: %s\n", what, text);
        exit(2);
    }
    return v;
}

static void usage(const char *argv0)
{
    fprintf(stderr, "usage: %s full | table | dense | sweep ETA K ALPHA M N0 N1\n", argv0);
    exit(2);
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "full") == 0) {
        size_t failed = interfaces_grid();
        failed += media_grid();
        failed += slabs_grid();
        printf("convergence full: %zu case%s off by more than 1%%\n", failed,
               failed == 1 ? "" : "s");
        return failed ? 1 : 0;
    }
    if (argc == 2 && strcmp(argv[1], "table") == 0) {
        resolution_table();
        return 0;
    }
    if (argc == 2 && strcmp(argv[1], "dense") == 0) {
        char text[128];
        size_t c, a;
        for (c = 0; c < sizeof cases / sizeof cases[0]; ++c)
            for (a = 0; a < sizeof alphas / sizeof alphas[0]; ++a) {
                snprintf(text, sizeof text, "%s alpha=%g\n", cases[c].name, alphas[a]);
                if (selected(text))
                    dense_case(text, cases[c].eta, cases[c].conductor);
            }
        return 0;
    }
    if (argc == 8 && strcmp(argv[1], "sweep") == 0) {
        double m = number(argv[5], "M");
        if (!(m >= 1.0 && m <= 1e6 && m == floor(m)))
            usage(argv[0]);
        probe_error_against_nodes(number(argv[2], "ETA"), number(argv[3], "K"),
                                  number(argv[4], "ALPHA"), (size_t)m, number(argv[6], "N0"),
                                  number(argv[7], "N1"));
        return 0;
    }
    usage(argv[0]);
    return 2;
}
