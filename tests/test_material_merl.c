/*
 * Measured BRDFs in the MERL format: file validation, the half/difference
 * lookup, the scale, and the layer (ll_layer_set_matusik) against direct
 * integration of synthetic tables.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <layerlab.h>
#include "test_util.h"
#include "words/merl.h"
#include "search/probe.h"
#include "material/material.h"

#define TH 12
#define TD 10
#define PD 20

static char path[64];

typedef double (*table_fn)(int channel, size_t ih, size_t id, size_t ip);

/* Write a MERL file (little-endian, as the database's) of TH x TD x PD. */
static void write_merl(const char *file, table_fn fn, uint32_t dims_override, long cut)
{
    FILE *f = fopen(file, "wb");
    uint32_t dims[3] = { TH, TD, PD };
    unsigned char b[8];
    size_t ih, id, ip, k;
    int c;
    assert_non_null(f);
    if (dims_override)
        dims[0] = dims_override;
    for (k = 0; k < 3; ++k) {
        b[0] = (unsigned char)(dims[k] & 0xff);
        b[1] = (unsigned char)(dims[k] >> 8 & 0xff);
        b[2] = (unsigned char)(dims[k] >> 16 & 0xff);
        b[3] = (unsigned char)(dims[k] >> 24 & 0xff);
        fwrite(b, 1, 4, f);
    }
    for (c = 0; c < 3; ++c)
        for (ih = 0; ih < TH; ++ih)
            for (id = 0; id < TD; ++id)
                for (ip = 0; ip < PD; ++ip) {
                    double v = fn(c, ih, id, ip);
                    uint64_t bits;
                    memcpy(&bits, &v, 8);
                    for (k = 0; k < 8; ++k)
                        b[k] = (unsigned char)(bits >> (8 * k) & 0xff);
                    fwrite(b, 1, 8, f);
                }
    fclose(f);
    if (cut > 0)
        assert_int_equal(truncate(file, cut), 0);
}

/* A constant table: stored 1500 * 0.4 / pi, i.e. a Lambertian of albedo 0.4
 * in red (green and blue get MERL's 1.15 and 1.66 factors). */
static double lambertian(int c, size_t ih, size_t id, size_t ip)
{
    (void)c;
    (void)ih;
    (void)id;
    (void)ip;
    return 1500.0 * 0.4 / LL_PI;
}

/* A table that is large near the specular direction (small theta_half) and
 * has missing (negative) entries at grazing theta_diff. */
static double glossy(int c, size_t ih, size_t id, size_t ip)
{
    (void)ip;
    if (id == TD - 1)
        return -1.0;
    return 1500.0 * (c + 1) * 2.0 / (1.0 + (double)(ih * ih));
}

static ll_layer *make_layer(size_t n, size_t m)
{
    double x[64], w[64];
    ll_layer *l = NULL;
    assert_true(n <= 64);
    assert_int_equal(ll_quad_gauss_lobatto(n, x, w, NULL), LL_OK);
    assert_int_equal(ll_layer_create(x, w, n, m, &l), LL_OK);
    return l;
}

static int setup(void **state)
{
    int fd;
    (void)state;
    strcpy(path, "/tmp/ll_merl_XXXXXX");
    fd = mkstemp(path);
    if (fd < 0)
        return -1;
    close(fd);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    unlink(path);
    return 0;
}

static void header_is_checked_against_the_size(void **state)
{
    (void)state;
    write_merl(path, lambertian, 0, 0);
    assert_int_equal(ll_merl_check(path), LL_OK);
    /* One resolution too large for the bytes present. */
    write_merl(path, lambertian, TH + 1, 0);
    assert_int_equal(ll_merl_check(path), LL_ERROR_FORMAT);
    assert_non_null(strstr(ll_last_error_message(), "bytes"));
    /* Truncated tables, truncated header, zero resolution. */
    write_merl(path, lambertian, 0, 12 + 8 * 100);
    assert_int_equal(ll_merl_check(path), LL_ERROR_FORMAT);
    write_merl(path, lambertian, 0, 7);
    assert_int_equal(ll_merl_check(path), LL_ERROR_FORMAT);
    assert_non_null(strstr(ll_last_error_message(), "header"));
    write_merl(path, lambertian, 0, 0);
    {
        FILE *f = fopen(path, "r+b");
        unsigned char zero[4] = { 0, 0, 0, 0 };
        assert_non_null(f);
        fwrite(zero, 1, 4, f);
        fclose(f);
    }
    assert_int_equal(ll_merl_check(path), LL_ERROR_FORMAT);
    assert_non_null(strstr(ll_last_error_message(), "theta_half"));
    assert_int_equal(ll_merl_check("/nonexistent/x.binary"), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "/nonexistent/x.binary"));
}

