/*
 * The table writer's nodes beyond the horizon (bsdf_write_tables_horizon.c)
 * at grazing viewers, where the sample grid's cells cross the horizon:
 *  - per channel: a coat of alpha 0.15 over gold of alpha 0.4, whose blue
 *    lobe parts from the luminance's towards grazing, holds every channel's
 *    reflected albedo to the source's at three of the writer's grazing
 *    slices and at 85 degrees (within 0.2%; one factor for all channels,
 *    from the luminance, left blue up to 4.1% high and red 1.2% low);
 *  - the reflected sets of a transmissive file: rough glass's reflection
 *    at 85 degrees from above and from below (stored as 0 beyond the
 *    horizon: 0.8% and 0.5% low).
 * Both files' albedo by the same quadrature of eval (ll_tables_albedo,
 * about 1e-4 of a lobe), the figure the writer's tolerance measures.
 */
#include "test_bsdf_util.h"
#include "tables_build.h"
#include "writer/bsdf_write_tables.h"

/* The reflected (r) and transmitted (t) albedo of b for a viewer at
 * elevation th (below the surface if bottom), eta the source's index. */
static void albedo_at(const ll_bsdf *b, double eta, int transmissive, double th, int bottom,
                      double r[3], double t[3])
{
    double wo[3] = { sin(th), 0.0, bottom ? -cos(th) : cos(th) }, peak[2];
    double st = sin(th) * (bottom ? eta : 1.0 / eta);
    peak[0] = th;
    peak[1] = st < 1.0 ? asin(st) : LL_PI / 2.0;
    assert_int_equal(ll_tables_albedo(b, wo, peak, transmissive, r, t), LL_OK);
}

/* The worst |table / source - 1| of the reflected albedo over the channels
 * at viewer elevation deg (degrees). */
static double worst_r(const ll_bsdf *src, const ll_bsdf *tab, double deg, int bottom,
                      const char *label)
{
    double th = deg * LL_PI / 180.0, rs[3], ts[3], rt[3], tt[3], worst = 0.0;
    int transmissive = ll_tables_transmits(src), c;
    albedo_at(src, src->eta, transmissive, th, bottom, rs, ts);
    albedo_at(tab, src->eta, transmissive, th, bottom, rt, tt);
    for (c = 0; c < 3; ++c)
        worst = fmax(worst, fabs(rt[c] / rs[c] - 1.0));
    printf("%s, viewer %.2f deg%s: R table / source %.5f %.5f %.5f\n", label, deg,
           bottom ? " from below" : "", rt[0] / rs[0], rt[1] / rs[1], rt[2] / rs[2]);
    return worst;
}

/* Coated gold at 32 x 64^2 x 64^2: the writer's elevations are 90 sin(90 v)
 * degrees, v = t / 31; slices 23..25 are 82.7, 84.4 and 85.9 degrees. */
static void test_channels(void **state)
{
    char bsdf_path[LL_TEST_PATH_SIZE], tab_path[LL_TEST_PATH_SIZE];
    ll_bsdf *src = NULL, *tab = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    double worst = 0.0;
    int s;
    (void)state;
    o.n_theta_i = 32;
    o.vndf_size = 64;
    o.sample_size = 64;
    ll_test_build_tables("dielectric eta=1.5 alpha=0.15\n"
                         "conductor eta=Au alpha=0.4\n",
                         "coated", &o, bsdf_path, tab_path, &src, &tab);
    for (s = 23; s <= 25; ++s)
        worst = fmax(worst, worst_r(src, tab, sin(s / 31.0 * LL_PI / 2) * 90.0, 0, "coated"));
    worst = fmax(worst, worst_r(src, tab, 85.0, 0, "coated"));
    printf("coated: worst %.3f%%\n", 100.0 * worst);
    assert_true(worst <= 0.005);
    ll_bsdf_release(tab);
    ll_bsdf_release(src);
}

/* Rough glass at 32 x 64^2 x 64^2: its reflection at 85 degrees from
 * above and from below within the tolerance's aim, 0.3%. */
static void test_glass_reflection(void **state)
{
    char bsdf_path[LL_TEST_PATH_SIZE], tab_path[LL_TEST_PATH_SIZE];
    ll_bsdf *src = NULL, *tab = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    double above, below;
    (void)state;
    o.n_theta_i = 32;
    o.vndf_size = 64;
    o.sample_size = 64;
    ll_test_build_tables("dielectric eta=1.5 alpha=0.3 compensate=0\n", "glass", &o,
                         bsdf_path, tab_path, &src, &tab);
    above = worst_r(src, tab, 85.0, 0, "glass");
    below = worst_r(src, tab, 85.0, 1, "glass");
    assert_true(above <= 0.003);
    assert_true(below <= 0.003);
    ll_bsdf_release(tab);
    ll_bsdf_release(src);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_channels),
        cmocka_unit_test(test_glass_reflection),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
