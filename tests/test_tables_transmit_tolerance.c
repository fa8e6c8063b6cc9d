/*
 * Transmissive tables by tolerance (ll_tables.h, slow tier): rough glass
 * (eta 1.5, alpha 0.3, compensate=0: a net interface, the refraction warp),
 * the same glass compensated (examples/frosted-glass.layers, whose
 * reflection from below beyond the critical angle returns nearly all of
 * the light) and a frosted pane (eta 1.5 over 1 / 1.5, alpha 0.3: eta 1 overall, the
 * warp of the z-flipped direction) built to .bsdf files at their default
 * resolution, written as tables with every size chosen by the default
 * tolerance, and a coat over a scattering medium without a base at a given
 * grid, and measured against the .bsdf by tests/tables_lobe_figures.h
 * (R and T apart, both sides, its own pairs). The targets (albedo R and T
 * within 0.3% at 0..85 degrees; f's median, 95th and 99th percentiles at
 * most 0.2%, 1% and 3%) are printed with the figures reached; the
 * assertions hold what the tables reach today: the glass seen from above,
 * the glass's f and the pane's R and f meet the targets; the glass's
 * transmission from below at 60 degrees by this stratified estimate
 * (0.52%: the lobe takes 3% of the samples there, and the
 * estimate of the .bsdf and of the table alike moves by up to 7% from one
 * stratification to another, where quadrature of eval puts the table
 * within 0.2% at these angles) does not, nor do the compensated glass's
 * transmission by this estimate (0.59%) and its f, nor does the coat, and
 * are held to their present figures so that a change that worsens them
 * fails. The pane meets every target.
 */
#include "test_util.h"
#include "tables_lobe_figures.h"
#include "tables_build.h"

#include <sys/stat.h>

typedef struct bounds {
    double r, t, p50, p95, p99;
} bounds;

/* What the tables reach (the glass 64 x 80^2 x 80^2, where the search meets
 * its aims; the frosted glass 64 x 96^2 x 96^2, the largest grid the size
 * cap lets the search take, where it now meets its own aims; the pane 48 x 96^2 x 96^2, where the search
 * meets its aims), with a margin: glass R 0.15%, T 0.51% (0.02% from the
 * top; from below 0.23% at 50 and 0.51% at 60 degrees), median 0.036%, 95th
 * 0.54%, 99th 2.67% (by lobe: reflection above 2.2%, transmission from
 * above 1.7%, reflection below 4.3%, transmission from below 1.7%; at
 * 64 x 96^2 x 96^2, the grid the search took while it counted the pairs by
 * the edge of total internal reflection, and with the reflection from
 * below interpolating the .bsdf's f / F across that edge: R 0.18%, median
 * 0.037%, 95th 0.47%, 99th 2.72%, reflection above 1.6%, transmission from
 * above 1.4%, reflection below 4.9%, transmission from below 1.6%; the
 * reflection below's 99th is the .bsdf's own error by that edge, which
 * tests/test_tables_transmit_edge.c measures against the closed form);
 * frosted glass R 0.20% (was 2.39% from below at 85 degrees
 * before its reflection from below took the D from above), T 0.59% (from
 * above at 60 degrees, 0.53% at 70; see below), median 0.059%, 95th 0.80%, 99th 3.42%
 * (reflection above 2.4%, transmission from above 3.4%, reflection below
 * 5.0%, transmission from below 2.1%; median 0.063%, 95th 1.02%, 99th
 * 3.69%, transmission from above 3.7% and from below 3.5% before its
 * transmitted sets followed the refracted peak: D over the incident
 * elevations from above, wo turned at the refracted direction's rate from
 * below; median 0.074%, 95th 1.08%, 99th
 * 4.01% and reflection below 5.9% before that set's f / F was continued
 * across the edge; 1.24% and 4.13% at the 95th and
 * 99th, transmission 3.8% and 3.9%, before its z-flipped sets were read at
 * the pair turned to each elevation); pane R 0.18% (at 85 degrees), T
 * 0.04%, median 0.097%, 95th 0.61%, 99th 1.55% (reflection 1.45% from
 * above and 1.40% from below, transmission 1.6% and 1.7%), where with its
 * transmitted sets' D on the floor of 0.02 the search stopped at the
 * size cap with T 0.35% (at 80 degrees), median 0.069%, 95th 0.55% and
 * 99th 1.57%; coat over a medium R 2.04% (from below at 30 degrees: this
 * stratified estimate of the .bsdf's R there is 0.94% below its
 * quadrature, the table's 1.0% above; by quadrature the table is within
 * 0.12% from below at 0..85 degrees), T 1.51% (blue, from below at 60
 * degrees; see below), median 0.072%, 95th 0.99%, 99th 3.30% (reflection
 * from above 0.94%, transmission from above 3.1%, reflection from below
 * 4.8%, transmission from below 2.7%; median 0.067%, 95th 1.12%, 99th
 * 4.07%, reflection from above 4.4% before the set from above took the
 * coat's heavier peak),
 * where with its reflection from
 * below warped by its own D and stored over F alone R was 2.16%, median
 * 0.155%, 95th 2.71%, 99th 14.4%, reflection from below 20.1%.
 *
 * T here is the stratified estimate of tl_albedo (192^2 strata), which
 * moves with the sampler's layout of the strata: a z-flipped set samples
 * one of wi's two elevations picked by u[0] (tables_refract.c), and so the
 * frosted glass's T from above at 70 degrees came to 1.0059 of the .bsdf's
 * at 192^2 strata but 0.9990, 0.9997 and 1.0006 at 256^2, 384^2 and 512^2
 * (0.9985, 0.9987, 0.9998, 0.9996 when it sampled the two elevations'
 * blend at one node), and by quadrature of eval (ll_tables_albedo) it is
 * 0.11% low (0.13% before); the coat's blue T from below at 60 degrees
 * 0.9849 at 192^2, 0.9959, 0.9966 and 0.9949 at the others (0.9930,
 * 0.9936, 0.9948, 0.9944 before), 0.41% low by quadrature (0.37%
 * before). These two bounds hold the 192^2 figures. */
