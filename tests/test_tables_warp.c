/*
 * The piecewise-bilinear 2D warp of the `measured` format
 * (src/reader/tables_warp.c): invert is the exact inverse of sample, the
 * density integrates to 1, the density sample reports is the one a
 * histogram of its points shows, and between parameter slices everything
 * is interpolated consistently.
 */
#include "test_util.h"
#include "reader/tables_atan.h"
#include "reader/tables_warp.h"

#include <string.h>

#define W 7
#define H 5
#define P0 2
#define P1 3

static double get_table(const void *ctx, size_t i) { return ((const double *)ctx)[i]; }

/* n positive, lumpy values drawn from rng. */
static void fill_lumpy(double *data, size_t n, uint64_t *rng)
{
    size_t k;
    for (k = 0; k < n; ++k)
        data[k] = 0.05 + ll_test_uniform(rng) * (k % 3 == 0 ? 4.0 : 1.0);
}

/* Sample at u and invert the point: u again (sample clamps u into
 * [2^-24, 1 - 2^-24]), and both densities that of eval at the point. */
static void check_inverse(const ll_warp2d *wp, const double u[2], const double param[2])
{
    double pos[2], back[2], pdf_s, pdf_i;
    ll_warp2d_sample(wp, u, param, pos, &pdf_s);
    ll_warp2d_invert(wp, pos, param, back, &pdf_i);
    assert_true(fabs(back[0] - u[0]) < 1e-7);
    assert_true(fabs(back[1] - u[1]) < 1e-7);
    assert_true(ll_test_close(pdf_s, pdf_i, 1e-9, 1e-12));
    assert_true(ll_test_close(pdf_s, ll_warp2d_eval(wp, pos, param), 1e-9, 1e-12));
}

/* A positive, lumpy table with 2 x 3 slices (parameter 0 outermost). */
static void make(ll_warp2d *wp, int sampling)
{
    static double data[P0 * P1 * H * W];
    static const double p0[P0] = { 0.0, 1.0 }, p1[P1] = { -1.0, 0.5, 2.0 };
    const double *params[2] = { p0, p1 };
    size_t sizes[2] = { P0, P1 };
    uint64_t rng = 12345;
    fill_lumpy(data, P0 * P1 * H * W, &rng);
    assert_int_equal(ll_warp2d_init(wp, W, H, 2, sizes, params, get_table, data, sampling),
                     LL_OK);
}

static void test_invert_of_sample(void **state)
{
    ll_warp2d wp;
    uint64_t rng = 7;
    int k;
    (void)state;
    make(&wp, 1);
    for (k = 0; k < 20000; ++k) {
        double u[2] = { ll_test_uniform(&rng), ll_test_uniform(&rng) };
        double param[2] = { ll_test_uniform(&rng), -1.2 + 3.5 * ll_test_uniform(&rng) };
        check_inverse(&wp, u, param);
    }
    ll_warp2d_free(&wp);
}

/* One value of the first parameter, as an isotropic file's single
 * incident azimuth: every look-up then reads at most two slices, which
 * the warp handles without its general loops; sample and invert must
 * still be each other's inverse, and the density that of eval. */
static void test_two_slices(void **state)
{
    static double data[P1 * H * W];
    static const double p0[1] = { 0.0 }, p1[P1] = { -1.0, 0.5, 2.0 };
    const double *params[2] = { p0, p1 };
    size_t sizes[2] = { 1, P1 }, k;
    uint64_t rng = 4242;
    ll_warp2d wp;
    ll_warp_slices s;
    (void)state;
    fill_lumpy(data, P1 * H * W, &rng);
    assert_int_equal(ll_warp2d_init(&wp, W, H, 2, sizes, params, get_table, data, 1), LL_OK);
    for (k = 0; k < 20000; ++k) {
        double u[2] = { ll_test_uniform(&rng), ll_test_uniform(&rng) };
        /* Every fifth parameter on a node exactly: one slice of weight 1. */
        double param[2] = { 0.0, k % 5 == 0 ? p1[k % P1] : -1.2 + 3.5 * ll_test_uniform(&rng) };
        ll_warp2d_slices(&wp, param, &s);
        assert_true(s.count >= 1 && s.count <= 2);
        check_inverse(&wp, u, param);
    }
    ll_warp2d_free(&wp);
}

/* The single-slice look-up of a warp without parameters is the general
 * one to rounding, at 1000 points drawn from rng. */
static void check_eval_single(const ll_warp2d *wp, uint64_t *rng)
{
    int k;
    for (k = 0; k < 1000; ++k) {
        double pos[2] = { ll_test_uniform(rng), ll_test_uniform(rng) };
        assert_true(ll_test_close(ll_warp2d_eval_single(wp, pos), ll_warp2d_eval(wp, pos, NULL),
                                  1e-14, 1e-15));
    }
}