/* The half/difference coordinates: normal incidence and viewing is
 * theta_half = theta_diff = 0; a mirror pair at 60 degrees has theta_half 0
 * and theta_diff 60 degrees. */
static void lookup_uses_half_and_difference_angles(void **state)
{
    ll_merl *m;
    double up[3] = { 0.0, 0.0, 1.0 }, wi[3], wo[3], red[3] = { 1.0, 0.0, 0.0 };
    double s60 = sin(LL_PI / 3.0), c60 = cos(LL_PI / 3.0);
    (void)state;
    write_merl(path, glossy, 0, 0);
    assert_int_equal(ll_merl_load(path, &m), LL_OK);
    /* ih = 0: stored 1500 * 2, scaled by 1/1500. */
    assert_float_equal(ll_merl_eval(m, up, up, red), 2.0, 1e-12);
    wi[0] = s60, wi[1] = 0.0, wi[2] = c60;
    wo[0] = -s60, wo[1] = 0.0, wo[2] = c60;
    assert_float_equal(ll_merl_eval(m, wi, wo, red), 2.0, 1e-12);
    /* Off-specular: theta_half = 30 degrees: index sqrt(1/3) * 12 = 6. */
    wi[0] = s60, wi[1] = 0.0, wi[2] = c60;
    assert_float_equal(ll_merl_eval(m, wi, up, red), 2.0 / (1.0 + 36.0), 1e-12);
    /* Below the horizon: nothing. */
    wo[2] = -c60;
    assert_float_equal(ll_merl_eval(m, wi, wo, red), 0.0, 0.0);
    /* Green uses MERL's 1.15 / 1500. */
    {
        double green[3] = { 0.0, 1.0, 0.0 };
        assert_float_equal(ll_merl_eval(m, up, up, green), 2.0 * 2.0 * 1.15, 1e-12);
    }
    ll_merl_free(m);
}

/* A constant table is a Lambertian reflector: f = stored / 1500 (red),
 * albedo pi f; nothing is transmitted or reflected from below. */
static void constant_table_is_lambertian(void **state)
{
    ll_layer *l = make_layer(24, 6);
    double x[24], R, T;
    size_t i;
    (void)state;
    write_merl(path, lambertian, 0, 0);
    assert_int_equal(ll_layer_set_matusik(l, path, 0, 0, NULL), LL_OK);
    assert_int_equal(ll_layer_get_nodes(l, x, NULL), LL_OK);
    assert_float_equal(ll_test_layer_eval(l, 0.8, -0.4, 0.3), 0.4 / LL_PI, 1e-9);
    assert_float_equal(ll_test_layer_eval(l, 0.2, -0.9, 2.5), 0.4 / LL_PI, 1e-9);
    for (i = 12; i < 24; ++i) {
        assert_int_equal(ll_layer_albedo(l, x[i], &R, &T), LL_OK);
        /* The rule's own hemispherical error, as for ll_layer_set_diffuse. */
        assert_float_equal(R, 0.4, 2e-3);
        assert_float_equal(T, 0.0, 0.0);
        assert_int_equal(ll_layer_albedo(l, -x[i], &R, &T), LL_OK);
        assert_float_equal(R, 0.0, 0.0);
    }
    /* Blue: 1.66 times brighter by MERL's scale. */
    assert_int_equal(ll_layer_set_matusik(l, path, 2, 0, NULL), LL_OK);
    assert_float_equal(ll_test_layer_eval(l, 0.8, -0.4, 0.3), 1.66 * 0.4 / LL_PI, 1e-9);
    ll_layer_destroy(l);
}

/* Order 0 of the layer is the azimuthal mean of the table's BRDF, and the
 * series peaks in the specular direction (phi_d = 0). */