#define BOUND_GLASS 0.003, 0.007, 0.001, 0.007, 0.029
#define BOUND_FROSTED 0.004, 0.0075, 0.001, 0.009, 0.037
#define BOUND_PANE 0.002, 0.001, 0.001, 0.007, 0.02
#define BOUND_COAT 0.022, 0.018, 0.001, 0.011, 0.036

/* text's tables by the sizes of o (NULL: chosen by the tolerance). */
static void check(const char *text, const char *name, const ll_tables_options *o,
                  const bounds *at_most)
{
    char bsdf_path[LL_TEST_PATH_SIZE], tab_path[LL_TEST_PATH_SIZE];
    ll_bsdf *src = NULL, *tab = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    struct stat st_b, st_t;
    tl_figures fig;
    ll_test_build_tables(text, name, o, bsdf_path, tab_path, &src, &tab);
    assert_int_equal(ll_bsdf_get_info(tab, &info), LL_OK);
    assert_int_equal(stat(bsdf_path, &st_b), 0);
    assert_int_equal(stat(tab_path, &st_t), 0);
    printf("%s: table %lld bytes, .bsdf %lld bytes; %.160s\n", name, (long long)st_t.st_size,
           (long long)st_b.st_size, strstr(info.metadata, "\"theta_i\""));
    tl_measure(src, tab, info.eta, &fig);
    assert_false(fig.failed);
    tl_print(name, &fig);
    printf("%s: targets R, T 0.3%%, median 0.2%%, 95th 1%%, 99th 3%%: %s\n", name,
           fig.worst_r <= 0.003 && fig.worst_t <= 0.003 && fig.p50 <= 0.002 &&
                   fig.p95 <= 0.01 && fig.p99 <= 0.03
               ? "met"
               : "not met");
    assert_true(fig.worst_r <= at_most->r);
    assert_true(fig.worst_t <= at_most->t);
    assert_true(fig.p50 <= at_most->p50);
    assert_true(fig.p95 <= at_most->p95);
    assert_true(fig.p99 <= at_most->p99);
    ll_bsdf_release(tab);
    ll_bsdf_release(src);
}

static void test_glass(void **state)
{
    const bounds b = { BOUND_GLASS };
    (void)state;
    check("dielectric eta=1.5 alpha=0.3 compensate=0\n", "glass", NULL, &b);
}

/* examples/frosted-glass.layers: the glass above with the compensation
 * on, whose reflection from below beyond the critical angle returns
 * nearly all of the light. */
static void test_frosted(void **state)
{
    const bounds b = { BOUND_FROSTED };
    (void)state;
    check("dielectric eta=1.5 alpha=0.3\n", "frosted", NULL, &b);
}

static void test_pane(void **state)
{
    const bounds b = { BOUND_PANE };
    (void)state;
    check("dielectric eta=1.5 alpha=0.3\ndielectric eta=0.6666667 alpha=0.3\n", "pane", NULL,
          &b);
}

/* A coat over a scattering medium without a base: the light the medium
 * sends back leaves where no refraction half vector leads, so its
 * transmitted sets take the warp of the z-flipped direction. At the grid
 * the others reach, given (the search would take a larger one: the .bsdf
 * is 17.7 MB). */
static void test_coat_over_medium(void **state)
{
    const bounds b = { BOUND_COAT };
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    (void)state;
    o.n_theta_i = 64;
    o.vndf_size = 96;
    o.sample_size = 96;
    check("dielectric eta=1.5 alpha=0.3\nmedium albedo=0.8,0.6,0.4 g=0.5 tau=0.5\n", "coat", &o,
          &b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_glass),
        cmocka_unit_test(test_frosted),
        cmocka_unit_test(test_pane),
        cmocka_unit_test(test_coat_over_medium),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
