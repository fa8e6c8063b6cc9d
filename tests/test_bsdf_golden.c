/*
 * The golden file roughgold_alpha_0.2.bsdf (written by the original tools,
 * shipped with pbrt-v3's tests): its header facts, and pbrt-v3's
 * FourierBSDF numbers (tests/data/README.md) reproduced through the
 * renderer-convention calls, plus the layer convention's mapping.
 */
#include "test_bsdf_util.h"
#include "reader/bsdf_internal.h"
#include "numerics/spline.h"

static ll_bsdf *open_golden(void)
{
    ll_bsdf *b = NULL;
    ll_status s = ll_bsdf_open(LL_TEST_GOLDEN, NULL, &b);
    if (s != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return b;
}

static void normalize(double v[3])
{
    double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    v[0] /= len;
    v[1] /= len;
    v[2] /= len;
}

/* pbrt-v3's BSDFs.Fourier test directions. */
static void pbrt_directions(double wo[3], double wi[3])
{
    wo[0] = -0.5; wo[1] = -0.5; wo[2] = 0.8;
    wi[0] = 0.4; wi[1] = 0.52; wi[2] = 0.7;
    normalize(wo);
    normalize(wi);
}

static void assert_rel(double value, double expected, double rel)
{
    if (!(fabs(value - expected) <= rel * fabs(expected)))
        fail_msg("%.9g differs from %.9g by more than %g relative", value, expected, rel);
}

static void header_facts(void **state)
{
    ll_bsdf *b = open_golden();
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    const float *nodes;
    size_t k;
    (void)state;
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_int_equal(info.n_nodes, 58);
    assert_int_equal(info.n_coeffs, 41502);
    assert_int_equal(info.max_order, 172);
    assert_int_equal(info.n_channels, 3);
    assert_int_equal(info.n_bases, 1);
    assert_int_equal(info.n_parameters, 0);
    assert_int_equal(info.metadata_size, 682);
    assert_int_equal(info.file_size, 207354);
    assert_int_equal(info.flags, 1);
    assert_true(info.eta == 1.0);
    assert_true(info.alpha[0] == 0.0 && info.alpha[1] == 0.0);
    assert_int_equal(strlen(info.metadata), 682);
    assert_non_null(strstr(info.metadata, "\"conductor_ior_preset\": \"Au\""));
    assert_non_null(strstr(info.metadata, "0.14355224039215753"));
    assert_non_null(strstr(info.metadata, "1.6043381450132959"));
    assert_non_null(strstr(info.metadata, "\"roughness\": 0.2"));

    nodes = ll_bsdf_nodes(b);
    assert_non_null(nodes);
    assert_true(nodes[0] == -1.0f && nodes[57] == 1.0f);
    assert_true(nodes[28] == 0.0f && nodes[29] == 0.0f);
    for (k = 1; k < 58; ++k)
        assert_true(nodes[k] >= nodes[k - 1]);
    for (k = 0; k < 58; ++k)
        assert_true(nodes[k] == -nodes[57 - k]);
    ll_bsdf_release(b);
}

static void pbrt_values(void **state)
{
    ll_bsdf *b = open_golden();
    double wo[3], wi[3], rgb[3], w[3], pdf, u[2] = { 0.1, 0.8 };
    (void)state;
    pbrt_directions(wo, wi);

    assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_IMPORTANCE, NULL, rgb), LL_OK);
    assert_rel(ll_test_luminance(rgb), 2.679294, 1e-4);
    assert_rel(ll_test_pdf_dir(b, wo, wi, NULL), 2.438230, 1e-4);
    assert_rel(ll_test_pdf_dir(b, wi, wo, NULL), 2.503326, 1e-4);

    assert_int_equal(ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_IMPORTANCE, NULL, w, &pdf, rgb),
                     LL_OK);
    assert_rel(ll_test_luminance(rgb), 2.596391, 1e-4);
    assert_rel(pdf, 1.855472, 1e-4);
    assert_rel(w[0], 0.539052, 1e-4);
    assert_rel(w[1], 0.617347, 1e-4);
    assert_rel(w[2], 0.572980, 1e-4);
    assert_rel(w[0] * w[0] + w[1] * w[1] + w[2] * w[2], 1.0, 1e-14);
    /* The sample's own pdf and value agree with the direct calls. */
    assert_rel(ll_test_pdf_dir(b, wo, w, NULL), pdf, 1e-5);
    {
        double f[3];
        assert_int_equal(ll_bsdf_eval_dir(b, wo, w, LL_TRANSPORT_IMPORTANCE, NULL, f), LL_OK);
        assert_rel(ll_test_luminance(f), ll_test_luminance(rgb), 1e-5);
    }
    /* eta = 1 and reflection: the two transport modes agree. */
    {
        double r[3];
        assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, NULL, r), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_IMPORTANCE, NULL, rgb), LL_OK);
        assert_memory_equal(r, rgb, sizeof r);
    }
    ll_bsdf_release(b);
}

