/*
 * The material language: every word and setting, and every error with its
 * file:line:column and what was expected.
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
#include "material/word_table.h"
#include "words/microfacet.h"

/* Parse text that must fail with LL_ERROR_PARSE and a message that starts
 * with `where` and contains `what`. */
static void expect_error(const char *text, const char *where, const char *what)
{
    ll_material *m = (ll_material *)1;
    ll_status s = ll_material_parse(text, "t", &m);
    const char *msg = ll_last_error_message();
    if (s != LL_ERROR_PARSE || strncmp(msg, where, strlen(where)) != 0 || !strstr(msg, what))
        fail_msg("for\n%s\nexpected status %d and \"%s ... %s\", got %d: \"%s\"", text,
                 LL_ERROR_PARSE, where, what, s, msg);
    assert_null(m);
}

static ll_material *parse_ok(const char *text)
{
    ll_material *m = NULL;
    ll_status s = ll_material_parse(text, "t", &m);
    if (s != LL_OK)
        fail_msg("for\n%s\ngot %d: %s", text, s, ll_last_error_message());
    assert_non_null(m);
    return m;
}

/* ------------------------------------------------------------ the words */

static void every_word_parses(void **state)
{
    ll_material *m;
    ll_word_params p;
    (void)state;
    m = parse_ok("# rough gold under a rough clear coat holding a thin blue-scattering layer\n"
                 "dielectric  eta=1.5 alpha=0.1\n"
                 "medium      albedo=0.25,0.0,0.95 g=0.5 tau=0.5\n"
                 "conductor   eta=Au alpha=0.1\n");
    assert_int_equal(ll_material_word_count(m), 3);
    assert_true(ll_material_is_rgb(m));
    assert_true(ll_material_is_opaque(m));
    assert_int_equal(m->words[1].choice, LL_PHASE_HG);
    /* Blue channel of the medium. */
    ll_word_params_get(m, 1, 2, 3, &p);
    assert_float_equal(p.v[LL_MEDIUM_ALBEDO], 0.95, 0.0);
    assert_float_equal(p.v[LL_MEDIUM_SHAPE], 0.5, 0.0);
    assert_float_equal(p.v[LL_MEDIUM_TAU], 0.5, 0.0);
    /* The gold sits under the coat: its index relative to the coat. */
    ll_word_params_get(m, 2, 0, 3, &p);
    assert_float_equal(p.v[LL_CONDUCTOR_ETA], m->words[2].metal_ior.eta[0] / 1.5, 1e-15);
    assert_float_equal(p.v[LL_CONDUCTOR_K], m->words[2].metal_ior.k[0] / 1.5, 1e-15);
    assert_non_null(strstr(m->metadata, "\"name\": \"Au\""));
    assert_non_null(strstr(m->metadata, "\"type\": \"medium\""));
    ll_material_destroy(m);

    m = parse_ok("diffuse albedo=0.5");
    assert_false(ll_material_is_rgb(m));
    ll_word_params_get(m, 0, 0, 1, &p);
    assert_ptr_equal(p.desc, &ll_word_diffuse);
    assert_float_equal(p.v[LL_DIFFUSE_ALBEDO], 0.5, 0.0);
    ll_material_destroy(m);

    m = parse_ok("medium albedo=0.9 tau=2 phase=vmf kappa=3\nmedium albedo=1 tau=0.5\n"
                 "medium albedo=1 tau=0 phase=isotropic\nmedium albedo=0.3 tau=1 phase=hg g=-0.3");
    assert_int_equal(m->words[0].choice, LL_PHASE_VMF);
    assert_int_equal(m->words[1].choice, LL_PHASE_ISOTROPIC);
    assert_int_equal(m->words[2].choice, LL_PHASE_ISOTROPIC);
    assert_int_equal(m->words[3].choice, LL_PHASE_HG);
    assert_false(ll_material_is_opaque(m));
    ll_material_destroy(m);
}

/* dist=beckmann|ggx on the interfaces: the word's choice, carried by its
 * parameters (which tell two words apart by it), and in the metadata only
 * when given, so a file without it describes what it always did. */
