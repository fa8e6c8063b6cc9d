/*
 * Spectral table files (ll_tables.h, LL_TABLES_SPECTRAL; docs/formats.md):
 * the upsampling of RGB albedos (its round trip), the conversion the
 * reader applies (reader/cie.h), the writer and reader together (the
 * layout [theta_i][wavelength][N][N] checked against single-wavelength
 * files of the same warp), the material at each wavelength
 * (ll_material_write_tables: a named metal, a fitted albedo, the
 * refusals), and hostile spectral files: a `wavelengths` of the wrong
 * length, wavelengths not increasing, NaN, wavelengths the observer does
 * not see, each a clear error naming the field.
 */
#include "test_bsdf_util.h"
#include "support/support.h"
#include "reader/cie.h"
#include "material/rgb_spectrum.h"
#include "material/material_spectral.h"

/* --------------------------------------------------------- the colours */

static const double colours[][3] = {
    { 0.5, 0.5, 0.5 }, { 0.8, 0.2, 0.1 }, { 0.2, 0.5, 0.8 }, { 0.9, 0.1, 0.1 },
    { 0.1, 0.9, 0.1 }, { 0.05, 0.05, 0.6 }, { 0.95, 0.9, 0.6 }, { 0.01, 0.02, 0.03 },
    { 0.3, 0.25, 0.2 }, { 1.0, 0.0, 0.0 }, { 0.0, 0.0, 1.0 }, { 0.0, 0.0, 0.0 },
    { 1.0, 1.0, 1.0 }, { 0.6, 0.6, 0.2 },
};

/* The fit reproduces each colour on the 1 nm tables it is made on, stays
 * inside [0, 1], and on a 10 nm grid (what a file is read with) is within
 * the stated 2e-3. */
static void test_upsampling_round_trip(void **state)
{
    double lambda[48], w[48][3], worst_fine = 0.0, worst_coarse = 0.0;
    size_t i, l, n = 48;
    int c;
    (void)state;
    for (l = 0; l < n; ++l)
        lambda[l] = 360.0 + 10.0 * (double)l;
    assert_true(ll_spectral_rgb_weights(lambda, n, w));
    for (i = 0; i < sizeof colours / sizeof colours[0]; ++i) {
        ll_rgb_spectrum s;
        double err, got[3], coarse[3] = { 0.0, 0.0, 0.0 }, nm;
        assert_int_equal(ll_rgb_spectrum_fit(colours[i], &s, &err), LL_OK);
        ll_rgb_spectrum_colour(&s, got);
        for (nm = 360.0; nm <= 830.0; nm += 0.5) {
            double v = ll_rgb_spectrum_at(&s, nm);
            assert_true(v >= 0.0 && v <= 1.0);
        }
        for (l = 0; l < n; ++l)
            for (c = 0; c < 3; ++c)
                coarse[c] += w[l][c] * ll_rgb_spectrum_at(&s, lambda[l]);
        for (c = 0; c < 3; ++c) {
            worst_fine = fmax(worst_fine, fabs(got[c] - colours[i][c]));
            worst_coarse = fmax(worst_coarse, fabs(coarse[c] - colours[i][c]));
        }
        assert_true(err <= 1e-9);
    }
    printf("upsampling round trip: |rgb - rgb(fit)| <= %.1e on the 1 nm tables, %.1e read "
           "on 360:830:10\n",
           worst_fine, worst_coarse);
    assert_true(worst_fine <= 1e-9);
    assert_true(worst_coarse <= 2e-3);
    {
        double bad[3] = { 0.5, 1.5, 0.5 };
        ll_rgb_spectrum s;
        assert_int_equal(ll_rgb_spectrum_fit(bad, &s, NULL), LL_ERROR_INVALID_ARGUMENT);
    }
}

