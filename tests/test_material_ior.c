/*
 * Named metals: measured spectra of n and k reduced to one complex index per
 * colour channel (CIE 1931 matching functions, XYZ -> linear sRGB), and the
 * search for the spectra.
 */
#define _XOPEN_SOURCE 700 /* realpath */
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
#include "material/ior.h"

#define IOR_DIR LL_SOURCE_DIR "/data/ior"
#define GOLD_FILE LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf"

/* The three numbers after `"key": [` in text. */
static void read_json_triple(const char *text, const char *key, double out[3])
{
    const char *p = strstr(text, key);
    int k;
    assert_non_null(p);
    p = strchr(p, '[');
    assert_non_null(p);
    ++p;
    for (k = 0; k < 3; ++k) {
        char *end;
        out[k] = strtod(p, &end);
        assert_true(end != p);
        p = end;
        while (*p == ',' || *p == ' ' || *p == '\n')
            ++p;
    }
}

/* The metadata of the original tools' rough gold file holds the indices
 * they computed from the same spectra (eta_cond, k_cond). Ours must land
 * within 3%. */
static void gold_matches_the_reference_file(void **state)
{
    FILE *f = fopen(GOLD_FILE, "rb");
    char *bytes;
    long size;
    double eta_ref[3], k_ref[3];
    ll_metal_ior au;
    int c;
    (void)state;
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    size = ftell(f);
    assert_true(size > 682);
    bytes = calloc(1, (size_t)size + 1);
    assert_non_null(bytes);
    assert_int_equal(fseek(f, 0, SEEK_SET), 0);
    assert_int_equal(fread(bytes, 1, (size_t)size, f), (size_t)size);
    fclose(f);
    /* The metadata is the file's last 682 bytes (tests/data/README.md). */
    read_json_triple(bytes + size - 682, "\"eta_cond\"", eta_ref);
    read_json_triple(bytes + size - 682, "\"k_cond\"", k_ref);
    free(bytes);
    assert_float_equal(eta_ref[0], 0.14355, 1e-4);
    assert_float_equal(k_ref[2], 1.60434, 1e-4);

    assert_int_equal(ll_metal_ior_from_dir(IOR_DIR, "Au", &au), LL_OK);
    for (c = 0; c < 3; ++c) {
        assert_true(fabs(au.eta[c] / eta_ref[c] - 1.0) < 0.03);
        assert_true(fabs(au.k[c] / k_ref[c] - 1.0) < 0.03);
    }
    /* Gold: red reflects best, so n is smallest and k largest in red. */
    assert_true(au.eta[0] < au.eta[1] && au.eta[1] < au.eta[2]);
    assert_true(au.k[0] > au.k[1] && au.k[1] > au.k[2]);
    /* The luminance values lie between the channels'. */
    assert_true(au.eta_y > au.eta[0] && au.eta_y < au.eta[2]);
    assert_true(au.k_y < au.k[0] && au.k_y > au.k[2]);
}

/* Every metal of data/ior reads and gives physical indices. */
static void every_shared_metal_is_usable(void **state)
{
    static const char *const names[] = { "Ag", "Al", "Au", "Be", "Cr", "Cu", "Cu2O", "CuO",
                                         "Hg", "Ir", "K", "Li", "Mo", "Na_palik", "Nb",
                                         "Ni_palik", "Rh", "Ta", "TiN", "V_palik", "W" };
    size_t i;
    int c;
    (void)state;
    for (i = 0; i < sizeof names / sizeof names[0]; ++i) {
        ll_metal_ior m;
        assert_int_equal(ll_metal_ior_from_dir(IOR_DIR, names[i], &m), LL_OK);
        for (c = 0; c < 3; ++c) {
            assert_true(m.eta[c] > 0.0 && m.eta[c] < 10.0);
            assert_true(m.k[c] >= 0.0 && m.k[c] < 15.0);
        }
    }
}

/* A flat spectrum averages to itself in Y (the normalisation), and to
 * nearly itself in X and Z (the CIE 1931 functions have nearly equal
 * integrals: equal-energy white is X = Y = Z). */
static void flat_spectrum_gives_equal_energy_white(void **state)
{
    double lambda[2] = { 300.0, 900.0 }, value[2] = { 2.5, 2.5 }, xyz[3], rgb[3];
    ll_spectrum s;
    (void)state;
    s.count = 2;
    s.lambda = lambda;
    s.value = value;
    ll_spectrum_to_xyz(&s, xyz);
    assert_float_equal(xyz[1], 2.5, 1e-12);
    assert_float_equal(xyz[0], 2.5, 2.5e-3);
    assert_float_equal(xyz[2], 2.5, 2.5e-3);
    /* sRGB's white is D65, not equal energy: (1.2049, 0.9483, 0.9088). */
    ll_xyz_to_linear_srgb(xyz, rgb);
    assert_float_equal(rgb[0] / 2.5, 1.2049, 2e-3);
    assert_float_equal(rgb[1] / 2.5, 0.9483, 2e-3);
    assert_float_equal(rgb[2] / 2.5, 0.9088, 2e-3);
}