static void interface_distribution(void **state)
{
    ll_material *m;
    ll_word_params p, q;
    (void)state;
    m = parse_ok("dielectric eta=1.5 alpha=0.1 dist=ggx\n"
                 "dielectric eta=1.2 alpha=0.2 dist=beckmann\n"
                 "conductor eta=Au alpha=0.3 dist=ggx compensate=0\n");
    assert_int_equal(m->words[0].choice, LL_DISTRIBUTION_GGX);
    assert_int_equal(m->words[1].choice, LL_DISTRIBUTION_BECKMANN);
    assert_int_equal(m->words[2].choice, LL_DISTRIBUTION_GGX);
    ll_word_params_get(m, 0, 0, 1, &p);
    assert_int_equal(p.choice, LL_DISTRIBUTION_GGX);
    ll_word_params_get(m, 2, 1, 3, &p);
    assert_int_equal(p.choice, LL_DISTRIBUTION_GGX);
    assert_float_equal(p.v[LL_CONDUCTOR_ALPHA], 0.3, 0.0);
    assert_non_null(strstr(m->metadata, "\"alpha\": 0.10000000000000001, \"dist\": \"ggx\""));
    assert_non_null(strstr(m->metadata, "\"dist\": \"beckmann\""));
    assert_non_null(strstr(m->metadata, "\"compensate\": 0, \"dist\": \"ggx\""));
    ll_material_destroy(m);

    /* The default is Beckmann, and says nothing. */
    m = parse_ok("dielectric eta=1.5 alpha=0.1\nconductor eta=Au alpha=0.3\n");
    assert_int_equal(m->words[0].choice, LL_DISTRIBUTION_BECKMANN);
    assert_int_equal(m->words[1].choice, LL_DISTRIBUTION_BECKMANN);
    assert_null(strstr(m->metadata, "dist"));
    ll_word_params_get(m, 0, 0, 1, &p);
    ll_material_destroy(m);
    m = parse_ok("dielectric eta=1.5 alpha=0.1 dist=ggx\n");
    ll_word_params_get(m, 0, 0, 1, &q);
    assert_false(ll_word_params_equal(&p, &q));
    ll_material_destroy(m);

    /* Sweeps over a GGX alpha. */
    m = parse_ok("dielectric eta=1.5 alpha=[0.05 0.1 0.3] dist=ggx\nconductor eta=Au alpha=0.2\n");
    assert_int_equal(ll_material_basis_count(m), 3);
    assert_int_equal(m->words[0].choice, LL_DISTRIBUTION_GGX);
    ll_material_destroy(m);

    expect_error("dielectric eta=1.5 alpha=0.1 dist=phong", "t:1:35: ",
                 "unknown microfacet distribution 'phong'; expected beckmann or ggx");
    expect_error("conductor eta=Au alpha=0.1 dist=ggx dist=ggx", "t:1:37: ", "dist is given twice");
    expect_error("diffuse albedo=0.5 dist=ggx", "t:1:20: ", "dist");
}

/* The table of words is complete: every descriptor has its hooks, unique
 * keys, and its example line parses (as the messages quote it) and builds
 * a resolution; only a measured BRDF needs a file that is not here. */
