/*
 * Textured table files (reader/tables_textured.c): a small swept material
 * (coat roughness 0.1 and 0.3 over gold) built to a textured .bsdf,
 * written as tables at a small explicit grid, and opened: the parameters
 * as on the .bsdf; the grids of each basis stored as float16, the rest as
 * float32, and a float32 file of the same values (as written before)
 * read the same; at a node of the parameter the values are those of
 * that basis' own (untextured) float16 table; between nodes the blend of the two
 * with the .bsdf's weights; sampling's pdf and value are the evaluated
 * ones, and its pdf integrates to 1; batches with per-element weights are
 * the scalar calls; and the tables are measured against the .bsdf at
 * random parameter values (tests/tables_figures.h), to the loose bounds
 * of this small grid (test_tables_tolerance.c holds the chosen grids to
 * the tolerance).
 */
#include "test_bsdf_util.h"
#include "tables_figures.h"
#include "tables_float32.h"
#include "writer/bsdf_write_tables.h"
#include "writer/bsdf_write_tensor.h"

static char bsdf_path[600], tab_path[600], golden_path[600] = LL_TEST_GOLDEN;

static int setup(void **state)
{
    ll_material *m = NULL;
    ll_bsdf *src = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    ll_test_dir_setup(state);
    snprintf(bsdf_path, sizeof bsdf_path, "%s/swept.bsdf", ll_test_dir());
    snprintf(tab_path, sizeof tab_path, "%s/swept.tab", ll_test_dir());
    o.n_theta_i = 12;
    o.vndf_size = 32;
    o.sample_size = 24;
    if (ll_material_parse("set nodes=30 orders=40\n"
                          "dielectric name=coat eta=1.5 alpha=[0.1 0.3]\n"
                          "conductor name=gold eta=Au alpha=0.2\n",
                          "swept.layers", &m) != LL_OK ||
        ll_material_build(m, NULL, NULL, bsdf_path) != LL_OK ||
        ll_bsdf_open(bsdf_path, NULL, &src) != LL_OK ||
        ll_tables_write_from_bsdf(src, tab_path, &o, NULL) != LL_OK)
        return 1;
    ll_material_destroy(m);
    ll_bsdf_release(src);
    return 0;
}

static ll_bsdf *open_file(const char *p)
{
    ll_bsdf *b = NULL;
    if (ll_bsdf_open(p, NULL, &b) != LL_OK)
        fail_msg("%s: %s", p, ll_last_error_message());
    return b;
}

static uint64_t rng = 77;

static double uniform(void) { return tf_uniform(&rng); }

static void random_pair(double wo[3], double wi[3])
{
    tf_direction(acos(uniform()) * 0.95, 2.0 * TF_PI * uniform(), wo);
    tf_direction(acos(uniform()) * 0.95, 2.0 * TF_PI * uniform(), wi);
}

static void test_parameters(void **state)
{
    ll_bsdf *t = open_file(tab_path), *src = open_file(bsdf_path);
    ll_bsdf_info it = LL_BSDF_INFO_INIT, is = LL_BSDF_INFO_INIT;
    double x[1] = { 0.15 };
    float wt[2], ws[2];
    const char *name = NULL;
    (void)state;
    assert_int_equal(ll_bsdf_get_info(t, &it), LL_OK);
    assert_int_equal(ll_bsdf_get_info(src, &is), LL_OK);
    assert_int_equal(it.format, LL_BSDF_FORMAT_TABLES);
    assert_int_equal(it.n_bases, 2);
    assert_int_equal(it.n_parameters, is.n_parameters);
    assert_string_equal(it.metadata, is.metadata);
    assert_int_equal(ll_bsdf_get_parameter_name(t, 0, &name), LL_OK);
    assert_string_equal(name, "coat.alpha");
    assert_int_equal(ll_bsdf_basis_coefficients(t, x, wt), LL_OK);
    assert_int_equal(ll_bsdf_basis_coefficients(src, x, ws), LL_OK);
    assert_true(wt[0] == ws[0] && wt[1] == ws[1]);
    assert_true(fabs(wt[0] - 0.75) < 1e-6);
    /* A textured file needs the weights. */
    {
        double wo[3] = { 0, 0, 1 }, wi[3] = { 0.3, 0, 0.95 }, f[3];
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, NULL, f),
                         LL_ERROR_INVALID_ARGUMENT);
    }
    ll_bsdf_release(t);
    ll_bsdf_release(src);
}