/* A warp without parameters whose rows are equal (an isotropic file's ndf
 * and sigma) is read along x only: the bilinear value to rounding. */
static void test_equal_rows(void **state)
{
    static double data[H * W];
    ll_warp2d wp;
    uint64_t rng = 77;
    size_t x, y;
    (void)state;
    for (x = 0; x < W; ++x) {
        double v = 0.1 + ll_test_uniform(&rng);
        for (y = 0; y < H; ++y)
            data[y * W + x] = v;
    }
    assert_int_equal(ll_warp2d_init(&wp, W, H, 0, NULL, NULL, get_table, data, 0), LL_OK);
    assert_true(wp.rows_equal);
    check_eval_single(&wp, &rng);
    ll_warp2d_free(&wp);
    data[W + 2] += 0.5;
    assert_int_equal(ll_warp2d_init(&wp, W, H, 0, NULL, NULL, get_table, data, 0), LL_OK);
    assert_false(wp.rows_equal);
    check_eval_single(&wp, &rng);
    ll_warp2d_free(&wp);
}

static void test_density_integrates_to_one(void **state)
{
    ll_warp2d wp;
    const size_t n = 600;
    size_t i, j;
    int q;
    (void)state;
    make(&wp, 1);
    for (q = 0; q < 3; ++q) {
        double param[2] = { 0.3 * q, -1.0 + 1.1 * q }, sum = 0.0;
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) {
                double pos[2] = { (i + 0.5) / n, (j + 0.5) / n };
                sum += ll_warp2d_eval(&wp, pos, param);
            }
        sum /= (double)(n * n);
        assert_true(fabs(sum - 1.0) < 1e-5);
    }
    ll_warp2d_free(&wp);
}

/* Chi-square of a histogram of sampled points against the density's
 * integral over each bin. */
static void test_histogram(void **state)
{
    enum { B = 12, SAMPLES = 400000, SUB = 16 };
    ll_warp2d wp;
    static double count[B][B];
    double param[2] = { 0.7, 0.9 }, chi2 = 0.0;
    uint64_t rng = 99;
    size_t i, j, a, c;
    (void)state;
    make(&wp, 1);
    memset(count, 0, sizeof count);
    for (i = 0; i < SAMPLES; ++i) {
        double u[2] = { ll_test_uniform(&rng), ll_test_uniform(&rng) }, pos[2], pdf;
        ll_warp2d_sample(&wp, u, param, pos, &pdf);
        a = (size_t)(pos[0] * B);
        c = (size_t)(pos[1] * B);
        count[a < B ? a : B - 1][c < B ? c : B - 1] += 1.0;
    }
    for (i = 0; i < B; ++i)
        for (j = 0; j < B; ++j) {
            double expected = 0.0;
            for (a = 0; a < SUB; ++a)
                for (c = 0; c < SUB; ++c) {
                    double pos[2] = { (i + (a + 0.5) / SUB) / B, (j + (c + 0.5) / SUB) / B };
                    expected += ll_warp2d_eval(&wp, pos, param);
                }
            expected *= (double)SAMPLES / ((double)B * B * SUB * SUB);
            chi2 += (count[i][j] - expected) * (count[i][j] - expected) / expected;
        }
    /* 143 degrees of freedom: the 99.9% point is about 200. */
    assert_true(chi2 < 200.0);
    ll_warp2d_free(&wp);
}

/* A value-only warp interpolates bilinearly, and linearly between slices. */
static void test_interpolation(void **state)
{
    ll_warp2d wp;
    double pos[2] = { 0.5 / (W - 1), 0.0 }, param_a[2] = { 0.0, -1.0 }, param_b[2] = { 1.0, -1.0 };
    double param_m[2] = { 0.25, -1.0 }, va, vb, vm;
    (void)state;
    make(&wp, 0);
    va = ll_warp2d_eval(&wp, pos, param_a);
    vb = ll_warp2d_eval(&wp, pos, param_b);
    vm = ll_warp2d_eval(&wp, pos, param_m);
    assert_true(ll_test_close(vm, 0.75 * va + 0.25 * vb, 1e-12, 1e-15));
    /* Nodes 0 and 1 of slice 0: a value-only warp stores its last
     * parameter innermost (tables_warp.h), so node 1 is inner floats on. */
    assert_int_equal(wp.inner, P1);
    assert_true(ll_test_close(va, 0.5 * ((double)wp.data[0] + (double)wp.data[wp.inner]), 1e-12,
                              1e-15));
    ll_warp2d_free(&wp);
}

