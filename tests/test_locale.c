/*
 * Numbers in material files and spectra are read the same way whatever
 * locale the host program has set (a regression test: under
 * LC_ALL=de_DE.UTF-8, `albedo=0.5` was "not a number" and the metals'
 * spectra did not load, because strtod reads the locale's decimal comma).
 *
 * The test switches the process to a comma-decimal locale: de_DE.UTF-8 if
 * installed, else one generated with localedef into the build folder (found
 * through LOCPATH), else any installed locale whose decimal point is ','.
 * Only when none can be had does it skip, saying so.
 */
#include "test_util.h"
#include "support/parse_number.h"
#include "material/ior.h"
#include "material/material.h"

#include <locale.h>

static int comma_locale_active(void)
{
    const struct lconv *lc = localeconv();
    return lc && lc->decimal_point && strcmp(lc->decimal_point, ",") == 0;
}

/* Switch LC_ALL to a comma-decimal locale; 0 if there is none. */
static int set_comma_locale(void)
{
    static const char *const installed[] = { "de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8",
                                             "nl_NL.UTF-8", "it_IT.UTF-8", "es_ES.UTF-8" };
    char command[1024], dir[600];
    size_t k;
    for (k = 0; k < sizeof installed / sizeof installed[0]; ++k)
        if (setlocale(LC_ALL, installed[k]) && comma_locale_active())
            return 1;
    /* Not installed: compile de_DE from the locales package's sources into
     * the build folder (no root needed; glibc reads LOCPATH). */
    snprintf(dir, sizeof dir, "%s/locale", LL_BUILD_DIR);
    mkdir(dir, 0755);
    snprintf(command, sizeof command,
             "localedef -i de_DE -f UTF-8 '%s/de_DE.UTF-8' >/dev/null 2>&1", dir);
    if (system(command) != 0 && access(dir, F_OK) != 0)
        return 0;
    setenv("LOCPATH", dir, 1);
    return setlocale(LC_ALL, "de_DE.UTF-8") && comma_locale_active();
}

static int setup(void **state)
{
    (void)state;
    ll_test_mkdtemp(ll_test_dir(), 512);
    if (!set_comma_locale()) {
        print_message("[  SKIP    ] no comma-decimal locale is installed and localedef could "
                      "not make de_DE.UTF-8 (install the `locales` package)\n");
        return -1;
    }
    print_message("[ INFO     ] LC_ALL = %s, decimal point '%s'\n", setlocale(LC_ALL, NULL),
                  localeconv()->decimal_point);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    setlocale(LC_ALL, "C");
    ll_test_rmdir(ll_test_dir());
    return 0;
}

static void parse_double_ignores_locale(void **state)
{
    char *end;
    (void)state;
    /* The host's strtod stops at the '.' now: what the bug looked like. */
    assert_true(strtod("0.5", &end) == 0.0 && *end == '.');
    assert_true(ll_parse_double("0.5", &end) == 0.5 && *end == '\0');
    assert_true(ll_parse_double("1.5e-3x", &end) == 1.5e-3 && *end == 'x');
    assert_true(ll_parse_double("-.25", &end) == -0.25 && *end == '\0');
    /* Correctly rounded as strtod: the nearest double of 0.1 and of a
     * 17-digit decimal. */
    assert_true(ll_parse_double("0.1", NULL) == 0.1);
    assert_true(ll_parse_double("2.2250738585072014e-308", NULL) == 2.2250738585072014e-308);
    /* The locale's own decimal comma is not a decimal point here. */
    assert_true(ll_parse_double("0,5", &end) == 0.0 && *end == ',');
    /* Nothing parsed: end = text. */
    {
        const char *text = "abc";
        assert_true(ll_parse_double(text, &end) == 0.0 && end == text);
    }
    /* The calling thread's locale is back afterwards. */
    assert_true(comma_locale_active());
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void material_and_spectra_under_comma_locale(void **state)
{
    char path[700];
    ll_material *m = NULL;
    ll_metal_ior ior;
    ll_build_estimate est = LL_BUILD_ESTIMATE_INIT;
    (void)state;
    /* A metal's spectra with decimal points, as the ior files are. */
    snprintf(path, sizeof path, "%s/Xm.eta.spd", ll_test_dir());
    write_text(path, "# lambda(nm) n\n380.0 0.25\n550.5 0.50\n780.0 0.75\n");
    snprintf(path, sizeof path, "%s/Xm.k.spd", ll_test_dir());
    write_text(path, "380.0 3.5\n550.5 3.5\n780.0 3.5\n");
    if (ll_metal_ior_from_dir(ll_test_dir(), "Xm", &ior) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    /* k is 3.5 at every wavelength: each channel's average is 3.5 (read as
     * 3 under the comma locale before the fix, or refused). */
    assert_true(fabs(ior.k_y - 3.5) < 1e-9);
    assert_true(ior.eta_y > 0.25 && ior.eta_y < 0.75);

    setenv("LAYERLAB_IOR_DIR", ll_test_dir(), 1);
    if (ll_material_parse("set error=1.5e-3\n"
                          "dielectric eta=1.5 alpha=0.25\n"
                          "medium albedo=0.5,0.25,0.125 tau=0.75 g=0.5\n"
                          "conductor eta=Xm alpha=0.1\n",
                          "locale.layers", &m) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    assert_int_equal(ll_material_word_count(m), 3);
    /* The JSON description written into files keeps its decimal points. */
    if (!strstr(m->metadata, "\"tau\": 0.75") || !strstr(m->metadata, "\"g\": 0.5"))
        fail_msg("metadata: %s", m->metadata);
    assert_int_equal(ll_material_estimate(m, NULL, &est, NULL), LL_OK);
    assert_int_equal(est.n_channels, 3);
    ll_material_destroy(m);
    unsetenv("LAYERLAB_IOR_DIR");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(parse_double_ignores_locale),
        cmocka_unit_test(material_and_spectra_under_comma_locale),
    };
    return cmocka_run_group_tests_name("locale", tests, setup, teardown);
}