/* At a node: basis k's own table, written from its untextured view with
 * the grids rounded to float16 as a textured file's are (the float32
 * table would differ by that rounding: the nodes sit where the rounded
 * VNDF's warp puts them). */
static void test_node_is_basis_table(void **state)
{
    ll_bsdf *t = open_file(tab_path), *src = open_file(bsdf_path), *view = NULL, *one;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    char path[600];
    size_t k, n;
    int c;
    (void)state;
    o.n_theta_i = 12;
    o.vndf_size = 32;
    o.sample_size = 24;
    for (k = 0; k < 2; ++k) {
        float w[2] = { 0.0f, 0.0f };
        w[k] = 1.0f;
        snprintf(path, sizeof path, "%s/basis%zu.tab", ll_test_dir(), k);
        assert_int_equal(ll_tables_basis_view(src, k, &view), LL_OK);
        assert_int_equal(ll_tables_write_half(view, path, &o, NULL), LL_OK);
        ll_bsdf_release(view);
        one = open_file(path);
        for (n = 0; n < 2000; ++n) {
            double wo[3], wi[3], a[3], b[3], pa, pb, u[2], sa[3], sb[3], fa[3], fb[3];
            random_pair(wo, wi);
            assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, w, a), LL_OK);
            assert_int_equal(ll_bsdf_eval_dir(one, wo, wi, LL_TRANSPORT_RADIANCE, NULL, b), LL_OK);
            assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, w, &pa), LL_OK);
            assert_int_equal(ll_bsdf_pdf_dir(one, wo, wi, NULL, &pb), LL_OK);
            for (c = 0; c < 3; ++c)
                assert_true(a[c] == b[c]);
            assert_true(pa == pb);
            u[0] = uniform();
            u[1] = uniform();
            assert_int_equal(ll_bsdf_sample_dir(t, wo, u, LL_TRANSPORT_RADIANCE, w, sa, &pa, fa),
                             LL_OK);
            assert_int_equal(ll_bsdf_sample_dir(one, wo, u, LL_TRANSPORT_RADIANCE, NULL, sb, &pb,
                                                fb),
                             LL_OK);
            assert_true(pa == pb);
            for (c = 0; c < 3; ++c)
                assert_true(sa[c] == sb[c] && fa[c] == fb[c]);
        }
        ll_bsdf_release(one);
    }
    ll_bsdf_release(t);
    ll_bsdf_release(src);
}

/* The file's fields: each basis' vndf, luminance and rgb float16, the
 * rest float32 (the parameter block, theta_i, phi_i, ndf, sigma). The
 * same values written as float32 (a textured file as written before
 * float16) open and evaluate, pdf and sample bit for bit the same. */
static void test_float16_fields(void **state)
{
    size_t k;
    ll_bsdf *t, *t32;
    char path[600];
    int c;
    (void)state;
    snprintf(path, sizeof path, "%s/swept32.tab", ll_test_dir());
    tables_rewrite_float32(tab_path, path, 6);
    t = open_file(tab_path);
    t32 = open_file(path);
    for (k = 0; k < 500; ++k) {
        double wo[3], wi[3], a[3], b[3], pa, pb, u[2], da[3], db[3];
        float w[2];
        w[0] = (float)uniform();
        w[1] = 1.0f - w[0];
        random_pair(wo, wi);
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, w, a), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(t32, wo, wi, LL_TRANSPORT_RADIANCE, w, b), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, w, &pa), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t32, wo, wi, w, &pb), LL_OK);
        assert_true(pa == pb);
        for (c = 0; c < 3; ++c)
            assert_true(a[c] == b[c]);
        u[0] = uniform();
        u[1] = uniform();
        assert_int_equal(ll_bsdf_sample_dir(t, wo, u, LL_TRANSPORT_RADIANCE, w, da, &pa, a),
                         LL_OK);
        assert_int_equal(ll_bsdf_sample_dir(t32, wo, u, LL_TRANSPORT_RADIANCE, w, db, &pb, b),
                         LL_OK);
        assert_true(pa == pb);
        for (c = 0; c < 3; ++c)
            assert_true(a[c] == b[c] && da[c] == db[c]);
    }
    ll_bsdf_release(t);
    ll_bsdf_release(t32);
    unlink(path);
}

