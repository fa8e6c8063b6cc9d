/*
 * The batch calls (ll_bsdf_*_dir_batch) give, element for element and bit
 * for bit, what the scalar _dir calls give: for random directions over the
 * whole sphere (reflection and transmission, some invalid elements), for
 * the golden untextured file and a textured file with per-element or shared
 * weights, and a table file (whose batches run as a pipeline over the
 * elements, tables_batch.c), with one thread and with several
 * (LAYERLAB_BATCH_THREADS), and the status of the first invalid element;
 * on the table also every count from 0 to past twice the pipeline's depth
 * and invalid or zero elements at every place in it.
 */
#include "test_bsdf_util.h"

#include <string.h>

enum { N_ELEMENTS = 5000, N_BASES = 4 };

typedef struct batch_data {
    double wo[3 * N_ELEMENTS], wi[3 * N_ELEMENTS], u[2 * N_ELEMENTS];
    float weights[N_BASES * N_ELEMENTS];
} batch_data;

static void random_direction(uint64_t *rng, double w[3])
{
    double z = 2.0 * ll_test_uniform(rng) - 1.0, r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * LL_TEST_PI * ll_test_uniform(rng);
    /* Some not normalised, as the calls allow. */
    double len = ll_test_uniform(rng) < 0.2 ? 0.5 + 2.0 * ll_test_uniform(rng) : 1.0;
    w[0] = len * r * cos(phi);
    w[1] = len * r * sin(phi);
    w[2] = len * z;
}

static batch_data *make_data(uint64_t seed)
{
    batch_data *d = malloc(sizeof *d);
    uint64_t rng = seed;
    size_t k;
    assert_non_null(d);
    for (k = 0; k < N_ELEMENTS; ++k) {
        random_direction(&rng, d->wo + 3 * k);
        random_direction(&rng, d->wi + 3 * k);
        d->u[2 * k] = ll_test_uniform(&rng);
        d->u[2 * k + 1] = ll_test_uniform(&rng);
    }
    for (k = 0; k < N_BASES * N_ELEMENTS; ++k)
        d->weights[k] = (float)ll_test_uniform(&rng);
    return d;
}

static void set_threads(const char *n)
{
    assert_int_equal(setenv("LAYERLAB_BATCH_THREADS", n, 1), 0);
}

/* Bitwise equality, so that -0.0 vs 0.0 or a different rounding fails. */
static void assert_same_bits(const double *a, const double *b, size_t n, const char *what,
                             size_t element)
{
    if (memcmp(a, b, n * sizeof *a) != 0)
        fail_msg("%s of element %zu: batch %.17g differs from scalar %.17g", what, element,
                 a[0], b[0]);
}

/* Compare every batch call against the scalar calls for one file and one
 * weight layout; stride 0 shares the first set of weights. */
static void check_against_scalar(const ll_bsdf *b, const batch_data *d, const float *weights,
                                 size_t stride, ll_transport mode)
{
    double *rgb = malloc(3 * N_ELEMENTS * sizeof *rgb), *pdf = malloc(N_ELEMENTS * sizeof *pdf);
    double *wi = malloc(3 * N_ELEMENTS * sizeof *wi), *srgb = malloc(3 * N_ELEMENTS * sizeof *srgb);
    double *spdf = malloc(N_ELEMENTS * sizeof *spdf);
    size_t k;
    assert_non_null(rgb && pdf && wi && srgb && spdf);
    assert_int_equal(ll_bsdf_eval_dir_batch(b, N_ELEMENTS, d->wo, d->wi, mode, weights, stride,
                                            rgb),
                     LL_OK);
    assert_int_equal(ll_bsdf_pdf_dir_batch(b, N_ELEMENTS, d->wo, d->wi, weights, stride, pdf),
                     LL_OK);
    assert_int_equal(ll_bsdf_sample_dir_batch(b, N_ELEMENTS, d->wo, d->u, mode, weights, stride,
                                              wi, spdf, srgb),
                     LL_OK);
    for (k = 0; k < N_ELEMENTS; ++k) {
        const float *w = weights ? weights + k * stride : NULL;
        double e[3], p, swi[3], sp, sf[3];
        assert_int_equal(ll_bsdf_eval_dir(b, d->wo + 3 * k, d->wi + 3 * k, mode, w, e), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(b, d->wo + 3 * k, d->wi + 3 * k, w, &p), LL_OK);
        assert_int_equal(ll_bsdf_sample_dir(b, d->wo + 3 * k, d->u + 2 * k, mode, w, swi, &sp,
                                            sf),
                         LL_OK);
        assert_same_bits(rgb + 3 * k, e, 3, "eval", k);
        assert_same_bits(pdf + k, &p, 1, "pdf", k);
        assert_same_bits(wi + 3 * k, swi, 3, "sampled wi", k);
        assert_same_bits(spdf + k, &sp, 1, "sampled pdf", k);
        assert_same_bits(srgb + 3 * k, sf, 3, "sampled f", k);
    }
    free(rgb);
    free(pdf);
    free(wi);
    free(srgb);
    free(spdf);
}