static void glossy_table_series_matches_direct_average(void **state)
{
    ll_layer *l = make_layer(16, 40);
    ll_merl *m;
    double x[16], *M0 = malloc(16 * 16 * sizeof(double)), w[3] = { 1.0, 0.0, 0.0 };
    size_t o, i;
    (void)state;
    assert_non_null(M0);
    write_merl(path, glossy, 0, 0);
    assert_int_equal(ll_merl_load(path, &m), LL_OK);
    /* 4000 azimuth samples internally: the trapezoid rule on a table of
     * steps converges slowly (about 5% off with the default 160 here). */
    assert_int_equal(ll_layer_set_matusik(l, path, 0, 1000, NULL), LL_OK);
    assert_int_equal(ll_layer_get_nodes(l, x, NULL), LL_OK);
    assert_int_equal(ll_layer_matrix(l, 0, M0), LL_OK);
    for (i = 8; i < 16; ++i)     /* mu_i > 0 */
        for (o = 0; o < 8; ++o) { /* mu_o < 0 */
            double mi = x[i], mo = -x[o], sum = 0.0, wi[3], wo[3];
            int j, N = 20000;
            wi[0] = sqrt(1 - mi * mi), wi[1] = 0.0, wi[2] = mi;
            for (j = 0; j < N; ++j) {
                double phi = LL_PI * (j + 0.5) / N;
                wo[0] = -sqrt(1 - mo * mo) * cos(phi);
                wo[1] = -sqrt(1 - mo * mo) * sin(phi);
                wo[2] = mo;
                sum += ll_merl_eval(m, wi, wo, w);
            }
            /* ll_layer_matrix holds f_0 = the mean over phi. */
            assert_float_equal(M0[o * 16 + i], sum / N, 5e-3 * sum / N + 1e-6);
        }
    /* Peak: specular azimuth above the opposite one. */
    assert_true(ll_test_layer_eval(l, 0.7, -0.7, 0.0) > 2.0 * ll_test_layer_eval(l, 0.7, -0.7, LL_PI));
    ll_merl_free(m);
    free(M0);
    ll_layer_destroy(l);
}