/* Between nodes: the weighted sum of the bases, and the pdf their
 * mixture by weight. */
static void test_blend(void **state)
{
    ll_bsdf *t = open_file(tab_path);
    const float w[2] = { 0.3f, 0.7f }, e0[2] = { 1.0f, 0.0f }, e1[2] = { 0.0f, 1.0f };
    size_t n;
    int c;
    (void)state;
    for (n = 0; n < 2000; ++n) {
        double wo[3], wi[3], f[3], f0[3], f1[3], p, p0, p1;
        random_pair(wo, wi);
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, w, f), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, e0, f0), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, e1, f1), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, w, &p), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, e0, &p0), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, e1, &p1), LL_OK);
        for (c = 0; c < 3; ++c)
            assert_true(fabs(f[c] - (0.3 * f0[c] + 0.7 * f1[c])) <= 1e-6 * (f[c] + 1e-12));
        assert_true(fabs(p - (0.3 * p0 + 0.7 * p1)) <= 1e-6 * (p + 1e-12));
    }
    ll_bsdf_release(t);
}

/* Sampling: the pdf and value returned are the evaluated ones, and the
 * density integrates to 1 over the hemisphere (uniform directions). */
static void test_sampling(void **state)
{
    ll_bsdf *t = open_file(tab_path);
    const float w[2] = { 0.6f, 0.4f };
    double wo[3] = { sin(0.6), 0.0, cos(0.6) }, total = 0.0;
    size_t n, hits = 0, N = 200000;
    int c;
    (void)state;
    for (n = 0; n < 4000; ++n) {
        double u[2] = { uniform(), uniform() }, wi[3], pdf, f[3], pe, fe[3];
        assert_int_equal(ll_bsdf_sample_dir(t, wo, u, LL_TRANSPORT_RADIANCE, w, wi, &pdf, f),
                         LL_OK);
        if (!(pdf > 0.0))
            continue;
        ++hits;
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, w, &pe), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, w, fe), LL_OK);
        assert_true(fabs(pdf - pe) <= 1e-9 * pe);
        for (c = 0; c < 3; ++c)
            assert_true(fabs(f[c] - fe[c]) <= 1e-9 * fe[c] + 1e-300);
    }
    assert_true(hits > 3900);
    for (n = 0; n < N; ++n) {
        double wi[3], p;
        tf_direction(acos(uniform()), 2.0 * TF_PI * uniform(), wi);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, w, &p), LL_OK);
        total += p * 2.0 * TF_PI;
    }
    total /= (double)N;
    printf("integral of the blend's pdf over the hemisphere: %.4f\n", total);
    assert_true(fabs(total - 1.0) < 0.03);
    ll_bsdf_release(t);
}

/* Batches with per-element weights: each element the scalar call. */
static void test_batches(void **state)
{
    enum { N = 64 };
    ll_bsdf *t = open_file(tab_path);
    double wo[3 * N], wi[3 * N], u[2 * N], rgb[3 * N], pdf[N], ws[3 * N], ps[N], rs[3 * N];
    float w[2 * N];
    size_t k;
    int c;
    (void)state;
    for (k = 0; k < N; ++k) {
        random_pair(wo + 3 * k, wi + 3 * k);
        u[2 * k] = uniform();
        u[2 * k + 1] = uniform();
        w[2 * k] = (float)uniform();
        w[2 * k + 1] = 1.0f - w[2 * k];
    }
    assert_int_equal(ll_bsdf_eval_dir_batch(t, N, wo, wi, LL_TRANSPORT_RADIANCE, w, 2, rgb), LL_OK);
    assert_int_equal(ll_bsdf_pdf_dir_batch(t, N, wo, wi, w, 2, pdf), LL_OK);
    for (k = 0; k < N; ++k) {
        double f[3], p;
        assert_int_equal(ll_bsdf_eval_dir(t, wo + 3 * k, wi + 3 * k, LL_TRANSPORT_RADIANCE,
                                          w + 2 * k, f),
                         LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo + 3 * k, wi + 3 * k, w + 2 * k, &p), LL_OK);
        assert_true(p == pdf[k]);
        for (c = 0; c < 3; ++c)
            assert_true(f[c] == rgb[3 * k + c]);
    }
    assert_int_equal(ll_bsdf_sample_dir_batch(t, N, wo, u, LL_TRANSPORT_RADIANCE, w, 2, ws, ps, rs),
                     LL_OK);
    for (k = 0; k < N; ++k) {
        double d[3], p, f[3];
        assert_int_equal(ll_bsdf_sample_dir(t, wo + 3 * k, u + 2 * k, LL_TRANSPORT_RADIANCE,
                                            w + 2 * k, d, &p, f),
                         LL_OK);
        assert_true(p == ps[k]);
        for (c = 0; c < 3; ++c)
            assert_true(d[c] == ws[3 * k + c] && f[c] == rs[3 * k + c]);
    }
    ll_bsdf_release(t);
}