static ll_bsdf *open_golden(void)
{
    ll_bsdf *b = NULL;
    if (ll_bsdf_open(LL_TEST_GOLDEN, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return b;
}

/* A textured file of N_BASES bases (one parameter at N_BASES positions),
 * transmissive (eta 1.5), one channel. */
static ll_bsdf *open_textured(void)
{
    const size_t counts[1] = { N_BASES };
    const double positions[N_BASES] = { 0.0, 0.3, 0.6, 1.0 };
    ll_layer *l[N_BASES];
    const ll_layer *layers[N_BASES];
    ll_test_smooth p[N_BASES];
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_bsdf *b = NULL;
    char path[600];
    size_t k;
    for (k = 0; k < N_BASES; ++k) {
        p[k].scale[0] = 0.2 + 0.1 * (double)k;
        p[k].scale[1] = 0.1 + 0.05 * (double)k;
        p[k].scale[2] = 0.5 - 0.05 * (double)k;
        p[k].scale[3] = 0.15;
        p[k].decay = 0.1 + 0.1 * (double)k;
        l[k] = ll_test_layer(14, 4);
        ll_test_fill(l[k], ll_test_smooth_fn, &p[k]);
        layers[k] = l[k];
    }
    opts.eta = 1.5;
    snprintf(path, sizeof path, "%s/textured.bsdf", ll_test_dir());
    if (ll_bsdf_write_textured(path, layers, 1, 1, counts, positions, &opts, NULL) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    for (k = 0; k < N_BASES; ++k)
        ll_layer_destroy(l[k]);
    if (ll_bsdf_open(path, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return b;
}

static void untextured_equals_scalar(void **state)
{
    ll_bsdf *b = open_golden();
    batch_data *d = make_data(17);
    float one = 0.75f;
    (void)state;
    set_threads("1");
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_RADIANCE);
    set_threads("3");
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_IMPORTANCE);
    /* An untextured file takes one weight: shared, or one per element. */
    check_against_scalar(b, d, &one, 0, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, d->weights, 1, LL_TRANSPORT_RADIANCE);
    unsetenv("LAYERLAB_BATCH_THREADS");
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_RADIANCE);
    free(d);
    ll_bsdf_release(b);
}

static void textured_equals_scalar(void **state)
{
    ll_bsdf *b = open_textured();
    batch_data *d = make_data(23);
    (void)state;
    set_threads("1");
    check_against_scalar(b, d, d->weights, N_BASES, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, d->weights, 0, LL_TRANSPORT_IMPORTANCE);
    set_threads("4");
    check_against_scalar(b, d, d->weights, N_BASES, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, d->weights, N_BASES, LL_TRANSPORT_IMPORTANCE);
    check_against_scalar(b, d, d->weights, 0, LL_TRANSPORT_RADIANCE);
    unsetenv("LAYERLAB_BATCH_THREADS");
    free(d);
    ll_bsdf_release(b);
}

/* Invalid elements: zeros as the scalar call, the rest computed, and the
 * status and message of the lowest invalid index -- also when that element
 * is handled by a worker thread. */
static void invalid_elements(void **state)
{
    ll_bsdf *b = open_golden();
    batch_data *d = make_data(5);
    double *rgb = malloc(3 * N_ELEMENTS * sizeof *rgb), *pdf = malloc(N_ELEMENTS * sizeof *pdf);
    double *wi = malloc(3 * N_ELEMENTS * sizeof *wi), e[3];
    const char *threads[2] = { "1", "4" };
    size_t t, bad1 = 4321, bad2 = 4400;
    (void)state;
    assert_non_null(rgb && pdf && wi);
    d->wo[3 * bad1] = d->wo[3 * bad1 + 1] = d->wo[3 * bad1 + 2] = 0.0; /* zero wo */
    d->u[2 * bad2] = 1.5;                                             /* u out of range */
    d->wi[3 * bad2 + 2] = NAN;
    for (t = 0; t < 2; ++t) {
        set_threads(threads[t]);
        memset(rgb, 0xff, 3 * N_ELEMENTS * sizeof *rgb);
        assert_int_equal(ll_bsdf_eval_dir_batch(b, N_ELEMENTS, d->wo, d->wi,
                                                LL_TRANSPORT_RADIANCE, NULL, 0, rgb),
                         LL_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(ll_last_error_message(), "ll_bsdf_eval_dir"));
        assert_true(rgb[3 * bad1] == 0.0 && rgb[3 * bad2 + 2] == 0.0);
        assert_int_equal(ll_bsdf_eval_dir(b, d->wo + 3 * (N_ELEMENTS - 1),
                                          d->wi + 3 * (N_ELEMENTS - 1), LL_TRANSPORT_RADIANCE,
                                          NULL, e),
                         LL_OK);
        assert_same_bits(rgb + 3 * (N_ELEMENTS - 1), e, 3, "eval after the invalid ones",
                         N_ELEMENTS - 1);
        memset(pdf, 0xff, N_ELEMENTS * sizeof *pdf);
        assert_int_equal(ll_bsdf_pdf_dir_batch(b, N_ELEMENTS, d->wo, d->wi, NULL, 0, pdf),
                         LL_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(ll_last_error_message(), "ll_bsdf_pdf_dir"));
        assert_true(pdf[bad1] == 0.0 && pdf[bad2] == 0.0);
        {
            double p;
            assert_int_equal(ll_bsdf_pdf_dir(b, d->wo + 3 * (N_ELEMENTS - 1),
                                             d->wi + 3 * (N_ELEMENTS - 1), NULL, &p),
                             LL_OK);
            assert_same_bits(pdf + N_ELEMENTS - 1, &p, 1, "pdf after the invalid ones",
                             N_ELEMENTS - 1);
        }
        assert_int_equal(ll_bsdf_sample_dir_batch(b, N_ELEMENTS, d->wo, d->u,
                                                  LL_TRANSPORT_RADIANCE, NULL, 0, wi, pdf, rgb),
                         LL_ERROR_INVALID_ARGUMENT);
        /* The message of element bad1 (zero wo), the lower of the two. */
        assert_non_null(strstr(ll_last_error_message(), "wo must be"));
        assert_null(strstr(ll_last_error_message(), "(1.5"));
        assert_true(pdf[bad1] == 0.0 && wi[3 * bad1 + 2] == 1.0 && pdf[bad2] == 0.0);
    }
    unsetenv("LAYERLAB_BATCH_THREADS");
    /* Batch-level errors write nothing; count 0 is fine. */
    assert_int_equal(ll_bsdf_eval_dir_batch(NULL, 1, d->wo, d->wi, LL_TRANSPORT_RADIANCE, NULL,
                                            0, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_pdf_dir_batch(b, 1, d->wo, NULL, NULL, 0, pdf),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_sample_dir_batch(b, 0, NULL, NULL, LL_TRANSPORT_RADIANCE, NULL, 0,
                                              NULL, NULL, NULL),
                     LL_OK);
    assert_int_equal(ll_bsdf_eval_dir_batch(b, (size_t)-1 / 2, d->wo, d->wi,
                                            LL_TRANSPORT_RADIANCE, NULL, 0, rgb),
                     LL_ERROR_INVALID_ARGUMENT);
    free(rgb);
    free(pdf);
    free(wi);
    free(d);
    ll_bsdf_release(b);
}

/* A table file of the golden file at a small grid (the pipeline reads
 * the same tables whatever their size). */
static ll_bsdf *open_table(void)
{
    ll_bsdf *src = open_golden(), *b = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    char path[600];
    o.n_theta_i = 8;
    o.vndf_size = 32;
    o.sample_size = 16;
    snprintf(path, sizeof path, "%s/table.bsdf", ll_test_dir());
    if (ll_tables_write_from_bsdf(src, path, &o, NULL) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    ll_bsdf_release(src);
    if (ll_bsdf_open(path, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return b;
}

static void table_equals_scalar(void **state)
{
    ll_bsdf *b = open_table();
    batch_data *d = make_data(29);
    float one = 0.75f;
    size_t k;
    (void)state;
    /* Some elements of weight 0 (an eval without a look-up). */
    for (k = 0; k < N_ELEMENTS; k += 7)
        d->weights[k] = 0.0f;
    set_threads("1");
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_IMPORTANCE);
    check_against_scalar(b, d, &one, 0, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, d->weights, 1, LL_TRANSPORT_IMPORTANCE);
    set_threads("3");
    check_against_scalar(b, d, NULL, 0, LL_TRANSPORT_RADIANCE);
    check_against_scalar(b, d, d->weights, 1, LL_TRANSPORT_RADIANCE);
    unsetenv("LAYERLAB_BATCH_THREADS");
    free(d);
    ll_bsdf_release(b);
}

/* The lowest failing status of the scalar calls on elements [0, n) (what
 * the batch must return), LL_OK if none. */
static ll_status first_status(const ll_status *s, size_t n)
{
    size_t k;
    for (k = 0; k < n; ++k)
        if (s[k] != LL_OK)
            return s[k];
    return LL_OK;
}

/* Batches of the first n elements, for every n up to past twice any
 * pipeline depth and a long one, on data with elements that fail (NaN,
 * zero, u or weight out of range) or give zero (below the horizon) at
 * neighbouring places, so that they meet every stage of the pipeline,
 * the filling and the draining: each element's outputs bit for bit those
 * of its scalar call, the status that of the lowest failing one. */
static void table_pipeline_edges(void **state)
{
    enum { N = 1000 };
    ll_bsdf *b = open_table();
    batch_data *d = make_data(31);
    static double rgb[3 * N], pdf[N], srgb[3 * N], spdf[N], swi[3 * N];
    static double brgb[3 * N], bpdf[N], bwi[3 * N], bsrgb[3 * N], bspdf[N];
    static ll_status se[N], sp[N], ss[N];
    const size_t counts[] = { 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 15, 16, 17, 18, 23,
                              31, 32, 33, 34, 40, 47, 63, 64, 65, 66, N };
    size_t k, c, n;
    (void)state;
    /* Valid directions above the surface for the first 80 elements (the
     * ones that reach the tables), then the stand-ins at chosen places. */
    for (k = 0; k < 80; ++k) {
        d->wo[3 * k + 2] = fabs(d->wo[3 * k + 2]) + 0.05;
        d->wi[3 * k + 2] = fabs(d->wi[3 * k + 2]) + 0.05;
    }
    for (k = 0; k < N; ++k)
        d->weights[k] = 1.0f;
    d->wi[3 * 2 + 2] = -0.5;                                    /* below: zeros, LL_OK */
    d->wo[3 * 5 + 2] = -0.5;
    d->wi[3 * 9 + 0] = NAN;                                     /* invalid wi */
    d->wo[3 * 10 + 0] = d->wo[3 * 10 + 1] = d->wo[3 * 10 + 2] = 0.0; /* zero wo */
    d->u[2 * 11] = 1.5;                                         /* u out of range */
    d->weights[12] = NAN;                                       /* weight not finite */
    d->weights[13] = 0.0f;
    d->wi[3 * 16 + 2] = -0.3;
    d->wo[3 * 17 + 1] = INFINITY;
    d->wi[3 * 33 + 2] = NAN;
    d->wo[3 * 34 + 2] = -1.0;
    d->wi[3 * 64 + 0] = d->wi[3 * 64 + 1] = d->wi[3 * 64 + 2] = 0.0;
    d->u[2 * 65 + 1] = -0.1;
    for (k = 0; k < N; ++k) {
        se[k] = ll_bsdf_eval_dir(b, d->wo + 3 * k, d->wi + 3 * k, LL_TRANSPORT_RADIANCE,
                                 d->weights + k, srgb + 3 * k);
        sp[k] = ll_bsdf_pdf_dir(b, d->wo + 3 * k, d->wi + 3 * k, d->weights + k, spdf + k);
        ss[k] = ll_bsdf_sample_dir(b, d->wo + 3 * k, d->u + 2 * k, LL_TRANSPORT_RADIANCE,
                                   d->weights + k, swi + 3 * k, pdf + k, rgb + 3 * k);
    }
    /* The chosen places do what they stand for. */
    assert_int_equal(se[2], LL_OK);
    assert_true(srgb[6] == 0.0 && spdf[2] == 0.0);
    assert_int_equal(se[9], LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ss[11], LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(se[12], LL_ERROR_INVALID_ARGUMENT);
    set_threads("1");
    for (c = 0; c < sizeof counts / sizeof counts[0]; ++c) {
        n = counts[c];
        memset(brgb, 0xff, sizeof brgb);
        memset(bpdf, 0xff, sizeof bpdf);
        memset(bwi, 0xff, sizeof bwi);
        memset(bsrgb, 0xff, sizeof bsrgb);
        memset(bspdf, 0xff, sizeof bspdf);
        assert_int_equal(ll_bsdf_eval_dir_batch(b, n, d->wo, d->wi, LL_TRANSPORT_RADIANCE,
                                                d->weights, 1, brgb),
                         first_status(se, n));
        assert_int_equal(ll_bsdf_pdf_dir_batch(b, n, d->wo, d->wi, d->weights, 1, bpdf),
                         first_status(sp, n));
        assert_int_equal(ll_bsdf_sample_dir_batch(b, n, d->wo, d->u, LL_TRANSPORT_RADIANCE,
                                                  d->weights, 1, bwi, bspdf, bsrgb),
                         first_status(ss, n));
        for (k = 0; k < n; ++k) {
            assert_same_bits(brgb + 3 * k, srgb + 3 * k, 3, "eval", k);
            assert_same_bits(bpdf + k, spdf + k, 1, "pdf", k);
            assert_same_bits(bwi + 3 * k, swi + 3 * k, 3, "sampled wi", k);
            assert_same_bits(bspdf + k, pdf + k, 1, "sampled pdf", k);
            assert_same_bits(bsrgb + 3 * k, rgb + 3 * k, 3, "sampled f", k);
        }
        /* Nothing written past the batch. */
        if (n < N)
            assert_true(isnan(brgb[3 * n]) && isnan(bpdf[n]) && isnan(bspdf[n]));
    }
    /* An invalid mode fails every element, as their scalar calls do. */
    assert_int_equal(ll_bsdf_eval_dir_batch(b, 20, d->wo, d->wi, (ll_transport)7, NULL, 0, brgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "transport mode"));
    assert_int_equal(ll_bsdf_sample_dir_batch(b, 20, d->wo, d->u, (ll_transport)7, NULL, 0, bwi,
                                              bspdf, bsrgb),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "transport mode"));
    unsetenv("LAYERLAB_BATCH_THREADS");
    free(d);
    ll_bsdf_release(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(untextured_equals_scalar),
        cmocka_unit_test(textured_equals_scalar),
        cmocka_unit_test(invalid_elements),
        cmocka_unit_test(table_equals_scalar),
        cmocka_unit_test(table_pipeline_edges),
    };
    return cmocka_run_group_tests_name("bsdf_batch", tests, ll_test_dir_setup,
                                       ll_test_dir_teardown);
}