static void word_table_is_complete(void **state)
{
    size_t i, j, k;
    (void)state;
    assert_true(ll_word_table_size >= 5);
    for (i = 0; i < ll_word_table_size; ++i) {
        const ll_word_desc *d = ll_word_table[i];
        ll_material *m = NULL;
        size_t n, o, c;
        ll_status s;
        assert_non_null(d->name);
        assert_non_null(d->example);
        assert_non_null(d->stage);
        assert_non_null(d->channel);
        assert_non_null(d->resolution);
        assert_non_null(d->cost);
        assert_non_null(d->build);
        assert_non_null(d->metadata);
        assert_int_equal(strncmp(d->example, d->name, strlen(d->name)), 0);
        for (j = 0; j < i; ++j)
            assert_string_not_equal(ll_word_table[j]->name, d->name);
        for (j = 0; j < LL_WORD_MAX_PARAMS && d->params[j].key; ++j) {
            const ll_param_desc *p = &d->params[j];
            assert_true(p->parse || (p->slot >= 0 && p->slot < LL_WORD_MAX_NUMBERS));
            assert_true(p->parse || p->why);
            for (k = 0; k < j; ++k)
                assert_string_not_equal(d->params[k].key, p->key);
        }
        s = ll_material_parse(d->example, "t", &m);
        if (d == &ll_word_measured) {
            assert_int_equal(s, LL_ERROR_PARSE);
            assert_non_null(strstr(ll_last_error_message(), "file: "));
            continue;
        }
        if (s != LL_OK)
            fail_msg("%s: %s", d->example, ll_last_error_message());
        assert_ptr_equal(m->words[0].desc, d);
        assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &o, &c), LL_OK);
        assert_true(n >= 10 && o >= 1);
        ll_material_destroy(m);
    }
}

/* Conductor indices: a name, complex numbers, or n with k. */
static void conductor_index_forms(void **state)
{
    ll_material *m;
    ll_word_params p;
    (void)state;
    m = parse_ok("conductor eta=0.2+3.9i alpha=0.2");
    assert_false(ll_material_is_rgb(m));
    ll_word_params_get(m, 0, 0, 1, &p);
    assert_float_equal(p.v[LL_CONDUCTOR_ETA], 0.2, 0.0);
    assert_float_equal(p.v[LL_CONDUCTOR_K], 3.9, 0.0);
    ll_material_destroy(m);

    m = parse_ok("conductor eta=0.2+3.9i,0.4+2.4e0i,1.4+1.6i alpha=0.2");
    assert_true(ll_material_is_rgb(m));
    ll_word_params_get(m, 0, 1, 3, &p);
    assert_float_equal(p.v[LL_CONDUCTOR_ETA], 0.4, 0.0);
    assert_float_equal(p.v[LL_CONDUCTOR_K], 2.4, 0.0);
    ll_material_destroy(m);

    m = parse_ok("conductor eta=0.2,0.4,1.4 k=3.9 alpha=0.2");
    ll_word_params_get(m, 0, 2, 3, &p);
    assert_float_equal(p.v[LL_CONDUCTOR_ETA], 1.4, 0.0);
    assert_float_equal(p.v[LL_CONDUCTOR_K], 3.9, 0.0);
    ll_material_destroy(m);

    /* Monochrome: the named metal's luminance averages. */
    m = parse_ok("set channels=mono\nconductor eta=Cu alpha=0.3");
    ll_word_params_get(m, 0, 0, 1, &p);
    assert_float_equal(p.v[LL_CONDUCTOR_ETA], m->words[0].metal_ior.eta_y, 0.0);
    assert_float_equal(p.v[LL_CONDUCTOR_K], m->words[0].metal_ior.k_y, 0.0);
    ll_material_destroy(m);
}

/* A monochrome build of three-valued numbers uses their luminance. */
static void mono_uses_luminance(void **state)
{
    ll_material *m = parse_ok("diffuse albedo=0.2,0.4,0.8");
    ll_word_params p;
    (void)state;
    ll_word_params_get(m, 0, 0, 1, &p);
    assert_float_equal(p.v[LL_DIFFUSE_ALBEDO], 0.212671 * 0.2 + 0.715160 * 0.4 + 0.072169 * 0.8, 1e-15);
    ll_material_destroy(m);
}

/* Comments, blank lines, tabs, CRLF, quoted values. */
static void layout_is_free(void **state)
{
    ll_material *m = parse_ok("\r\n  # top\r\n\tdielectric\teta=1.5   alpha=0.1 # coat\r\n\r\n"
                              "diffuse albedo=\"0.5\"#no space needed\r\n");
    (void)state;
    assert_int_equal(ll_material_word_count(m), 2);
    assert_int_equal(m->words[0].line, 3);
    assert_int_equal(m->words[0].column, 2);
    assert_int_equal(m->words[1].line, 5);
    ll_material_destroy(m);
}