static void bad_arguments_are_rejected(void **state)
{
    ll_layer *l = make_layer(8, 2);
    (void)state;
    write_merl(path, lambertian, 0, 0);
    assert_int_equal(ll_layer_set_matusik(l, path, 3, 0, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_layer_set_matusik(l, path, -1, 0, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_layer_set_matusik(NULL, path, 0, 0, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_layer_set_matusik(l, NULL, 0, 0, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_layer_set_matusik(l, "/nonexistent.binary", 0, 0, NULL), LL_ERROR_IO);
    ll_layer_destroy(l);
}

/* A gentle table: a broad lobe in theta_half and a mild phi_diff term,
 * whose steps from cell to cell are small enough that the staircase of the
 * nearest-neighbour lookup converges to 2% (measured: (24, 20) and
 * (48, 40) each differ by 0.6% from twice themselves on the probes; that
 * floor, the cells' edges, stays as the resolution grows). */
static double gentle(int c, size_t ih, size_t id, size_t ip)
{
    double u = ((double)ih + 0.5) / TH, th = u * u * 0.5 * LL_PI;
    double td = ((double)id + 0.5) / TD * 0.5 * LL_PI, pd = ((double)ip + 0.5) / PD * LL_PI;
    (void)c;
    return 1500.0 * 0.3 / LL_PI * (1.0 + 0.01 * cos(th) + 0.005 * cos(td)) *
           (1.0 + 0.005 * cos(2.0 * pd));
}

static ll_layer *matusik_layer(size_t n, size_t m)
{
    double *x = malloc(n * sizeof(double)), *w = malloc(n * sizeof(double));
    ll_layer *l = NULL;
    assert_non_null(x);
    assert_non_null(w);
    assert_int_equal(ll_quad_gauss_lobatto(n, x, w, NULL), LL_OK);
    assert_int_equal(ll_layer_create(x, w, n, m, &l), LL_OK);
    assert_int_equal(ll_layer_set_matusik(l, path, 0, 0, NULL), LL_OK);
    free(x);
    free(w);
    return l;
}

/* The measured word's resolution: the layer built at what the
 * material's resolution chooses agrees with the one at twice its nodes and
 * orders within the tolerance wherever it is above 1% of its peak, at
 * grazing (mu 0.1, 0.15, 0.2) and pseudo-random pairs, mirror and
 * off-mirror azimuths (not the search's probes); the probes' shortcut is
 * the built layer's ll_layer_eval; a staircase too steep for the tolerance
 * is held at the table's resolution, not grown without end. */
static void measured_resolution_meets_the_tolerance(void **state)
{
    static const double grazing[] = { 0.1, 0.15, 0.2 };
    static const double azimuths[] = { 0.0, 0.05, 0.4, 1.3, 2.9 };
    const double tolerance = 0.02, red[3] = { 1.0, 0.0, 0.0 };
    char text[128];
    ll_material *mat = NULL;
    ll_layer *a, *b;
    ll_merl *merl;
    ll_probe_set set;
    double *probe, worst = 0.0, peak = 0.0, e;
    size_t n, m, c, i, j, k;
    uint64_t seed = 7;
    (void)state;
    write_merl(path, gentle, 0, 0);
    snprintf(text, sizeof text, "set tolerance=%g\nmeasured file=\"%s\"\n", tolerance, path);
    assert_int_equal(ll_material_parse(text, "t", &mat), LL_OK);
    assert_int_equal(ll_material_resolution(mat, NULL, NULL, &n, &m, &c), LL_OK);
    ll_material_destroy(mat);
    /* Found below the cap (2 x 12 nodes, 20 orders), not assumed. */
    assert_true(n >= 10 && m >= 1);
    a = matusik_layer(n, m);
    b = matusik_layer(2 * n, 2 * m);
    for (i = 0; i < 3 + 40; ++i) {
        double mu_i = i < 3 ? grazing[i] : 0.1 + 0.9 * (double)(seed = seed * 6364136223846793005ULL +
                                                                 1442695040888963407ULL) /
                                                    18446744073709551616.0;
        for (j = 0; j < 3 + 6; ++j) {
            double mu_o = j < 3 ? grazing[j] : j == 3 ? mu_i : 0.1 + 0.1 * (double)j;
            for (k = 0; k < sizeof azimuths / sizeof azimuths[0]; ++k)
                peak = fmax(peak, ll_test_layer_eval(b, mu_i, -mu_o, azimuths[k]));
        }
    }
    seed = 7;
    for (i = 0; i < 3 + 40; ++i) {
        double mu_i = i < 3 ? grazing[i] : 0.1 + 0.9 * (double)(seed = seed * 6364136223846793005ULL +
                                                                 1442695040888963407ULL) /
                                                    18446744073709551616.0;
        for (j = 0; j < 3 + 6; ++j) {
            double mu_o = j < 3 ? grazing[j] : j == 3 ? mu_i : 0.1 + 0.1 * (double)j;
            for (k = 0; k < sizeof azimuths / sizeof azimuths[0]; ++k) {
                double ref = ll_test_layer_eval(b, mu_i, -mu_o, azimuths[k]);
                if (ref > 0.01 * peak)
                    worst = fmax(worst, fabs(ll_test_layer_eval(a, mu_i, -mu_o, azimuths[k]) - ref) / ref);
            }
        }
    }
    if (!(worst <= tolerance))
        fail_msg("measured at %zu x %zu: %g off twice that resolution", n, m, worst);
    ll_layer_destroy(b);

    /* The probes' values are the layer's own. */
    assert_int_equal(ll_merl_load(path, &merl), LL_OK);
    assert_int_equal(ll_probe_opaque(0.1, &set), LL_OK);
    probe = malloc(LL_PROBE_VALUES(&set) * sizeof(double));
    assert_non_null(probe);
    assert_int_equal(ll_merl_probe_eval(merl, red, n, m, &set, NULL, probe), LL_OK);
    for (i = 0; i < set.n_pairs; ++i)
        for (k = 0; k < set.n_phi; ++k) {
            double v = ll_test_layer_eval(a, set.pairs[i].mu_i, set.pairs[i].mu_o, set.phi[k]);
            assert_float_equal(probe[i * set.n_phi + k], v, 1e-12 * fmax(1.0, v));
        }
    free(probe);
    ll_probe_free(&set);
    ll_layer_destroy(a);

    /* The search's own verdict: met, with its margin. */
    n = 100;
    m = 180;
    assert_int_equal(ll_merl_resolution(merl, red, tolerance, 0.1, NULL, &n, &m, &e), LL_OK);
    assert_true(e <= 0.6 * tolerance);
    ll_merl_free(merl);

    /* A steep table: its steps exceed 2%, so the search stops at the cap
     * (2 x TH nodes, PD orders) and says it is unverified. */
    write_merl(path, glossy, 0, 0);
    assert_int_equal(ll_merl_load(path, &merl), LL_OK);
    n = 100;
    m = 180;
    assert_int_equal(ll_merl_resolution(merl, red, tolerance, 0.1, NULL, &n, &m, &e), LL_OK);
    assert_int_equal(n, 2 * TH);
    assert_int_equal(m, PD);
    assert_true(isinf(e));
    ll_merl_free(merl);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(header_is_checked_against_the_size),
        cmocka_unit_test(lookup_uses_half_and_difference_angles),
        cmocka_unit_test(constant_table_is_lambertian),
        cmocka_unit_test(glossy_table_series_matches_direct_average),
        cmocka_unit_test(bad_arguments_are_rejected),
        cmocka_unit_test(measured_resolution_meets_the_tolerance),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