/* Against the .bsdf at random parameter values (not only the nodes):
 * blending adds no error of its own, so between the nodes the figures
 * stay within those at the nodes (a convex combination of non-negative
 * values has a relative error at most the largest of its terms'; the
 * percentiles and the albedo move a little with the mixture, hence the
 * margin). This small grid's own figures are far from the tolerance's
 * (test_tables_tolerance.c holds the chosen grids to it). */
static void measure_at(const ll_bsdf *src, const ll_bsdf *t, double x, tf_figures *fig)
{
    double p[1] = { x };
    float w[2];
    char label[64];
    assert_int_equal(ll_bsdf_basis_coefficients(src, p, w), LL_OK);
    tf_measure_weighted(src, t, w, fig);
    assert_false(fig->failed);
    snprintf(label, sizeof label, "parameter 0 = %.3f", x);
    tf_print(label, fig);
}

static void test_against_fourier(void **state)
{
    ll_bsdf *t = open_file(tab_path), *src = open_file(bsdf_path);
    tf_figures node[2], fig;
    double albedo, p50, p95;
    int k;
    (void)state;
    measure_at(src, t, 0.1, &node[0]);
    measure_at(src, t, 0.3, &node[1]);
    albedo = fmax(node[0].worst_albedo, node[1].worst_albedo);
    p50 = fmax(node[0].p50, node[1].p50);
    p95 = fmax(node[0].p95, node[1].p95);
    for (k = 0; k < 2; ++k) {
        measure_at(src, t, 0.1 + 0.2 * uniform(), &fig);
        assert_true(fig.worst_albedo <= 1.2 * albedo);
        assert_true(fig.p50 <= 1.2 * p50);
        assert_true(fig.p95 <= 1.2 * p95);
    }
    ll_bsdf_release(t);
    ll_bsdf_release(src);
}

/* The grids chosen by the default tolerance (ll_tables_write_from_bsdf
 * with no options), measured on the tables as stored (float16): each
 * basis' search says it met the tolerance, and at each node and between
 * them the tests' own figures meet it too (albedo within 0.3%, f's median
 * 0.2%, 95th percentile 2%, 99th 5%, as tests/test_tables_tolerance.c
 * holds an untextured file to). A sweep of rough gold, whose .bsdf at
 * this small resolution the tables can follow (the coat of 0.1 above is
 * 8% off in albedo at any grid: its .bsdf does not resolve it). */