/* The layer convention is the renderer's with mu_i = wo.z, mu_o = -wi.z and
 * cos(phi_d) = cos of the azimuth between -wi and wo. */
static void layer_convention_mapping(void **state)
{
    ll_bsdf *b = open_golden();
    uint64_t rng = 12345;
    int n;
    (void)state;
    for (n = 0; n < 2000; ++n) {
        double to = acos(ll_test_uniform(&rng)), ti = acos(2.0 * ll_test_uniform(&rng) - 1.0);
        double po = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        double pi_ = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        double wo[3] = { sin(to) * cos(po), sin(to) * sin(po), cos(to) };
        double wi[3] = { sin(ti) * cos(pi_), sin(ti) * sin(pi_), cos(ti) };
        /* -wi has azimuth pi_ + pi: the difference to wo's is phi_d. */
        double phi_d = pi_ + LL_TEST_PI - po, a[3], c[3];
        assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_IMPORTANCE, NULL, a), LL_OK);
        assert_int_equal(ll_bsdf_eval(b, wo[2], -wi[2], phi_d, NULL, c), LL_OK);
        assert_true(ll_test_close(a[0], c[0], 1e-9, 1e-12));
        assert_true(ll_test_close(a[1], c[1], 1e-9, 1e-12));
        assert_true(ll_test_close(a[2], c[2], 1e-9, 1e-12));
        assert_true(ll_test_close(ll_test_pdf_dir(b, wo, wi, NULL),
                                  ll_test_pdf(b, wo[2], -wi[2], phi_d, NULL), 1e-9, 1e-12));
    }
    /* Sampling: the same u gives mu_o = -wi.z and the same pdf and f. */
    for (n = 0; n < 500; ++n) {
        double to = acos(ll_test_uniform(&rng)), po = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        double wo[3] = { sin(to) * cos(po), sin(to) * sin(po), cos(to) };
        double u[2], wi[3], pdf_dir, f[3], mu_o, phi_d, pdf, f_layer[3];
        u[0] = ll_test_uniform(&rng);
        u[1] = ll_test_uniform(&rng);
        assert_int_equal(
            ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_IMPORTANCE, NULL, wi, &pdf_dir, f), LL_OK);
        assert_int_equal(ll_bsdf_sample(b, wo[2], u, NULL, &mu_o, &phi_d, &pdf, f_layer), LL_OK);
        assert_true(ll_test_close(pdf, pdf_dir, 1e-12, 0.0));
        if (pdf > 0.0) {
            assert_true(ll_test_close(mu_o, -wi[2], 1e-9, 1e-12));
            assert_true(ll_test_close(f_layer[0], f[0], 1e-9, 1e-12));
            assert_true(ll_test_close(f_layer[1], f[1], 1e-9, 1e-12));
            assert_true(ll_test_close(f_layer[2], f[2], 1e-9, 1e-12));
            assert_true(phi_d >= 0.0 && phi_d <= 2.0 * LL_TEST_PI);
        }
    }
    ll_bsdf_release(b);
}

/* Unnormalised directions give what their normalised versions give. */
static void unnormalised_directions(void **state)
{
    ll_bsdf *b = open_golden();
    double wo[3], wi[3], wo2[3], wi2[3], a[3], c[3];
    int k;
    (void)state;
    pbrt_directions(wo, wi);
    for (k = 0; k < 3; ++k) {
        wo2[k] = 3.5 * wo[k];
        wi2[k] = 0.25 * wi[k];
    }
    assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, NULL, a), LL_OK);
    assert_int_equal(ll_bsdf_eval_dir(b, wo2, wi2, LL_TRANSPORT_RADIANCE, NULL, c), LL_OK);
    for (k = 0; k < 3; ++k)
        assert_true(ll_test_close(a[k], c[k], 1e-12, 0.0));
    assert_true(ll_test_close(ll_test_pdf_dir(b, wo, wi, NULL), ll_test_pdf_dir(b, wo2, wi2, NULL),
                              1e-12, 0.0));
    ll_bsdf_release(b);
}

