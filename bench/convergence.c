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
 *
 * Each case (an interface word, a medium, a slab, a row of the table) runs
 * as a test of cmocka's runner, so that a failed check prints the case's
 * name, the check and its values (assert_ll_ok: the library's message) and
 * the mode goes on with the next case; the exit status is 1 when any case
 * failed. (Outside a runner cmocka's assertions end the program with
 * status 255 and keep their message.) A metal's spectra are looked for in
 * $LAYERLAB_IOR_DIR and, this program linking liblayerlab.a, in
 * ../share/layerlab/ior from the program's own folder: build it in
 * BUILD/bench as bench/run.sh does, or set LAYERLAB_IOR_DIR=data/ior.
 */
#include "convergence_util.h"

/* The cases of the mode being run, one cmocka test each: the test's
 * name and its state. 8 interfaces x 6 roughnesses is the largest mode. */
#define MAX_CASES 64

typedef struct bench_case {
    char name[128]; /* the word without its newline, the medium or the row's label */
    char text[128]; /* the word, one line (interfaces, the table's rows) */
    double eta, g;  /* a dielectric's relative index; HG's asymmetry       */
    int conductor;
} bench_case;

static bench_case bench_cases[MAX_CASES];
static struct CMUnitTest bench_tests[MAX_CASES];
static size_t bench_count;
/* convergence full: the cases off by more than the tolerance 1% (each
 * also a failed test, with the other failed checks). */
static size_t off_count;

static bench_case *add_case(CMUnitTestFunction run, const char *name)
{
    bench_case *c;
    if (bench_count == MAX_CASES) {
        fprintf(stderr, "convergence: more than %d cases\n", MAX_CASES);
        exit(2);
    }
    c = &bench_cases[bench_count];
    memset(c, 0, sizeof *c);
    snprintf(c->name, sizeof c->name, "%.*s", (int)strcspn(name, "\n"), name);
    snprintf(c->text, sizeof c->text, "%s", name);
    bench_tests[bench_count].name = c->name;
    bench_tests[bench_count].test_func = run;
    bench_tests[bench_count].setup_func = NULL;
    bench_tests[bench_count].teardown_func = NULL;
    bench_tests[bench_count].initial_state = c;
    ++bench_count;
    return c;
}

/* The cases added so far as one group of cmocka's runner (the function
 * behind its cmocka_run_group_tests macro, which needs an array of fixed
 * size); the count of failed tests. */
static int run_cases(const char *group)
{
    int failed = _cmocka_run_group_tests(group, bench_tests, bench_count, NULL, NULL);
    bench_count = 0;
    return failed;
}

/* The dense scan's direction pairs of the interface (eta, conductor) into
 * set->pairs, or (pairs NULL) only counted: set->n_pairs and n_groups. */
static void dense_pairs(ll_probe_set *set, double eta, int conductor)
{
    static const double offsets[] = { 0.0,   -0.01, 0.01, -0.02, 0.02, -0.03, 0.03,
                                      -0.05, 0.05,  -0.08, 0.08, -0.15, 0.15 };
    size_t k, j;
    int side;
    set->n_pairs = set->n_groups = 0;
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
                    if (set->pairs) {
                        assert_true(set->n_pairs < set->cap_pairs);
                        set->pairs[set->n_pairs].mu_o = centre[b] < 0.0 ? -c : c;
                        set->pairs[set->n_pairs].mu_i = sign * mu;
                        set->pairs[set->n_pairs].group = set->n_groups;
                    }
                    ++set->n_pairs;
                }
                ++set->n_groups;
            }
        }
}

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
    ll_probe_set set;
    double *va, *vb, *peak, worst = 0.0, at_o = 0.0, at_i = 0.0, at_phi = 0.0, at_ratio = 0.0;
    size_t p, j;
    memset(&set, 0, sizeof set);
    /* Counted first: the set holds exactly the case's pairs. */
    dense_pairs(&set, eta, conductor);
    set.cap_pairs = set.n_pairs;
    set.pairs = malloc((set.cap_pairs + 1) * sizeof *set.pairs);
    assert_non_null(set.pairs);
    set.n_phi = LOBE_PHIS;
    for (j = 0; j < LOBE_PHIS; ++j)
        set.phi[j] = lobe_phis[j];
    dense_pairs(&set, eta, conductor);
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