/* White reads white on any grid; one wavelength reads as (v, v, v). */
static void test_conversion(void **state)
{
    double lambda[3] = { 450.0, 551.5, 640.0 }, w[3][3], one[1] = { 555.0 }, w1[1][3];
    double far[2] = { 900.0, 950.0 }, wf[2][3];
    int c;
    (void)state;
    assert_true(ll_spectral_rgb_weights(lambda, 3, w));
    for (c = 0; c < 3; ++c)
        assert_float_equal(w[0][c] + w[1][c] + w[2][c], 1.0, 1e-12);
    assert_true(ll_spectral_rgb_weights(one, 1, w1));
    for (c = 0; c < 3; ++c)
        assert_float_equal(w1[0][c], 1.0, 1e-12);
    assert_false(ll_spectral_rgb_weights(far, 2, wf));
}

/* ----------------------------------------------- the writer and reader */

static ll_bsdf *golden, *diffuse;
static char two_path[600], one_path[2][600];

/* Wavelength 0 from the golden file, the others from a diffuse one. */
static ll_status two_sources(void *user, size_t index, double nm, ll_bsdf **out)
{
    const double *expected = user;
    assert_float_equal(nm, expected[index], 0.0);
    *out = ll_bsdf_retain(index == 0 ? golden : diffuse);
    return LL_OK;
}

static ll_status only_diffuse(void *user, size_t index, double nm, ll_bsdf **out)
{
    (void)user;
    (void)index;
    (void)nm;
    *out = ll_bsdf_retain(diffuse);
    return LL_OK;
}

static ll_tables_options small_options(void)
{
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    o.n_theta_i = 4;
    o.vndf_size = 8;
    o.sample_size = 8;
    o.format = LL_TABLES_SPECTRAL;
    return o;
}

static int setup(void **state)
{
    static double two[2] = { 500.0, 600.0 };
    ll_material *m = NULL;
    ll_build_options b = LL_BUILD_OPTIONS_INIT;
    ll_tables_options o = small_options();
    char path[600];
    size_t k;
    ll_test_dir_setup(state);
    snprintf(path, sizeof path, "%s/diffuse.bsdf", ll_test_dir());
    b.n_nodes = 20;
    b.n_orders = 1;
    if (ll_material_parse("diffuse albedo=0.4\n", "diffuse", &m) != LL_OK ||
        ll_material_build(m, &b, NULL, path) != LL_OK ||
        ll_bsdf_open(path, NULL, &diffuse) != LL_OK ||
        ll_bsdf_open(LL_TEST_GOLDEN, NULL, &golden) != LL_OK)
        return 1;
    ll_material_destroy(m);
    /* The two-wavelength file, and one file per wavelength with the same
     * warp (the golden file's) and the same source. */
    snprintf(two_path, sizeof two_path, "%s/two.tab", ll_test_dir());
    o.wavelengths = two;
    o.n_wavelengths = 2;
    o.spectrum = two_sources;
    o.spectrum_user = two;
    if (ll_tables_write_from_bsdf(golden, two_path, &o, NULL) != LL_OK)
        return 1;
    for (k = 0; k < 2; ++k) {
        snprintf(one_path[k], sizeof one_path[k], "%s/one%zu.tab", ll_test_dir(), k);
        o.wavelengths = &two[k];
        o.n_wavelengths = 1;
        o.spectrum = k == 0 ? two_sources : only_diffuse;
        if (ll_tables_write_from_bsdf(golden, one_path[k], &o, NULL) != LL_OK)
            return 1;
    }
    return 0;
}

static int teardown(void **state)
{
    ll_bsdf_release(golden);
    ll_bsdf_release(diffuse);
    return ll_test_dir_teardown(state);
}

static ll_bsdf *open_file(const char *p)
{
    ll_bsdf *b = NULL;
    if (ll_bsdf_open(p, NULL, &b) != LL_OK)
        fail_msg("%s: %s", p, ll_last_error_message());
    return b;
}

static void direction(double cos_theta, double phi, double w[3])
{
    double s = sqrt(1.0 - cos_theta * cos_theta);
    w[0] = s * cos(phi);
    w[1] = s * sin(phi);
    w[2] = cos_theta;
}