/* The observer table itself: its peak values (CIE 015:2004, Table T.4). */
static void observer_table_has_the_cie_values(void **state)
{
    (void)state;
    assert_float_equal(ll_cie1931_cmf[555 - 360][1], 1.0, 1e-4);       /* y peak, 555 nm */
    assert_float_equal(ll_cie1931_cmf[599 - 360][0], 1.0629096, 1e-6); /* x peak, 599 nm */
    assert_float_equal(ll_cie1931_cmf[446 - 360][2], 1.7829682, 1e-6); /* z peak, 446 nm */
    assert_float_equal(ll_cie1931_cmf[0][0], 0.0001299, 1e-10);        /* 360 nm */
}

static void d65_white_is_srgb_white(void **state)
{
    double xyz[3] = { 0.95047, 1.0, 1.08883 }, rgb[3];
    (void)state;
    ll_xyz_to_linear_srgb(xyz, rgb);
    assert_float_equal(rgb[0], 1.0, 1e-3);
    assert_float_equal(rgb[1], 1.0, 1e-3);
    assert_float_equal(rgb[2], 1.0, 1e-3);
}

/* A spectrum that ends before 830 nm holds its last value (Li ends at
 * 751 nm): the result equals that of the spectrum extended flat. */
static void short_spectrum_is_held_at_its_ends(void **state)
{
    double l1[3] = { 400.0, 500.0, 700.0 }, v1[3] = { 1.0, 2.0, 3.0 };
    double l2[5] = { 300.0, 400.0, 500.0, 700.0, 900.0 }, v2[5] = { 1.0, 1.0, 2.0, 3.0, 3.0 };
    double a[3], b[3];
    ll_spectrum s1, s2;
    (void)state;
    s1.count = 3;
    s1.lambda = l1;
    s1.value = v1;
    s2.count = 5;
    s2.lambda = l2;
    s2.value = v2;
    ll_spectrum_to_xyz(&s1, a);
    ll_spectrum_to_xyz(&s2, b);
    /* The two interpolants differ only in the end intervals' tangents. */
    assert_float_equal(a[1], b[1], 0.05);
    assert_true(a[1] > 1.0 && a[1] < 3.0);
}

static char tmpdir[64];

static int make_tmpdir(void **state)
{
    (void)state;
    ll_test_mkdtemp(tmpdir, sizeof tmpdir);
    return 0;
}

static int remove_tmpdir(void **state)
{
    (void)state;
    ll_test_rmdir(tmpdir);
    return 0;
}

static void write_text(const char *name, const char *text)
{
    char path[256];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", tmpdir, name);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void broken_spectra_are_rejected_with_line(void **state)
{
    char path[256];
    ll_spectrum s;
    (void)state;
    write_text("bad1.spd", "# comment\n400 1.0\n500 oops\n");
    snprintf(path, sizeof path, "%s/bad1.spd", tmpdir);
    assert_int_equal(ll_spectrum_read(path, &s), LL_ERROR_FORMAT);
    assert_non_null(strstr(ll_last_error_message(), "bad1.spd:3:"));

    write_text("bad2.spd", "400 1.0\n390 1.0\n");
    snprintf(path, sizeof path, "%s/bad2.spd", tmpdir);
    assert_int_equal(ll_spectrum_read(path, &s), LL_ERROR_FORMAT);
    assert_non_null(strstr(ll_last_error_message(), "bad2.spd:2:"));
    assert_non_null(strstr(ll_last_error_message(), "does not increase"));

    write_text("bad3.spd", "# only one\n400 1.0\n");
    snprintf(path, sizeof path, "%s/bad3.spd", tmpdir);
    assert_int_equal(ll_spectrum_read(path, &s), LL_ERROR_FORMAT);
    assert_non_null(strstr(ll_last_error_message(), "at least 2"));

    write_text("bad4.spd", "400 1.0 7\n");
    snprintf(path, sizeof path, "%s/bad4.spd", tmpdir);
    assert_int_equal(ll_spectrum_read(path, &s), LL_ERROR_FORMAT);

    snprintf(path, sizeof path, "%s/missing.spd", tmpdir);
    assert_int_equal(ll_spectrum_read(path, &s), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "missing.spd"));
}