static void test_tolerance_met(void **state)
{
    ll_material *m = NULL;
    ll_bsdf *src, *t;
    char path[600], bsdf[600];
    unsigned char *bytes;
    size_t size = 0, k;
    ll_tensor_file tf;
    (void)state;
    snprintf(bsdf, sizeof bsdf, "%s/gold-sweep.bsdf", ll_test_dir());
    snprintf(path, sizeof path, "%s/tolerance.tab", ll_test_dir());
    assert_int_equal(ll_material_parse("set nodes=30 orders=30\n"
                                       "conductor name=gold eta=Au alpha=[0.2 0.3]\n",
                                       "gold-sweep.layers", &m),
                     LL_OK);
    assert_int_equal(ll_material_build(m, NULL, NULL, bsdf), LL_OK);
    ll_material_destroy(m);
    src = open_file(bsdf);
    assert_int_equal(ll_tables_write_from_bsdf(src, path, NULL, NULL), LL_OK);
    bytes = ll_test_read_file(path, &size);
    assert_non_null(bytes);
    assert_int_equal(ll_tensor_parse(bytes, size, path, &tf), LL_OK);
    for (k = 0; k < 2; ++k) {
        char name[64], *text;
        const ll_tensor_field *f;
        snprintf(name, sizeof name, "basis%zu.vndf", k);
        assert_non_null(f = ll_tensor_find(&tf, name));
        assert_int_equal(f->dtype, LL_TENSOR_F16);
        snprintf(name, sizeof name, "basis%zu.layerlab_metadata", k);
        assert_non_null(f = ll_tensor_find(&tf, name));
        text = calloc(f->count + 1, 1);
        assert_non_null(text);
        memcpy(text, f->data, f->count);
        print_message("basis %zu: %s\n", k, strstr(text, "\"figures\""));
        assert_non_null(strstr(text, "\"met\": true"));
        free(text);
    }
    ll_tensor_file_free(&tf);
    free(bytes);
    t = open_file(path);
    for (k = 0; k < 3; ++k) {
        tf_figures fig;
        measure_at(src, t, k == 2 ? 0.2 + 0.1 * uniform() : 0.2 + 0.1 * (double)k, &fig);
        assert_true(fig.worst_albedo <= 0.003);
        assert_true(fig.p50 <= 0.002);
        assert_true(fig.p95 <= 0.02);
        assert_true(fig.p99 <= 0.05);
    }
    ll_bsdf_release(t);
    ll_bsdf_release(src);
    unlink(path);
    unlink(bsdf);
}

/* At a node, the luminance albedo at the elevations of the slices towards
 * grazing (where the sample grid's cells cross the horizon) is the
 * basis' own: the writer fits the nodes beyond the horizon to it
 * (bsdf_write_tables_horizon.c). The table's albedo is its own sampler's
 * stratified estimate, the .bsdf's ll_bsdf_albedo. At 81.9 and 86.4
 * degrees on this small grid: within 0.33% (nodes beyond the horizon
 * stored as 0 gave 3.8-10.8%). The last slice below 90 degrees (89.1)
 * is not checked: there the fit's lambda reaches its bound. */
static void test_grazing_slices(void **state)
{
    enum { STRATA = 128, SLICES = 12 };
    ll_bsdf *t = open_file(tab_path), *src = open_file(bsdf_path);
    double worst = 0.0;
    size_t k;
    int s, i, j;
    (void)state;
    for (k = 0; k < 2; ++k) {
        float w[2] = { 0.0f, 0.0f };
        w[k] = 1.0f;
        for (s = 8; s < SLICES - 2; ++s) {
            /* The writer's elevations: 90 sin(90 v) degrees, v uniform. */
            double th = sin((double)s / (SLICES - 1) * TF_PI / 2) * TF_PI / 2;
            double wo[3], ref[3], got = 0.0, want;
            tf_direction(th, 0.0, wo);
            assert_int_equal(ll_bsdf_albedo(src, cos(th), w, ref, NULL), LL_OK);
            want = 0.212671 * ref[0] + 0.715160 * ref[1] + 0.072169 * ref[2];
            for (i = 0; i < STRATA; ++i)
                for (j = 0; j < STRATA; ++j) {
                    double u[2] = { (i + 0.5) / STRATA, (j + 0.5) / STRATA }, wi[3], pdf, f[3];
                    assert_int_equal(ll_bsdf_sample_dir(t, wo, u, LL_TRANSPORT_RADIANCE, w, wi,
                                                        &pdf, f),
                                     LL_OK);
                    if (pdf > 0.0)
                        got += (0.212671 * f[0] + 0.715160 * f[1] + 0.072169 * f[2]) *
                               fabs(wi[2]) / pdf;
                }
            got /= (double)STRATA * STRATA;
            print_message("basis %zu, viewer %.1f deg: albedo %.4f, .bsdf %.4f\n", k,
                          th * 180.0 / TF_PI, got, want);
            worst = fmax(worst, fabs(got / want - 1.0));
        }
    }
    print_message("worst %.3f%%\n", 100.0 * worst);
    assert_true(worst <= 0.005);
    ll_bsdf_release(t);
    ll_bsdf_release(src);
}

/* A textured table file is made from its .bsdf, not converted again. */
static void test_refusals(void **state)
{
    ll_bsdf *t = open_file(tab_path);
    char out[600];
    (void)state;
    snprintf(out, sizeof out, "%s/again.tab", ll_test_dir());
    assert_int_equal(ll_tables_write_from_bsdf(t, out, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "textured table file"));
    assert_int_equal(access(out, F_OK), -1);
    ll_bsdf_release(t);
}