/* convergence dense, one case: the dense scan at the resolution the search
 * chooses. */
static void dense_case(void **state)
{
    const bench_case *c = *state;
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    lean_interface la, lb;
    size_t n, m;
    assert_ll_ok(ll_material_parse(c->text, "convergence", &mat));
    o.n_channels = 1;
    assert_ll_ok(ll_material_resolution(mat, &o, NULL, &n, &m, NULL));
    lean_interface_make(mat, c->conductor, n, &la);
    lean_interface_make(mat, c->conductor, 2 * n, &lb);
    printf("  %s at n %zu m %zu:", c->name, n, m);
    dense_scan(&la, &lb, m, c->eta, c->conductor);
    fflush(stdout);
    lean_interface_free(&la);
    lean_interface_free(&lb);
    ll_material_destroy(mat);
}

/* The grid's interfaces (those LL_CONVERGENCE_CASES selects), one case each,
 * for run, the mode's test. */
static void add_interface_cases(CMUnitTestFunction run)
{
    char text[128];
    size_t c, a;
    for (c = 0; c < sizeof cases / sizeof cases[0]; ++c)
        for (a = 0; a < sizeof alphas / sizeof alphas[0]; ++a) {
            snprintf(text, sizeof text, "%s alpha=%g\n", cases[c].name, alphas[a]);
            if (selected(text)) {
                bench_case *bc = add_case(run, text);
                bc->eta = cases[c].eta;
                bc->conductor = cases[c].conductor;
            }
        }
}

/* convergence full, an interface: within the tolerance 1% against twice
 * the chosen resolution (check_interface prints the worst point of a case
 * off). */
static void interface_case_within(void **state)
{
    const bench_case *c = *state;
    if (!check_interface(c->text, c->eta, c->conductor, 0.01)) {
        ++off_count;
        fail_msg("%s: off by more than the tolerance 1%%", c->name);
    }
}

/* Media: HG's phase layer at the chosen resolution against twice it, lean
 * (media_case), within 1%. */
static void medium_case_within(void **state)
{
    const bench_case *c = *state;
    point_set *s = malloc(sizeof *s);
    double e;
    assert_non_null(s);
    medium_points(s);
    e = media_case(c->g, s);
    free(s);
    if (e > 0.01) {
        ++off_count;
        fail_msg("%s: worst %.4f, off by more than the tolerance 1%%", c->name, e);
    }
}

/* A slab of the medium (what a build makes of `medium ... tau=`: the
 * phase layer doubled to its thickness) at the resolution the material
 * chooses against twice it, reflection lobes (the transmission holds the
 * unscattered beam, a diagonal spike that grows with n in ll_layer_eval
 * and is not a lobe), within 1%. Skipped where twice it needs more than
 * FULL_GRID_BYTES. */