/* The two-wavelength file reads as the weighted sum of its slices, each
 * of which is the single-wavelength file of its source: the layout and
 * the conversion agree. A single-wavelength file of the golden source is
 * the luminance of its RGB table (same warp, same nodes) up to the horizon
 * fit, which the RGB table takes per channel. */
static void test_layout_and_conversion(void **state)
{
    double lambda[2] = { 500.0, 600.0 }, w[2][3];
    ll_bsdf *two = open_file(two_path), *one[2], *rgb;
    double got[400][3], want[400][3], top[3] = { 0.0, 0.0, 0.0 };
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    ll_tables_options o = small_options();
    char rgb_path[600];
    int k, c, nonzero = 0;
    double worst_fit = 0.0;
    (void)state;
    one[0] = open_file(one_path[0]);
    one[1] = open_file(one_path[1]);
    o.format = LL_TABLES_RGB;
    snprintf(rgb_path, sizeof rgb_path, "%s/rgb.tab", ll_test_dir());
    assert_int_equal(ll_tables_write_from_bsdf(golden, rgb_path, &o, NULL), LL_OK);
    rgb = open_file(rgb_path);
    assert_int_equal(ll_bsdf_get_info(two, &info), LL_OK);
    assert_int_equal(info.format, LL_BSDF_FORMAT_TABLES);
    assert_int_equal(info.n_wavelengths, 2);
    assert_int_equal(info.n_channels, 3);
    assert_non_null(strstr(info.metadata, "\"wavelengths\": 2"));
    assert_int_equal(ll_bsdf_get_info(rgb, &info), LL_OK);
    assert_int_equal(info.n_wavelengths, 0);
    assert_true(ll_spectral_rgb_weights(lambda, 2, w));
    for (k = 0; k < 400; ++k) {
        double wi[3], wo[3], f2[3], f0[3], f1[3], fr[3], lum;
        direction(0.05 + 0.95 * (k % 20) / 19.0, 0.0, wi);
        direction(0.05 + 0.95 * (k / 20) / 19.0, 0.3 * k, wo);
        assert_int_equal(ll_bsdf_eval_dir(two, wi, wo, LL_TRANSPORT_RADIANCE, NULL, f2), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(one[0], wi, wo, LL_TRANSPORT_RADIANCE, NULL, f0),
                         LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(one[1], wi, wo, LL_TRANSPORT_RADIANCE, NULL, f1),
                         LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(rgb, wi, wo, LL_TRANSPORT_RADIANCE, NULL, fr), LL_OK);
        lum = 0.212671 * fr[0] + 0.715160 * fr[1] + 0.072169 * fr[2];
        for (c = 0; c < 3; ++c) {
            got[k][c] = f2[c];
            want[k][c] = w[0][c] * f0[c] + w[1][c] * f1[c];
            top[c] = fmax(top[c], want[k][c]);
            /* (Where the golden file's f is far below its peak a channel of
             * it may be slightly negative: the RGB table clips each channel,
             * the spectral one their luminance.) */
            if (lum > 1e-3)
                worst_fit = fmax(worst_fit, fabs(f0[c] / lum - 1.0));
            /* (The diffuse source through the gold's warp on this tiny
             * grid is only roughly albedo / pi: 3x at grazing.) */
            assert_true(f1[c] >= 0.0 && ll_is_finite(f1[c]));
        }
        nonzero += lum > 0.0;
    }
    assert_true(nonzero > 300);
    /* The golden file is coloured: its RGB table's nodes beyond the
     * horizon and its slices' scale are fitted per channel to that
     * channel's albedo, the single wavelength's to the luminance's
     * (bsdf_write_tables_horizon.c), which at this tiny grid differ by
     * 0.57% at most. A grey source, whose channels are one, is checked
     * exactly below (test_grey_conversion). */
    printf("golden: one wavelength against the RGB table's luminance: %.3f%%\n",
           100.0 * worst_fit);
    assert_true(worst_fit <= 0.008);
    /* The converted values. Green has positive weights at 500 and 600 nm,
     * so it is the sum exactly; red and blue have a negative one (the
     * spectrum of two wavelengths lies far outside the sRGB gamut), and
     * where their sum is negative at a node it is clipped to 0 there,
     * before the interpolation, which can only raise the value. */
    assert_true(w[0][1] > 0.0 && w[1][1] > 0.0);
    for (k = 0, nonzero = 0; k < 400; ++k)
        for (c = 0; c < 3; ++c) {
            if (c == 1 && want[k][c] > 1e-3 * top[c]) {
                assert_float_equal(got[k][c], want[k][c], 1e-5 * want[k][c]);
                ++nonzero;
            }
            assert_true(got[k][c] >= want[k][c] - 1e-6 * top[c]);
        }
    printf("green values above 1e-3 of the peak compared: %d of 400\n", nonzero);
    assert_true(nonzero > 300);
    ll_bsdf_release(two);
    ll_bsdf_release(one[0]);
    ll_bsdf_release(one[1]);
    ll_bsdf_release(rgb);
}