/* A spectral textured file: the source gives a textured file of the same
 * parameters at each wavelength (here the RGB file itself, whose
 * luminance is taken); one without the basis is refused. */
static ll_status same_file(void *user, size_t index, double nm, ll_bsdf **out)
{
    (void)index;
    (void)nm;
    return ll_bsdf_open((const char *)user, NULL, out);
}

static void test_spectral(void **state)
{
    ll_bsdf *src = open_file(bsdf_path), *t;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    double nm[3] = { 450.0, 550.0, 650.0 };
    char out[600];
    (void)state;
    snprintf(out, sizeof out, "%s/spectral.tab", ll_test_dir());
    o.n_theta_i = 6;
    o.vndf_size = 16;
    o.sample_size = 12;
    o.format = LL_TABLES_SPECTRAL;
    o.wavelengths = nm;
    o.n_wavelengths = 3;
    o.spectrum = same_file;
    o.spectrum_user = bsdf_path;
    assert_int_equal(ll_tables_write_from_bsdf(src, out, &o, NULL), LL_OK);
    {
        /* The spectra stored as float16, the wavelengths as float32. */
        size_t size = 0;
        unsigned char *bytes = ll_test_read_file(out, &size);
        ll_tensor_file tf;
        assert_non_null(bytes);
        assert_int_equal(ll_tensor_parse(bytes, size, out, &tf), LL_OK);
        assert_int_equal(ll_tensor_find(&tf, "basis1.spectra")->dtype, LL_TENSOR_F16);
        assert_int_equal(ll_tensor_find(&tf, "basis1.luminance")->dtype, LL_TENSOR_F16);
        assert_int_equal(ll_tensor_find(&tf, "basis1.wavelengths")->dtype, LL_TENSOR_F32);
        ll_tensor_file_free(&tf);
        free(bytes);
    }
    t = open_file(out);
    assert_int_equal(ll_bsdf_get_info(t, &info), LL_OK);
    assert_int_equal(info.n_bases, 2);
    assert_int_equal(info.n_wavelengths, 3);
    ll_bsdf_release(t);
    unlink(out);
    o.spectrum_user = golden_path;
    assert_int_equal(ll_tables_write_from_bsdf(src, out, &o, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "no basis"));
    assert_int_equal(access(out, F_OK), -1);
    ll_bsdf_release(src);
}

/* ll_material_write_tables of a sweep: its textured .bsdf's tables (RGB);
 * spectral is refused saying so. */
static void test_material_sweep(void **state)
{
    ll_material *m = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    double nm[2] = { 500.0, 600.0 };
    char out[600];
    ll_bsdf *t;
    (void)state;
    snprintf(out, sizeof out, "%s/sweep.tab", ll_test_dir());
    assert_int_equal(ll_material_parse("set nodes=20 orders=20\n"
                                       "conductor name=gold eta=Au alpha=[0.2 0.3]\n",
                                       "sweep.layers", &m),
                     LL_OK);
    o.n_theta_i = 6;
    o.vndf_size = 16;
    o.sample_size = 12;
    assert_int_equal(ll_material_write_tables(m, NULL, NULL, out, &o, NULL), LL_OK);
    t = open_file(out);
    assert_int_equal(ll_bsdf_get_info(t, &info), LL_OK);
    assert_int_equal(info.n_bases, 2);
    ll_bsdf_release(t);
    unlink(out);
    o.format = LL_TABLES_SPECTRAL;
    o.wavelengths = nm;
    o.n_wavelengths = 2;
    assert_int_equal(ll_material_write_tables(m, NULL, NULL, out, &o, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "spectral textured"));
    assert_int_equal(access(out, F_OK), -1);
    ll_material_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parameters),
        cmocka_unit_test(test_node_is_basis_table),
        cmocka_unit_test(test_float16_fields),
        cmocka_unit_test(test_blend),
        cmocka_unit_test(test_sampling),
        cmocka_unit_test(test_batches),
        cmocka_unit_test(test_against_fourier),
        cmocka_unit_test(test_tolerance_met),
        cmocka_unit_test(test_grazing_slices),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_spectral),
        cmocka_unit_test(test_material_sweep),
    };
    return cmocka_run_group_tests(tests, setup, ll_test_dir_teardown);
}