/* A warp of GW x GH nodes over three incident slices whose values have
 * stretches of zeros (flat running integrals, where a search's target can
 * tie) and a row of zeros in every slice. */
#define GW 37
#define GH 19
static void init_guided(ll_warp2d *wp, const double *data)
{
    static const double p0[1] = { 0.0 }, p1[P1] = { -1.0, 0.5, 2.0 };
    const double *params[2] = { p0, p1 };
    size_t sizes[2] = { 1, P1 };
    assert_int_equal(ll_warp2d_init(wp, GW, GH, 2, sizes, params, get_table, data, 1), LL_OK);
}

static void make_guided(ll_warp2d *wp, double *data, uint64_t *rng)
{
    size_t k;
    for (k = 0; k < P1 * GH * GW; ++k) {
        size_t x = k % GW, y = k / GW % GH;
        data[k] = y == 3 || (x > 5 && x < 12) || (x + y) % 7 == 0
                      ? 0.0
                      : 0.05 + ll_test_uniform(rng) * (k % 3 == 0 ? 4.0 : 1.0);
    }
    init_guided(wp, data);
}

/* guided and whole (the same warp without guides) sample the same points
 * and densities, to the bit, by sample_at and by the batch calls' steps,
 * at n u anywhere, on the guides' bucket edges and at the square's edges,
 * between slices and on them. */
static void check_same_samples(const ll_warp2d *guided, const ll_warp2d *whole, size_t n,
                               uint64_t *rng)
{
    ll_warp_slices s;
    size_t k;
    for (k = 0; k < n; ++k) {
        double u[2], param[2], a[2], b[2], c[2], pa, pb, pc;
        ll_warp_draw dr;
        int e;
        for (e = 0; e < 2; ++e) {
            size_t g = e == 0 ? guided->cond_buckets : guided->marg_buckets;
            double v = ll_test_uniform(rng);
            /* A third on a bucket's edge (a few at 0 and 1). */
            u[e] = k % 3 == 0 ? floor(v * (double)(g + 1)) / (double)g : v;
        }
        param[0] = 0.0;
        param[1] = k % 5 == 0 ? guided->param_values[1][k % P1]
                              : -1.2 + 3.5 * ll_test_uniform(rng);
        ll_warp2d_slices(guided, param, &s);
        ll_warp2d_sample_at(guided, &s, u, a, &pa);
        ll_warp2d_sample_at(whole, &s, u, b, &pb);
        ll_warp2d_draw_begin(guided, &s, u, &dr);
        ll_warp2d_prefetch_draw(guided, &s, &dr);
        ll_warp2d_draw_end(guided, &s, &dr, c, &pc);
        assert_memory_equal(a, b, sizeof a);
        assert_memory_equal(&pa, &pb, sizeof pa);
        assert_memory_equal(a, c, sizeof a);
        assert_memory_equal(&pa, &pc, sizeof pa);
    }
}

/* The guided searches (ll_warp2d.marg_guide, cond_guide) find what the
 * whole searches find, to the bit; and a guide whose stretch does not
 * bracket the target (as rounding can leave one at a tie) only sends the
 * search to the whole one: guides set to the first node everywhere, then
 * to the last, give the same samples again. */
static void test_guides_find_the_whole_search(void **state)
{
    static double data[P1 * GH * GW];
    ll_warp2d guided, whole;
    uint64_t rng = 99;
    size_t n_marg, n_cond;
    (void)state;
    make_guided(&guided, data, &rng);
    init_guided(&whole, data);
    assert_non_null(guided.marg_guide);
    assert_non_null(guided.cond_guide);
    assert_true(guided.cond_buckets >= 8 && guided.marg_buckets >= 8);
    ll_free(whole.marg_guide);
    ll_free(whole.cond_guide);
    whole.marg_guide = NULL;
    whole.cond_guide = NULL;
    check_same_samples(&guided, &whole, 40000, &rng);
    n_marg = guided.n_slices * (guided.marg_buckets + 1);
    n_cond = guided.n_slices * GH * (guided.cond_buckets + 1);
    assert_false(guided.guide_wide);
    memset(guided.marg_guide, 0, n_marg);
    memset(guided.cond_guide, 0, n_cond);
    check_same_samples(&guided, &whole, 5000, &rng);
    memset(guided.marg_guide, GH - 2, n_marg);
    memset(guided.cond_guide, GW - 2, n_cond);
    check_same_samples(&guided, &whole, 5000, &rng);
    ll_warp2d_free(&guided);
    ll_warp2d_free(&whole);
}