/* A single-wavelength file of a grey source is its RGB table's
 * luminance, node for node: the same warp, the same nodes, the same fit
 * (each channel's albedo is the luminance's). */
static void test_grey_conversion(void **state)
{
    double nm[1] = { 550.0 };
    ll_tables_options o = small_options();
    char one_grey[600], rgb_grey[600];
    ll_bsdf *one, *rgb;
    int k, c, compared = 0;
    (void)state;
    snprintf(one_grey, sizeof one_grey, "%s/one_grey.tab", ll_test_dir());
    snprintf(rgb_grey, sizeof rgb_grey, "%s/rgb_grey.tab", ll_test_dir());
    o.wavelengths = nm;
    o.n_wavelengths = 1;
    o.spectrum = only_diffuse;
    assert_int_equal(ll_tables_write_from_bsdf(diffuse, one_grey, &o, NULL), LL_OK);
    o.format = LL_TABLES_RGB;
    assert_int_equal(ll_tables_write_from_bsdf(diffuse, rgb_grey, &o, NULL), LL_OK);
    one = open_file(one_grey);
    rgb = open_file(rgb_grey);
    for (k = 0; k < 400; ++k) {
        double wi[3], wo[3], f1[3], fr[3], lum;
        direction(0.05 + 0.95 * (k % 20) / 19.0, 0.0, wi);
        direction(0.05 + 0.95 * (k / 20) / 19.0, 0.3 * k, wo);
        assert_int_equal(ll_bsdf_eval_dir(one, wi, wo, LL_TRANSPORT_RADIANCE, NULL, f1), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(rgb, wi, wo, LL_TRANSPORT_RADIANCE, NULL, fr), LL_OK);
        lum = 0.212671 * fr[0] + 0.715160 * fr[1] + 0.072169 * fr[2];
        if (!(lum > 1e-3))
            continue;
        for (c = 0; c < 3; ++c)
            assert_float_equal(f1[c], lum, 1e-5 * lum);
        ++compared;
    }
    printf("grey: %d of 400 pairs compared\n", compared);
    assert_true(compared > 300);
    ll_bsdf_release(one);
    ll_bsdf_release(rgb);
}

