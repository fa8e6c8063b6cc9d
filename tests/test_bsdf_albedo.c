/*
 * ll_bsdf_albedo: the reflected and transmitted albedo of a file agree with
 * the mean of ll_bsdf_sample's weights f |mu_o| / pdf split by the side of
 * mu_o (a stratified grid of u, so the mean is accurate to well below the
 * tolerance), and with the albedo of the layers the file was written from
 * (what llbuild's summary prints), per colour channel, for a transmissive
 * pane (eta 1 in its header) and a coloured opaque stack; table files and
 * bad arguments are refused.
 */
#include "test_bsdf_util.h"
#include "layerlab/ll_material.h"

/* u[1] picks mu_o and so the side: its grid is fine enough that the
 * split lands within 1e-4 of the CDF's; u[0] picks the azimuth. */
#define GRID_MU 20000
#define GRID_PHI 24

static char g_dir[512];

typedef struct built {
    ll_bsdf *file;
    ll_layer *layers[3];
    size_t n_channels;
} built;

static void build(const char *text, const char *name, built *out)
{
    char path[600];
    ll_material *m = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    const ll_layer *ls[3];
    ll_bsdf_write_options wo = LL_BSDF_WRITE_OPTIONS_INIT;
    size_t c;
    memset(out, 0, sizeof *out);
    o.n_nodes = 100;
    o.n_orders = 40;
    assert_int_equal(ll_material_parse(text, name, &m), LL_OK);
    assert_int_equal(ll_material_build_layers(m, &o, NULL, out->layers, &out->n_channels, &header),
                     LL_OK);
    snprintf(path, sizeof path, "%s/%s.bsdf", g_dir, name);
    for (c = 0; c < out->n_channels; ++c)
        ls[c] = out->layers[c];
    wo = header;
    wo.error_goal = 1e-6;
    if (ll_bsdf_write(path, ls, out->n_channels, &wo, NULL) != LL_OK ||
        ll_bsdf_open(path, NULL, &out->file) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    ll_material_destroy(m);
}

static void release(built *b)
{
    size_t c;
    for (c = 0; c < b->n_channels; ++c)
        ll_layer_destroy(b->layers[c]);
    ll_bsdf_release(b->file);
}

/* The sample-weight means, reflected and transmitted, over a grid of
 * cell midpoints in u. */
static void sample_mean(const ll_bsdf *b, double mu_i, double R[3], double T[3])
{
    int i, j, c;
    for (c = 0; c < 3; ++c)
        R[c] = T[c] = 0.0;
    for (i = 0; i < GRID_PHI; ++i)
        for (j = 0; j < GRID_MU; ++j) {
            double u[2] = { (i + 0.5) / GRID_PHI, (j + 0.5) / GRID_MU }, mu_o, phi, pdf, f[3];
            assert_int_equal(ll_bsdf_sample(b, mu_i, u, NULL, &mu_o, &phi, &pdf, f), LL_OK);
            if (!(pdf > 0.0))
                continue;
            for (c = 0; c < 3; ++c) {
                double w = f[c] * fabs(mu_o) / pdf / ((double)GRID_PHI * GRID_MU);
                if ((mu_o < 0.0) == (mu_i > 0.0))
                    R[c] += w;
                else
                    T[c] += w;
            }
        }
}

static void check(const char *text, const char *name, int transmits)
{
    /* llbuild's summary angles (0, 30, 60, 80 degrees) and light from below. */
    static const double mus[] = { 1.0, 0.8660254, 0.5, 0.1736482, -0.7 };
    built b;
    size_t k;
    int c;
    build(text, name, &b);
    for (k = 0; k < sizeof mus / sizeof mus[0]; ++k) {
        double R[3], T[3], sR[3], sT[3], lR[3] = { 0 }, lT[3] = { 0 };
        assert_int_equal(ll_bsdf_albedo(b.file, mus[k], NULL, R, T), LL_OK);
        sample_mean(b.file, mus[k], sR, sT);
        for (c = 0; c < (int)b.n_channels; ++c)
            assert_int_equal(ll_layer_albedo(b.layers[c], mus[k], &lR[c], &lT[c]), LL_OK);
        if (b.n_channels == 1)
            lR[1] = lR[2] = lR[0], lT[1] = lT[2] = lT[0];
        for (c = 0; c < 3; ++c) {
            if (fabs(R[c] - sR[c]) > 1e-3 || fabs(T[c] - sT[c]) > 1e-3 ||
                fabs(R[c] - lR[c]) > 1e-3 || fabs(T[c] - lT[c]) > 1e-3)
                fail_msg("%s mu_i %g channel %d: albedo R %.5f T %.5f, sample mean R %.5f "
                         "T %.5f, layer R %.5f T %.5f",
                         name, mus[k], c, R[c], T[c], sR[c], sT[c], lR[c], lT[c]);
        }
        if (transmits)
            assert_true(T[1] > 0.3);
        else
            assert_true(T[1] < 1e-6);
    }
    /* Either output may be NULL; the results do not change. */
    {
        double R[3], T[3], R2[3], T2[3];
        assert_int_equal(ll_bsdf_albedo(b.file, 0.5, NULL, R, T), LL_OK);
        assert_int_equal(ll_bsdf_albedo(b.file, 0.5, NULL, R2, NULL), LL_OK);
        assert_int_equal(ll_bsdf_albedo(b.file, 0.5, NULL, NULL, T2), LL_OK);
        assert_int_equal(ll_bsdf_albedo(b.file, 0.5, NULL, NULL, NULL), LL_OK);
        for (c = 0; c < 3; ++c) {
            assert_true(R[c] == R2[c]);
            assert_true(T[c] == T2[c]);
        }
    }
    release(&b);
}

static void pane(void **state)
{
    (void)state;
    check("dielectric eta=1.5 alpha=0.3\ndielectric eta=0.6666667 alpha=0.3\n", "pane", 1);
}

static void coloured_opaque(void **state)
{
    (void)state;
    check("dielectric eta=1.5 alpha=0.2\ndiffuse albedo=0.2,0.5,0.8\n", "coloured", 0);
}

static void refusals(void **state)
{
    double R[3] = { 1, 1, 1 }, T[3] = { 1, 1, 1 };
    ll_bsdf *golden = NULL;
    (void)state;
    assert_int_equal(ll_bsdf_albedo(NULL, 0.5, NULL, R, T), LL_ERROR_INVALID_ARGUMENT);
    assert_true(R[0] == 0.0 && T[2] == 0.0);
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &golden), LL_OK);
    assert_int_equal(ll_bsdf_albedo(golden, NAN, NULL, R, T), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_albedo(golden, 0.5, NULL, R, T), LL_OK);
    assert_true(R[0] > 0.1 && R[0] < 1.0 && T[0] == 0.0);
    ll_bsdf_release(golden);
}

static int setup(void **state)
{
    (void)state;
    ll_test_mkdtemp(g_dir, sizeof g_dir);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    ll_test_rmdir(g_dir);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(pane),
        cmocka_unit_test(coloured_opaque),
        cmocka_unit_test(refusals),
    };
    return cmocka_run_group_tests_name("bsdf_albedo", tests, setup, teardown);
}