/* A warp too wide for byte entries (300 nodes along x) takes 16-bit ones,
 * which find the whole search's answers as well. */
#define WIDE 300
static void test_wide_guides(void **state)
{
    static double data[P1 * 4 * WIDE];
    static const double p0[1] = { 0.0 }, p1[P1] = { -1.0, 0.5, 2.0 };
    const double *params[2] = { p0, p1 };
    size_t sizes[2] = { 1, P1 };
    ll_warp2d guided, whole;
    uint64_t rng = 31;
    (void)state;
    fill_lumpy(data, P1 * 4 * WIDE, &rng);
    assert_int_equal(ll_warp2d_init(&guided, WIDE, 4, 2, sizes, params, get_table, data, 1),
                     LL_OK);
    assert_int_equal(ll_warp2d_init(&whole, WIDE, 4, 2, sizes, params, get_table, data, 1),
                     LL_OK);
    assert_true(guided.guide_wide);
    assert_non_null(guided.cond_guide);
    ll_free(whole.marg_guide);
    ll_free(whole.cond_guide);
    whole.marg_guide = NULL;
    whole.cond_guide = NULL;
    check_same_samples(&guided, &whole, 20000, &rng);
    ll_warp2d_free(&guided);
    ll_warp2d_free(&whole);
}

/* A running integral that decreases (a negative value, which the reader
 * refuses but the warp takes) leaves the warp without guides: only the
 * whole search defines its answer. */
static void test_no_guides_where_integrals_decrease(void **state)
{
    static double data[P1 * GH * GW];
    ll_warp2d wp;
    uint64_t rng = 5;
    (void)state;
    make_guided(&wp, data, &rng);
    assert_non_null(wp.cond_guide);
    ll_warp2d_free(&wp);
    /* Row 1 of slice 0: its running integral falls after node 20. */
    data[GW + 20] = -10.0;
    init_guided(&wp, data);
    assert_null(wp.marg_guide);
    assert_null(wp.cond_guide);
    ll_warp2d_free(&wp);
}

/* The look-ups' atan2 (tables_atan.h) against the C library's: across
 * the circle at several scales, on and next to the axes and diagonals
 * (where its reductions switch), within 1e-15 (its own error is about
 * 9e-16 at most, near +-pi); the signed zeros and both-zero arguments
 * exactly as the C library's. */
static void test_atan2(void **state)
{
    static const double scale[4] = { 1.0, 1e-300, 1e200, 3.7e-5 };
    static const double zeros[4][2] = { { 0.0, 0.0 }, { 0.0, -0.0 }, { -0.0, 0.0 },
                                        { -0.0, -0.0 } };
    uint64_t rng = 17;
    size_t k, j;
    (void)state;
    for (k = 0; k < 400000; ++k) {
        double t = ll_test_uniform(&rng) * 2.0 * LL_PI - LL_PI, r = scale[k % 4];
        double x = r * cos(t), y = r * sin(t);
        assert_true(fabs(ll_tables_atan2(y, x) - atan2(y, x)) <= 1e-15);
    }
    for (k = 0; k < 16; ++k) {
        /* The axes, the diagonals and tan(pi / 8), and one unit in the
         * last place to either side. */
        double t = (double)k * (LL_PI / 8.0) - LL_PI, x = cos(t), y = sin(t);
        double ys[3] = { y, nextafter(y, 2.0), nextafter(y, -2.0) };
        for (j = 0; j < 3; ++j)
            assert_true(fabs(ll_tables_atan2(ys[j], x) - atan2(ys[j], x)) <= 1e-15);
    }
    for (k = 0; k < 4; ++k) {
        double y = zeros[k][0], x = zeros[k][1], a = ll_tables_atan2(y, x), b = atan2(y, x);
        assert_true(a == b && signbit(a) == signbit(b));
        a = ll_tables_atan2(y, 1.0);
        b = atan2(y, 1.0);
        assert_true(a == b && signbit(a) == signbit(b));
        a = ll_tables_atan2(y, -1.0);
        b = atan2(y, -1.0);
        assert_true(a == b && signbit(a) == signbit(b));
        a = ll_tables_atan2(1.0, x);
        b = atan2(1.0, x);
        assert_true(a == b);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_invert_of_sample),
        cmocka_unit_test(test_two_slices),
        cmocka_unit_test(test_equal_rows),
        cmocka_unit_test(test_density_integrates_to_one),
        cmocka_unit_test(test_histogram),
        cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_guides_find_the_whole_search),
        cmocka_unit_test(test_wide_guides),
        cmocka_unit_test(test_no_guides_where_integrals_decrease),
        cmocka_unit_test(test_atan2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