static void settings_are_read(void **state)
{
    ll_material *m = parse_ok("set nodes=40 orders=12\nset channels=3 error=1e-4\n"
                              "diffuse albedo=0.5");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    size_t n, k, c;
    (void)state;
    assert_int_equal(m->nodes, 40);
    assert_int_equal(m->orders, 12);
    assert_int_equal(m->channels, 3);
    assert_float_equal(m->error_goal, 1e-4, 0.0);
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(n, 40);
    assert_int_equal(k, 12);
    assert_int_equal(c, 3);
    /* Options override the file. */
    o.n_nodes = 20;
    o.n_orders = 4;
    o.n_channels = 1;
    assert_int_equal(ll_material_resolution(m, &o, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(n, 20);
    assert_int_equal(k, 4);
    assert_int_equal(c, 1);
    o.n_nodes = 21;
    assert_int_equal(ll_material_resolution(m, &o, NULL, &n, &k, &c), LL_ERROR_INVALID_ARGUMENT);
    o.n_nodes = 20;
    o.struct_size = 3;
    assert_int_equal(ll_material_resolution(m, &o, NULL, &n, &k, &c), LL_ERROR_INVALID_ARGUMENT);
    ll_material_destroy(m);
}

/* Without settings: the largest resolution any word's search asks for. */
static void resolution_defaults_to_the_heuristics(void **state)
{
    ll_material *m = parse_ok("dielectric eta=1.5 alpha=0.1\nmedium albedo=0.5 g=0.8 tau=1\n"
                              "diffuse albedo=0.5");
    size_t n, k, c, hn, hk, gn, gk;
    (void)state;
    assert_int_equal(ll_test_search_microfacet(0.1, 1.5, 0.0, 0.0, 0.0, &hn, &hk, NULL), LL_OK);
    assert_int_equal(ll_resolution_search_henyey_greenstein(0.8, 0.0, 0.0, NULL, &gn, &gk, NULL),
                     LL_OK);
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(n, hn > gn ? hn : gn);
    assert_int_equal(k, hk > gk ? hk : gk);
    assert_int_equal(c, 1);
    ll_material_destroy(m);
}

/* The header: eta(bottom)/eta(top) of a transmissive stack, 1 if opaque;
 * roughness of the top and bottom interfaces. */
static void header_follows_the_stack(void **state)
{
    ll_material *m;
    double eta, alpha[2];
    (void)state;
    m = parse_ok("dielectric eta=1.5 alpha=0.3");
    ll_material_header(m, 1, &eta, alpha);
    assert_float_equal(eta, 1.5, 0.0);
    assert_float_equal(alpha[0], 0.3, 0.0);
    assert_float_equal(alpha[1], 0.3, 0.0);
    ll_material_destroy(m);

    m = parse_ok("dielectric eta=1.5 alpha=0.1\nmedium albedo=0.5 tau=1\n"
                 "dielectric eta=0.8 alpha=0.2");
    ll_material_header(m, 1, &eta, alpha);
    assert_float_equal(eta, 1.2, 1e-15);
    assert_float_equal(alpha[0], 0.1, 0.0);
    assert_float_equal(alpha[1], 0.2, 0.0);
    ll_material_destroy(m);

    m = parse_ok("dielectric eta=1.5 alpha=0.1\nconductor eta=Au alpha=0.25");
    ll_material_header(m, 3, &eta, alpha);
    assert_float_equal(eta, 1.0, 0.0);
    assert_float_equal(alpha[0], 0.1, 0.0);
    assert_float_equal(alpha[1], 0.25, 0.0);
    ll_material_destroy(m);

    m = parse_ok("medium albedo=0.5 tau=1\ndiffuse albedo=0.5");
    ll_material_header(m, 1, &eta, alpha);
    assert_float_equal(eta, 1.0, 0.0);
    assert_float_equal(alpha[0], 0.0, 0.0);
    ll_material_destroy(m);
}

/* --------------------------------------------------------------- errors */

static void stack_errors(void **state)
{
    (void)state;
    expect_error("dielectric eta=1.5 alpha=0.1\nconductor eta=Au alpha=0.1\n"
                 "medium albedo=0.5 tau=1\n",
                 "t:2:1: ", "conductor is opaque");
    expect_error("  diffuse albedo=0.5\ndiffuse albedo=0.5", "t:1:3: ", "must be the bottom");
    expect_error("medium albedo=0.5", "t:1:1: ", "medium needs tau=");
    expect_error("medium tau=0.5", "t:1:1: ", "medium needs albedo=");
    expect_error("dielectric eta=1.5", "t:1:1: ", "needs alpha=");
    expect_error("", "t:1:1: ", "no layers");
    expect_error("# nothing\n\n   # at all\n", "t:4:1: ", "no layers");
    expect_error("set nodes=20\n", "t:2:1: ", "no layers");
}

static void value_errors(void **state)
{
    (void)state;
    expect_error("dielectric eta=1.5 alpha=0", "t:1:26: ", "alpha=0 is out of range");
    expect_error("dielectric eta=1.5 alpha=-0.2", "t:1:26: ", "must be >= 0.001 (LL_MICROFACET_MIN_ALPHA");
    expect_error("dielectric eta=1.5 alpha=0.0001", "t:1:26: ", "0.001");
    expect_error("diffuse albedo=1.5", "t:1:16: ", "in [0, 1]");
    expect_error("diffuse albedo=0.5,1.2,0.3", "t:1:16: ", "albedo=1.2 is out of range");
    expect_error("diffuse albedo=-0.1", "t:1:16: ", "out of range");
    expect_error("diffuse albedo=0.5,0.2", "t:1:16: ", "one value or three");
    expect_error("diffuse albedo=0.5,0.2,0.1,0.1", "t:1:16: ", "one value or three");
    expect_error("diffuse albedo=abc", "t:1:16: ", "is not a number");
    expect_error("diffuse albedo=0.5,x,0.2", "t:1:20: ", "'x' is not a number");
    expect_error("diffuse albedo=nan", "t:1:16: ", "not a number");
    expect_error("diffuse albedo=inf", "t:1:16: ", "not a number");
    expect_error("diffuse albedo=0x1p-1", "t:1:16: ", "not a number");
    expect_error("diffuse albedo=1e999", "t:1:16: ", "not a number");
    expect_error("diffuse albedo=", "t:1:16: ", "has no value");
    expect_error("dielectric eta=1 alpha=0.1", "t:1:16: ", "eta=1 is no interface");
    expect_error("dielectric eta=-1.5 alpha=0.1", "t:1:16: ", "must be > 0");
    expect_error("medium albedo=0.5 tau=-1", "t:1:23: ", "tau");
    expect_error("medium albedo=0.5 tau=1 g=1", "t:1:27: ", "(-1, 1)");
    expect_error("medium albedo=0.5 tau=1 g=-1", "t:1:27: ", "(-1, 1)");
    expect_error("medium albedo=0.5 tau=1 phase=vmf kappa=-2", "t:1:41: ", "kappa");
    expect_error("conductor eta=0.2+0i alpha=0.1", "t:1:15: ", "must be > 0");
    expect_error("conductor eta=0.2+3.9j alpha=0.1", "t:1:15: ", "not a complex index");
    expect_error("conductor eta=-0.2+3.9i alpha=0.1", "t:1:15: ", "must be > 0");
    expect_error("conductor eta=0.2 k=0 alpha=0.1", "t:1:21: ", "k must be > 0");
    expect_error("set nodes=15\ndiffuse albedo=0.5", "t:1:11: ", "even");
    expect_error("set nodes=many\ndiffuse albedo=0.5", "t:1:11: ", "whole number");
    expect_error("set orders=0\ndiffuse albedo=0.5", "t:1:12: ", "at least 1");
    expect_error("set channels=2\ndiffuse albedo=0.5", "t:1:14: ", "1 (mono) or 3 (rgb)");
    expect_error("set error=2\ndiffuse albedo=0.5", "t:1:11: ", "(0, 1)");
    expect_error("set nodes=10 nodes=20\ndiffuse albedo=0.5", "t:1:14: ", "set twice");
    expect_error("set colour=red\ndiffuse albedo=0.5", "t:1:5: ", "no setting 'colour'");
}

static void syntax_errors(void **state)
{
    (void)state;
    expect_error("   plastic albedo=0.5", "t:1:4: ", "unknown word 'plastic'");
    /* A typing mistake gets the word it was likely meant to be; a word
     * like no other gets the list alone. */
    expect_error("dielectirc eta=1.5 alpha=0.1", "t:1:1: ",
                 "unknown word 'dielectirc'; did you mean 'dielectric'?");
    expect_error("difuse albedo=0.5", "t:1:1: ", "did you mean 'diffuse'?");
    expect_error("Conductr eta=Au alpha=0.1", "t:1:1: ", "did you mean 'conductor'?");
    expect_error("sett nodes=10\ndiffuse albedo=0.5", "t:1:1: ", "did you mean 'set'?");
    expect_error("   plastic albedo=0.5", "t:1:4: ", "expected diffuse, dielectric");
    expect_error("diffuse color=0.5", "t:1:9: ", "diffuse has no parameter 'color'");
    expect_error("diffuse albedo", "t:1:9: ", "expected key=value");
    expect_error("diffuse =0.5", "t:1:9: ", "expected key=value");
    expect_error("diffuse Albedo=0.5", "t:1:9: ", "not a parameter name");
    expect_error("diffuse albedo=0.5 albedo=0.2", "t:1:20: ", "given twice");
    expect_error("medium albedo=0.5 tau=1 phase=vmf", "t:1:1: ", "needs kappa");
    expect_error("medium albedo=0.5 tau=1 kappa=2", "t:1:1: ", "kappa= needs phase=vmf");
    expect_error("medium albedo=0.5 tau=1 phase=isotropic g=0.3", "t:1:1: ", "phase=hg");
    expect_error("medium albedo=0.5 tau=1 phase=hg", "t:1:1: ", "needs g");
    expect_error("medium albedo=0.5 tau=1 phase=mie", "t:1:31: ", "unknown phase function");
    expect_error("medium albedo=0.5 tau=1 phase=hg phase=hg g=0", "t:1:34: ", "twice");
    expect_error("conductor eta=0.2 alpha=0.1", "t:1:1: ", "absorbing index");
    expect_error("conductor eta=Xx alpha=0.1", "t:1:15: ", "unknown metal 'Xx'");
    expect_error("conductor eta=Au k=3 alpha=0.1", "t:1:18: ", "already gives the metal's k");
    expect_error("conductor k=3 eta=Au alpha=0.1", "t:1:19: ", "k= is given already");
    expect_error("conductor eta=0.2+3i k=3 alpha=0.1", "t:1:22: ", "given already");
    expect_error("measured file=\"abc", "t:1:15: ", "unterminated quote");
    expect_error("measured file=/nonexistent/gold.binary", "t:1:15: ", "cannot open");
    expect_error("measured", "t:1:1: ", "measured needs file=");
    expect_error("dielectric eta=1.5 alpha=0.1\n\n  diffuse albedo=0.5 albedo=2",
                 "t:3:22: ", "given twice");
}

/* A measured word: the file is checked while parsing, and relative paths in
 * a file resolve against the file's directory. */
static void measured_paths_resolve_against_the_file(void **state)
{
    char dir[] = "/tmp/ll_mat_XXXXXX", path[128], cmd[160];
    FILE *f;
    ll_material *m = NULL;
    unsigned char header[12] = { 1, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0 };
    double values[6] = { 1500, 1500, 1500, 1500, 1500, 1500 };
    (void)state;
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/tiny.binary", dir);
    f = fopen(path, "wb");
    assert_non_null(f);
    fwrite(header, 1, 12, f);
    fwrite(values, 8, 6, f); /* the test machine is little-endian, as MERL's files */
    fclose(f);
    snprintf(path, sizeof path, "%s/m.layers", dir);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs("dielectric eta=1.5 alpha=0.2\nmeasured file=tiny.binary\n", f);
    fclose(f);
    assert_int_equal(ll_material_parse_file(path, &m), LL_OK);
    assert_true(ll_material_is_rgb(m));
    assert_non_null(strstr(m->words[1].file, "/tiny.binary"));
    assert_int_equal(access(m->words[1].file, R_OK), 0);
    ll_material_destroy(m);
    /* Broken size: the parser says where and why. */
    snprintf(path, sizeof path, "%s/tiny.binary", dir);
    assert_int_equal(truncate(path, 20), 0);
    snprintf(path, sizeof path, "%s/m.layers", dir);
    assert_int_equal(ll_material_parse_file(path, &m), LL_ERROR_PARSE);
    assert_non_null(strstr(ll_last_error_message(), "m.layers:2:15: file: "));
    assert_non_null(strstr(ll_last_error_message(), "bytes"));
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
}

/* Mutated descriptions never crash: each parses or fails with a parse
 * error (run under ASan + UBSan in CI). */
static void mutations_parse_or_fail_cleanly(void **state)
{
    static const char base[] =
        "# comment\nset nodes=20 orders=4 channels=3 error=1e-3\n"
        "dielectric eta=1.5,1.4,1.3 alpha=0.1\nmedium albedo=0.2,0.5,0.9 tau=1 phase=vmf kappa=2\n"
        "medium albedo=0.5 tau=0.5 g=0.3\nconductor eta=0.2+3.9i,0.4+2.4i,1.4+1.6i alpha=0.2\n";
    static const char alphabet[] = "=,+-.#\" \t\nie0123456789abcdkgtu";
    char text[sizeof base];
    unsigned long seed = 12345;
    int round, k;
    (void)state;
    for (round = 0; round < 3000; ++round) {
        ll_material *m = NULL;
        ll_status s;
        memcpy(text, base, sizeof base);
        for (k = 0; k < 1 + round % 4; ++k) {
            size_t at;
            seed = seed * 6364136223846793005ul + 1442695040888963407ul;
            at = (size_t)(seed >> 33) % (sizeof base - 1);
            text[at] = alphabet[(seed >> 20) % (sizeof alphabet - 1)];
        }
        s = ll_material_parse(text, "fuzz", &m);
        if (s == LL_OK) {
            assert_non_null(m);
            assert_true(ll_material_word_count(m) >= 1);
        } else {
            assert_int_equal(s, LL_ERROR_PARSE);
            assert_null(m);
            assert_non_null(strstr(ll_last_error_message(), "fuzz:"));
        }
        ll_material_destroy(m);
    }
}

static void api_arguments_are_checked(void **state)
{
    ll_material *m = (ll_material *)1;
    (void)state;
    assert_int_equal(ll_material_parse(NULL, "t", &m), LL_ERROR_INVALID_ARGUMENT);
    assert_null(m);
    assert_int_equal(ll_material_parse("diffuse albedo=1", "t", NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_parse_file(NULL, &m), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_parse_file("/nonexistent.layers", &m), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "/nonexistent.layers"));
    assert_int_equal(ll_material_word_count(NULL), 0);
    ll_material_destroy(NULL);
    /* Messages without a source name. */
    assert_int_equal(ll_material_parse("bogus", NULL, &m), LL_ERROR_PARSE);
    assert_non_null(strstr(ll_last_error_message(), "<material>:1:1: "));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_word_parses),
        cmocka_unit_test(word_table_is_complete),
        cmocka_unit_test(conductor_index_forms),
        cmocka_unit_test(mono_uses_luminance),
        cmocka_unit_test(layout_is_free),
        cmocka_unit_test(settings_are_read),
        cmocka_unit_test(resolution_defaults_to_the_heuristics),
        cmocka_unit_test(header_follows_the_stack),
        cmocka_unit_test(stack_errors),
        cmocka_unit_test(value_errors),
        cmocka_unit_test(syntax_errors),
        cmocka_unit_test(measured_paths_resolve_against_the_file),
        cmocka_unit_test(mutations_parse_or_fail_cleanly),
        cmocka_unit_test(api_arguments_are_checked),
        cmocka_unit_test(interface_distribution),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