/* $LAYERLAB_IOR_DIR comes first; unknown names list what is there. */
static void search_uses_the_environment_first(void **state)
{
    ll_metal_ior m, au;
    (void)state;
    write_text("Au.eta.spd", "300 0.5\n900 0.5\n");
    write_text("Au.k.spd", "300 3\n900 3\n");
    write_text("Zz.eta.spd", "300 0.5\n900 0.5\n");
    write_text("Zz.k.spd", "300 3\n900 3\n");
    assert_int_equal(setenv("LAYERLAB_IOR_DIR", tmpdir, 1), 0);
    assert_int_equal(ll_metal_ior_lookup("Au", NULL, &m), LL_OK);
    assert_float_equal(m.eta_y, 0.5, 1e-12);
    assert_float_equal(m.k_y, 3.0, 1e-12);
    /* A name only the library's own spectra have is still found there (this
     * program links liblayerlab.a, so its folder build/tests leads to
     * build/share/layerlab/ior, the build's copy of data/ior). */
    assert_int_equal(ll_metal_ior_lookup("Cu", NULL, &m), LL_OK);
    assert_int_equal(ll_metal_ior_lookup("Nope", NULL, &m), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "unknown metal 'Nope'"));
    assert_non_null(strstr(ll_last_error_message(), "Au, Zz"));
    assert_int_equal(ll_metal_ior_lookup("../Au", NULL, &m), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_metal_ior_lookup("", NULL, &m), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(unsetenv("LAYERLAB_IOR_DIR"), 0);
    /* Without it, gold comes from the library's spectra again. */
    assert_int_equal(ll_metal_ior_lookup("Au", LL_SOURCE_DIR "/examples", &au), LL_OK);
    assert_true(au.eta[0] < 0.2);
}

/* The search list is exactly: environment, the material's ior/, then
 * ../share/layerlab/ior from the folder of the code that runs (here this
 * statically linked program, build/tests) - nothing else, in particular no
 * folder outside the project (docs/material-language.md, "Named metals"). */
static void search_list_is_in_the_documented_order(void **state)
{
    char *dirs = NULL, *tests_dir, expected[4200];
    (void)state;
    tests_dir = realpath(LL_BUILD_DIR "/tests", NULL);
    assert_non_null(tests_dir);
    snprintf(expected, sizeof expected, "/a\n/b\n/m/ior\n%s/../share/layerlab/ior\n", tests_dir);
    assert_int_equal(setenv("LAYERLAB_IOR_DIR", "/a:/b", 1), 0);
    assert_int_equal(ll_ior_search_dirs("/m", &dirs), LL_OK);
    assert_string_equal(dirs, expected);
    free(dirs);
    assert_int_equal(unsetenv("LAYERLAB_IOR_DIR"), 0);
    /* Without the environment and a material folder only the library's
     * own spectra remain. */
    snprintf(expected, sizeof expected, "%s/../share/layerlab/ior\n", tests_dir);
    assert_int_equal(ll_ior_search_dirs(NULL, &dirs), LL_OK);
    assert_string_equal(dirs, expected);
    free(dirs);
    free(tests_dir);
}

/* The build tree holds the spectra where the rule looks (make copies
 * data/ior to build/share/layerlab/ior), and the lookup does not depend on
 * the working directory: from an empty folder, with no $LAYERLAB_IOR_DIR
 * and no material folder, gold is found and equals the project's data/ior. */
static void build_tree_spectra_are_found_from_any_directory(void **state)
{
    char cwd[4096];
    ll_metal_ior found, source;
    int c;
    (void)state;
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(access(LL_BUILD_DIR "/share/layerlab/ior/Au.eta.spd", R_OK), 0);
    assert_int_equal(unsetenv("LAYERLAB_IOR_DIR"), 0);
    assert_int_equal(chdir(tmpdir), 0);
    assert_int_equal(ll_metal_ior_lookup("Au", NULL, &found), LL_OK);
    assert_int_equal(chdir(cwd), 0);
    assert_int_equal(ll_metal_ior_from_dir(IOR_DIR, "Au", &source), LL_OK);
    for (c = 0; c < 3; ++c) {
        assert_true(found.eta[c] == source.eta[c]);
        assert_true(found.k[c] == source.k[c]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gold_matches_the_reference_file),
        cmocka_unit_test(every_shared_metal_is_usable),
        cmocka_unit_test(flat_spectrum_gives_equal_energy_white),
        cmocka_unit_test(observer_table_has_the_cie_values),
        cmocka_unit_test(d65_white_is_srgb_white),
        cmocka_unit_test(short_spectrum_is_held_at_its_ends),
        cmocka_unit_test(broken_spectra_are_rejected_with_line),
        cmocka_unit_test(search_uses_the_environment_first),
        cmocka_unit_test(search_list_is_in_the_documented_order),
        cmocka_unit_test(build_tree_spectra_are_found_from_any_directory),
    };
    return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}