/* Degenerate inputs: the normal, grazing directions, u at its ends. */
static void degenerate_inputs(void **state)
{
    ll_bsdf *b = open_golden();
    static const double dirs[][3] = { { 0, 0, 1 },      { 0, 0, -1 },   { 1, 0, 0 },
                                      { 0.6, 0.8, 0 },  { 1e-12, 0, 1 }, { 0.3, -0.2, -0.9 },
                                      { 0, 1e-300, 1 } };
    static const double us[][2] = { { 0, 0 }, { 1, 1 }, { 0.5, 0.5 }, { 0, 1 }, { 1, 0 },
                                    { 0.999999999, 1e-12 } };
    size_t d, k;
    (void)state;
    for (d = 0; d < sizeof dirs / sizeof dirs[0]; ++d)
        for (k = 0; k < sizeof us / sizeof us[0]; ++k) {
            double wi[3], pdf, f[3], rgb[3];
            assert_int_equal(ll_bsdf_sample_dir(b, dirs[d], us[k], LL_TRANSPORT_RADIANCE, NULL,
                                                wi, &pdf, f),
                             LL_OK);
            assert_true(isfinite(pdf) && pdf >= 0.0);
            assert_true(isfinite(f[0]) && f[0] >= 0.0 && isfinite(f[1]) && f[1] >= 0.0 &&
                        isfinite(f[2]) && f[2] >= 0.0);
            assert_true(fabs(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2] - 1.0) < 1e-12);
            assert_int_equal(ll_bsdf_eval_dir(b, dirs[d], wi, LL_TRANSPORT_RADIANCE, NULL, rgb),
                             LL_OK);
            assert_true(isfinite(rgb[0]) && isfinite(rgb[1]) && isfinite(rgb[2]));
            assert_true(isfinite(ll_test_pdf_dir(b, dirs[d], wi, NULL)));
        }
    /* Normal incidence: the sample is a proper direction above the surface. */
    {
        double up[3] = { 0, 0, 1 }, u[2] = { 0.3, 0.4 }, wi[3], pdf, f[3];
        assert_int_equal(ll_bsdf_sample_dir(b, up, u, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f),
                         LL_OK);
        assert_true(pdf > 0.0 && wi[2] > 0.0 && wi[2] < 1.0);
    }
    ll_bsdf_release(b);
}