static void slab_case_within(void **state)
{
    const bench_case *c = *state;
    point_set *all = malloc(sizeof *all), *s = malloc(sizeof *s);
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *a, *b;
    size_t k, n, m, where;
    double e;
    assert_non_null(all);
    assert_non_null(s);
    medium_points(all);
    s->count = 0;
    s->groups = all->groups;
    for (k = 0; k < all->count; ++k)
        if (all->p[k].mu_o < 0.0)
            s->p[s->count++] = all->p[k];
    free(all);
    assert_ll_ok(ll_material_parse(c->text, "slab", &mat));
    o.n_channels = 1;
    assert_ll_ok(ll_material_resolution(mat, &o, NULL, &n, &m, NULL));
    if (peak_bytes(mat, 2 * n, 2 * m) > FULL_GRID_BYTES) {
        printf("  %s n %zu m %zu: skipped (twice it needs %.1f GB)\n", c->name, n, m,
               peak_bytes(mat, 2 * n, 2 * m) / 1e9);
        ll_material_destroy(mat);
        free(s);
        skip();
    }
    a = build_one(mat, n, m);
    b = build_one(mat, 2 * n, 2 * m);
    e = worst_difference(s, a, b, &where);
    printf("  %s n %zu m %zu: worst %.4f at mu_o %.3f mu_i %.3f phi %.3f\n", c->name, n, m, e,
           s->p[where].mu_o, s->p[where].mu_i, s->p[where].phi);
    fflush(stdout);
    ll_layer_destroy(a);
    ll_layer_destroy(b);
    ll_material_destroy(mat);
    free(s);
    if (e > 0.01) {
        ++off_count;
        fail_msg("%s: off by more than the tolerance 1%%", c->name);
    }
}

/* convergence full: the interfaces, media and slabs; the count of failed
 * cases. */
static int full_grid(void)
{
    static const double media[] = { 0.5, 0.8, 0.9, 0.95, -0.9, -0.95 };
    static const double slabs[] = { 0.5, 0.8, 0.9, 0.95 };
    char text[128];
    size_t k;
    int failed;
    add_interface_cases(interface_case_within);
    for (k = 0; k < sizeof media / sizeof media[0]; ++k) {
        snprintf(text, sizeof text, "hg g=%g", media[k]);
        add_case(medium_case_within, text)->g = media[k];
    }
    for (k = 0; k < sizeof slabs / sizeof slabs[0]; ++k) {
        snprintf(text, sizeof text, "medium albedo=0.95 g=%g tau=1\n", slabs[k]);
        add_case(slab_case_within, text)->g = slabs[k];
    }
    failed = run_cases("convergence full");
    printf("convergence full: %zu case%s off by more than 1%%, %zu stopped by a failed check\n",
           off_count, off_count == 1 ? "" : "s", (size_t)failed - off_count);
    return failed;
}

/* convergence table: docs/method.md's resolution table, before (the
 * original's fit, ll_fit_microfacet) and after (the tolerance 1%), each
 * against the layer at twice the chosen n and m, at the grazing incident
 * cosines 0.1, 0.15, 0.2 alone (mirror and off-mirror, reflection and
 * transmission), compensation on. Markdown rows: each as it is measured
 * (among the runner's lines) and the table once every row is. */
static char table_rows[MAX_CASES][640];

static void table_row(void **state)
{
    const bench_case *c = *state;
    point_set *s = malloc(sizeof *s);
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *fit, *chosen, *ref;
    size_t n, m, fn, fm, where;
    double eta_re, eta_im, alpha, ef, ec;
    assert_non_null(s);
    assert_ll_ok(ll_material_parse(c->text, "table", &mat));
    o.n_channels = 1;
    assert_ll_ok(ll_material_resolution(mat, &o, NULL, &n, &m, NULL));
    /* The fit of the layer's own index (gold: its monochrome channel). */
    interface_params(mat, c->conductor, &eta_re, &eta_im, &alpha);
    assert_ll_ok(ll_fit_microfacet(alpha, eta_re, eta_im, &fn, &fm));
    fit = build_one(mat, fn, fm);
    chosen = build_one(mat, n, m);
    ref = build_one(mat, 2 * n, 2 * m);
    interface_points_of(s, c->eta, c->conductor, 3);
    ef = worst_difference(s, fit, ref, &where);
    ec = worst_difference(s, chosen, ref, &where);
    snprintf(table_rows[c - bench_cases], sizeof table_rows[0],
             "| %s | %zu x %zu, %.3g%% | %zu x %zu, %.2f%% |", c->name, fn, fm, 100.0 * ef, n, m,
             100.0 * ec);
    printf("%s\n", table_rows[c - bench_cases]);
    fflush(stdout);
    ll_layer_destroy(fit);
    ll_layer_destroy(chosen);
    ll_layer_destroy(ref);
    ll_material_destroy(mat);
    free(s);
}