static void test_writer_refusals(void **state)
{
    double bad_order[2] = { 600.0, 500.0 }, low[1] = { 300.0 }, ok[1] = { 500.0 };
    ll_tables_options o = small_options();
    char path[600];
    (void)state;
    snprintf(path, sizeof path, "%s/refused.tab", ll_test_dir());
    o.spectrum = only_diffuse;
    o.wavelengths = bad_order;
    o.n_wavelengths = 2;
    assert_int_equal(ll_tables_write_from_bsdf(golden, path, &o, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "not above"));
    o.wavelengths = low;
    o.n_wavelengths = 1;
    assert_int_equal(ll_tables_write_from_bsdf(golden, path, &o, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "CIE 1931"));
    o.wavelengths = ok;
    o.n_wavelengths = 0;
    assert_int_equal(ll_tables_write_from_bsdf(golden, path, &o, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    o.n_wavelengths = LL_TABLES_MAX_WAVELENGTHS + 1;
    assert_int_equal(ll_tables_write_from_bsdf(golden, path, &o, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    o.n_wavelengths = 1;
    o.spectrum = NULL;
    assert_int_equal(ll_tables_write_from_bsdf(golden, path, &o, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "spectrum source"));
    assert_int_equal(access(path, F_OK), -1);
}

/* ------------------------------------------------------ hostile files */

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    int k;
    for (k = 7; k >= 0; --k)
        v = (v << 8) | p[k];
    return v;
}

/* Where field name's entry keeps its offset (its extents follow). */
static size_t offset_entry(const unsigned char *d, const char *name)
{
    size_t at = 18, n = d[14] | (d[15] << 8), k;
    for (k = 0; k < n; ++k) {
        size_t len = d[at] | (d[at + 1] << 8);
        size_t r = d[at + 2 + len] | (d[at + 3 + len] << 8);
        if (len == strlen(name) && memcmp(d + at + 2, name, len) == 0)
            return at + 2 + len + 3;
        at += 2 + len + 2 + 1 + 8 + 8 * r;
    }
    fail_msg("no field %s", name);
    return 0;
}

static void put_f32(unsigned char *p, float v)
{
    uint32_t bits;
    int k;
    memcpy(&bits, &v, sizeof bits);
    for (k = 0; k < 4; ++k)
        p[k] = (unsigned char)(bits >> (8 * k));
}

static void expect(const unsigned char *data, size_t size, const char *what)
{
    ll_bsdf *b = NULL;
    ll_status s = ll_bsdf_open_memory(data, size, NULL, &b);
    if (s != LL_ERROR_FORMAT || !strstr(ll_last_error_message(), what))
        fail_msg("status %d (%s), expected a format error naming \"%s\"", (int)s,
                 ll_last_error_message(), what);
    assert_null(b);
}

static void test_hostile(void **state)
{
    size_t size, lam, spectra, at;
    unsigned char *good = ll_test_read_file(two_path, &size), *d = malloc(size);
    (void)state;
    assert_non_null(good);
    assert_non_null(d);
    lam = offset_entry(good, "wavelengths");
    spectra = offset_entry(good, "spectra");
    at = (size_t)get_u64(good + lam);
    /* wavelengths of the wrong length (1 where the spectra have 2) */
    memcpy(d, good, size);
    d[lam + 8] = 1;
    expect(d, size, "\"spectra\": shape must be [phi_i, theta_i, n, N, N] with the n of "
                    "\"wavelengths\"");
    /* not increasing */
    memcpy(d, good, size);
    put_f32(d + at + 4, 500.0f);
    expect(d, size, "\"wavelengths\": element 1");
    /* NaN in the wavelengths, and in the spectra */
    memcpy(d, good, size);
    put_f32(d + at, NAN);
    expect(d, size, "\"wavelengths\": element 0");
    memcpy(d, good, size);
    put_f32(d + (size_t)get_u64(good + spectra) + 8, NAN);
    expect(d, size, "\"spectra\": element 2");
    /* wavelengths the observer does not see */
    memcpy(d, good, size);
    put_f32(d + at, 900.0f);
    put_f32(d + at + 4, 950.0f);
    expect(d, size, "no light of the CIE 1931 observer");
    /* a spectral file without spectra */
    memcpy(d, good, size);
    d[spectra - 3 - 7] = 'x'; /* the name "spectra" becomes "xpectra" */
    expect(d, size, "\"spectra\" is missing");
    free(d);
    free(good);
}

/* ------------------------------------------------- a material's spectra */

static ll_status write_material(const char *text, const double *nm, size_t n, const char *path)
{
    ll_material *m = NULL;
    ll_build_options b = LL_BUILD_OPTIONS_INIT;
    ll_tables_options o = small_options();
    ll_status s = ll_material_parse(text, "test", &m);
    assert_int_equal(s, LL_OK);
    b.n_nodes = 30;
    b.n_orders = 30;
    o.wavelengths = nm;
    o.n_wavelengths = n;
    s = ll_material_write_tables(m, &b, NULL, path, &o, NULL);
    ll_material_destroy(m);
    return s;
}

static void test_material(void **state)
{
    double nm[7] = { 400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0 };
    char path[600];
    ll_bsdf *b;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    double wi[3], f[3];
    (void)state;
    snprintf(path, sizeof path, "%s/gold.tab", ll_test_dir());
    assert_int_equal(write_material("conductor eta=Au alpha=0.3\n", nm, 7, path), LL_OK);
    b = open_file(path);
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_int_equal(info.n_wavelengths, 7);
    direction(0.9, 0.0, wi);
    assert_int_equal(ll_bsdf_eval_dir(b, wi, (double[3]){ -wi[0], 0.0, wi[2] },
                                      LL_TRANSPORT_RADIANCE, NULL, f),
                     LL_OK);
    /* Gold: red above green above blue at the mirror direction. */
    printf("gold at the mirror direction, 7 wavelengths: R %g G %g B %g\n", f[0], f[1], f[2]);
    assert_true(f[0] > f[1] && f[1] > f[2] && f[2] > 0.0);
    ll_bsdf_release(b);
    /* A coloured diffuse base under a coat: its albedo's spectrum. */
    assert_int_equal(write_material("dielectric eta=1.5 alpha=0.2\ndiffuse albedo=0.8,0.3,0.1\n",
                                    nm, 3, path),
                     LL_OK);
    /* Refusals: an index given as R,G,B; a transmissive stack. */
    assert_int_equal(write_material("conductor eta=0.2+3i,0.4+2.5i,1.2+1.8i alpha=0.2\n", nm,
                                    3, path),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "R,G,B"));
    assert_int_equal(write_material("dielectric eta=1.5 alpha=0.2\n", nm, 3, path),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "reflection only"));
}

/* Wavelengths share word layers: a coat over gold at 7 wavelengths builds
 * one coat and 7 gold interfaces, as ll_material_write_tables builds them
 * (material_tables.c: one cache for all wavelengths). */
static void test_sharing(void **state)
{
    ll_material *m = NULL;
    ll_spectral_plan p;
    ll_word_cache *cache = ll_word_cache_create();
    ll_build_options o = LL_BUILD_OPTIONS_INIT, r;
    double nm;
    size_t n = 0;
    (void)state;
    assert_non_null(cache);
    assert_int_equal(ll_material_parse("dielectric eta=1.5 alpha=0.1\nconductor eta=Au "
                                       "alpha=0.1\n",
                                       "coated gold", &m),
                     LL_OK);
    o.n_nodes = 30;
    o.n_orders = 30;
    o.n_channels = 1;
    assert_int_equal(ll_build_options_read(&o, &r, "test"), LL_OK);
    assert_int_equal(ll_spectral_plan_init(m, &p, "test"), LL_OK);
    for (nm = 400.0; nm <= 700.0; nm += 50.0, ++n) {
        ll_material view;
        ll_layer *layers[3];
        size_t nch;
        ll_spectral_view(&p, nm, &view);
        assert_int_equal(ll_material_build_layers_cached(&view, &r, NULL, cache, layers, &nch,
                                                         NULL),
                         LL_OK);
        assert_int_equal(nch, 1);
        ll_layer_destroy(layers[0]);
    }
    assert_int_equal(ll_word_cache_built(cache), n + 1);
    ll_word_cache_destroy(cache);
    ll_spectral_plan_free(&p);
    ll_material_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_upsampling_round_trip),
        cmocka_unit_test(test_conversion),
        cmocka_unit_test(test_layout_and_conversion),
        cmocka_unit_test(test_grey_conversion),
        cmocka_unit_test(test_writer_refusals),
        cmocka_unit_test(test_hostile),
        cmocka_unit_test(test_material),
        cmocka_unit_test(test_sharing),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