static void bad_arguments(void **state)
{
    ll_bsdf *b = open_golden();
    double wo[3] = { 0, 0, 1 }, zero[3] = { 0, 0, 0 }, nan3[3] = { NAN, 0, 1 }, rgb[3], wi[3];
    double pdf, u[2] = { 0.5, 0.5 }, bad_u[2] = { 1.5, 0.5 }, mu_o, phi;
    float basis[1] = { 1.0f };
    (void)state;
    assert_int_equal(ll_bsdf_eval_dir(NULL, wo, wo, LL_TRANSPORT_RADIANCE, NULL, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_eval_dir(b, zero, wo, LL_TRANSPORT_RADIANCE, NULL, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_eval_dir(b, nan3, wo, LL_TRANSPORT_RADIANCE, NULL, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_eval_dir(b, wo, wo, (ll_transport)7, NULL, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_eval(b, NAN, 0.5, 0.0, NULL, rgb), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_sample_dir(b, wo, bad_u, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_sample(b, 0.5, bad_u, NULL, &mu_o, &phi, &pdf, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_sample(b, 0.5, u, NULL, NULL, &phi, &pdf, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    pdf = 1.0;
    assert_int_equal(ll_bsdf_pdf_dir(b, zero, wo, NULL, &pdf), LL_ERROR_INVALID_ARGUMENT);
    assert_true(pdf == 0.0);
    assert_int_equal(ll_bsdf_pdf_dir(NULL, wo, wo, NULL, &pdf), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_pdf_dir(b, wo, wo, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    pdf = 1.0;
    assert_int_equal(ll_bsdf_pdf(b, NAN, 0.5, 0.0, NULL, &pdf), LL_ERROR_INVALID_ARGUMENT);
    assert_true(pdf == 0.0);
    assert_int_equal(ll_bsdf_pdf(b, 0.5, 0.5, 0.0, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    /* An untextured file takes one basis weight, and scales by it. */
    {
        double a[3], c[3], wi2[3] = { 0.1, 0.2, 0.9 };
        basis[0] = 0.5f;
        assert_int_equal(ll_bsdf_eval_dir(b, wo, wi2, LL_TRANSPORT_RADIANCE, NULL, a), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(b, wo, wi2, LL_TRANSPORT_RADIANCE, basis, c), LL_OK);
        assert_true(ll_test_close(c[1], 0.5 * a[1], 1e-12, 0.0));
    }
    assert_int_equal(ll_bsdf_get_info(b, NULL), LL_ERROR_INVALID_ARGUMENT);
    {
        size_t count;
        const float *positions;
        assert_int_equal(ll_bsdf_get_parameter(b, 0, &count, &positions),
                         LL_ERROR_INVALID_ARGUMENT);
    }
    assert_null(ll_bsdf_nodes(NULL));
    ll_bsdf_release(NULL);
    ll_bsdf_release(b);
}

/* From memory == from the file; reference counting; small info structs. */
static void memory_refcount_info(void **state)
{
    size_t size;
    unsigned char *data = ll_test_read_file(LL_TEST_GOLDEN, &size);
    ll_bsdf *a = open_golden(), *m = NULL;
    double wo[3], wi[3], ra[3], rm[3];
    (void)state;
    assert_int_equal(ll_bsdf_open_memory(data, size, NULL, &m), LL_OK);
    memset(data, 0xAB, size); /* the bytes were copied */
    free(data);
    pbrt_directions(wo, wi);
    assert_int_equal(ll_bsdf_eval_dir(a, wo, wi, LL_TRANSPORT_RADIANCE, NULL, ra), LL_OK);
    assert_int_equal(ll_bsdf_eval_dir(m, wo, wi, LL_TRANSPORT_RADIANCE, NULL, rm), LL_OK);
    assert_memory_equal(ra, rm, sizeof ra);

    assert_ptr_equal(ll_bsdf_retain(m), m);
    ll_bsdf_release(m);
    assert_int_equal(ll_bsdf_eval_dir(m, wo, wi, LL_TRANSPORT_RADIANCE, NULL, rm), LL_OK);
    ll_bsdf_release(m);
    assert_null(ll_bsdf_retain(NULL));

    {
        /* An older, smaller struct: only its fields are written. */
        struct { size_t struct_size, n_nodes, max_order; size_t guard; } small;
        small.struct_size = 3 * sizeof(size_t);
        small.guard = 777;
        assert_int_equal(ll_bsdf_get_info(a, (ll_bsdf_info *)(void *)&small), LL_OK);
        assert_int_equal(small.n_nodes, 58);
        assert_int_equal(small.max_order, 172);
        assert_int_equal(small.guard, 777);
        small.struct_size = 1;
        assert_int_equal(ll_bsdf_get_info(a, (ll_bsdf_info *)(void *)&small),
                         LL_ERROR_INVALID_ARGUMENT);
    }
    ll_bsdf_release(a);
}

/* The prepared spline weights (bsdf_spline.c) are ll_spline_weights'. */
static void check_weights(const ll_bsdf *b, double mu)
{
    ptrdiff_t o1 = 0, o2 = 0;
    double w1[4], w2[4];
    int r1 = ll_bsdf_weights(b, mu, &o1, w1), r2 = ll_spline_weights(b->nodes, b->n_nodes, mu,
                                                                     &o2, w2, 0);
    int k;
    assert_int_equal(r1, r2);
    if (!r1)
        return;
    if (o1 != o2)
        fail_msg("mu %.17g: offset %td, ll_spline_weights %td", mu, o1, o2);
    for (k = 0; k < 4; ++k)
        if (!(fabs(w1[k] - w2[k]) <= 1e-13))
            fail_msg("mu %.17g: weight %d = %.17g, ll_spline_weights %.17g", mu, k, w1[k], w2[k]);
}

static void prepared_spline_weights(void **state)
{
    ll_bsdf *b = open_golden(), *small = NULL;
    uint64_t rng = 99;
    size_t k;
    unsigned char *data;
    size_t size;
    (void)state;
    for (k = 0; k < b->n_nodes; ++k) {
        check_weights(b, b->nodes[k]);
        check_weights(b, nextafter(b->nodes[k], 2.0));
        check_weights(b, nextafter(b->nodes[k], -2.0));
    }
    for (k = 0; k < 200000; ++k)
        check_weights(b, 2.2 * ll_test_uniform(&rng) - 1.1);
    check_weights(b, NAN);
    check_weights(b, -0.0);
    /* A file with four nodes, two of them at 0. */
    data = ll_test_read_file(LL_SOURCE_DIR "/tests/fuzz/corpus/seed-diffuse_n2", &size);
    assert_int_equal(ll_bsdf_open_memory(data, size, NULL, &small), LL_OK);
    for (k = 0; k < 20000; ++k)
        check_weights(small, 2.2 * ll_test_uniform(&rng) - 1.1);
    for (k = 0; k < small->n_nodes; ++k)
        check_weights(small, small->nodes[k]);
    free(data);
    ll_bsdf_release(small);
    ll_bsdf_release(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(header_facts),
        cmocka_unit_test(pbrt_values),
        cmocka_unit_test(layer_convention_mapping),
        cmocka_unit_test(unnormalised_directions),
        cmocka_unit_test(degenerate_inputs),
        cmocka_unit_test(bad_arguments),
        cmocka_unit_test(memory_refcount_info),
        cmocka_unit_test(prepared_spline_weights),
    };
    return cmocka_run_group_tests_name("bsdf_golden", tests, NULL, NULL);
}