static int resolution_table(void)
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
    static const char header[] =
        "| interface | before: n x m, worst | after: n x m, worst |\n|---|---|---|\n";
    size_t r, count;
    int failed;
    for (r = 0; r < sizeof rows / sizeof rows[0]; ++r)
        if (selected(rows[r].text)) {
            /* The test's name is the row's label; its word is the row's. */
            bench_case *c = add_case(table_row, rows[r].label);
            snprintf(c->text, sizeof c->text, "%s", rows[r].text);
            c->eta = rows[r].eta;
            c->conductor = rows[r].conductor;
            table_rows[bench_count - 1][0] = '\0';
        }
    count = bench_count;
    printf("%s", header);
    failed = run_cases("convergence table");
    printf("\n%s", header);
    for (r = 0; r < count; ++r)
        if (table_rows[r][0])
            printf("%s\n", table_rows[r]);
    if (failed)
        printf("(%d row%s failed: above)\n", failed, failed == 1 ? "" : "s");
    return failed;
}

/* convergence sweep ETA K ALPHA M N0 N1: the resolution search's own
 * error (its probes, ll_probe_error against twice the resolution, the
 * compensation on) of the interface ETA + i K, ALPHA at M orders for node
 * counts from N0 to N1 in steps of 10%. Printed, not checked: how the
 * criterion the search sees moves with n (docs/method.md, "Between the
 * probes"). */
static struct {
    double eta_re, eta_im, alpha, lo, hi;
    size_t m;
} sweep;

static void probe_error_against_nodes(void **state)
{
    double eta_re = sweep.eta_re, eta_im = sweep.eta_im, alpha = sweep.alpha;
    double x, *a, *b;
    size_t m = sweep.m;
    ll_probe_set set;
    (void)state;
    assert_ll_ok(ll_probe_interface(eta_re, eta_im, 0.1, &set));
    a = malloc(LL_PROBE_VALUES(&set) * sizeof *a);
    b = malloc(LL_PROBE_VALUES(&set) * sizeof *b);
    assert_true(a && b);
    for (x = sweep.lo; x <= sweep.hi * 1.0001; x *= 1.1) {
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
    /* Line by line, so that cmocka's failure messages (stderr) stand next
     * to their case's lines in one log. */
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (argc == 2 && strcmp(argv[1], "full") == 0)
        return full_grid() ? 1 : 0;
    if (argc == 2 && strcmp(argv[1], "table") == 0)
        return resolution_table() ? 1 : 0;
    if (argc == 2 && strcmp(argv[1], "dense") == 0) {
        add_interface_cases(dense_case);
        return run_cases("convergence dense") ? 1 : 0;
    }
    if (argc == 8 && strcmp(argv[1], "sweep") == 0) {
        char name[128];
        double m = number(argv[5], "M");
        if (!(m >= 1.0 && m <= 1e6 && m == floor(m)))
            usage(argv[0]);
        sweep.eta_re = number(argv[2], "ETA");
        sweep.eta_im = number(argv[3], "K");
        sweep.alpha = number(argv[4], "ALPHA");
        sweep.m = (size_t)m;
        sweep.lo = number(argv[6], "N0");
        sweep.hi = number(argv[7], "N1");
        snprintf(name, sizeof name, "sweep %s %s %s %s %s %s", argv[2], argv[3], argv[4],
                 argv[5], argv[6], argv[7]);
        add_case(probe_error_against_nodes, name);
        return run_cases("convergence sweep") ? 1 : 0;
    }
    usage(argv[0]);
    return 2;
}
