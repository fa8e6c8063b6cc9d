/*
 * ll_bsdf_get_tables (src/reader/bsdf_tables.c): the reader's tables as
 * views. Checked by evaluating from them what the reader evaluates: at a
 * pair of nodes the Catmull-Rom weights are one-hot, so f there is one
 * stored series summed against cos(k phi), which must equal ll_bsdf_eval
 * (golden file, every channel, every basis of a textured file); the CDF rows
 * end at the albedo that ll_bsdf_pdf normalises by; the parameters match
 * ll_bsdf_get_parameter; a short struct_size is honoured.
 */
#ifndef LL_EXPERIMENTAL /* ll_bsdf_get_tables (the Makefile defines it for every test) */
#define LL_EXPERIMENTAL
#endif
#include "test_bsdf_util.h"

#include <math.h>

static ll_bsdf *g_golden, *g_grid;
static const double g_grid_positions[5] = { -1.0, 0.5, 2.0, 0.0, 1.0 };

static int setup(void **state)
{
    size_t counts[2] = { 3, 2 }, k;
    const ll_layer *layers[6];
    ll_layer *synthetic[6];
    ll_test_smooth p[6];
    char path[600];
    ll_test_dir_setup(state);
    if (ll_bsdf_open(LL_TEST_GOLDEN, NULL, &g_golden) != LL_OK)
        fail_msg("open %s: %s", LL_TEST_GOLDEN, ll_last_error_message());
    for (k = 0; k < 6; ++k) {
        p[k].scale[0] = 0.2 + 0.1 * (double)k;
        p[k].scale[1] = 0.03 * (double)k;
        p[k].scale[2] = 0.5;
        p[k].scale[3] = 0.1;
        p[k].decay = 0.1 + 0.05 * (double)k;
        synthetic[k] = ll_test_layer(8, 4);
        ll_test_fill(synthetic[k], ll_test_smooth_fn, &p[k]);
        layers[k] = synthetic[k];
    }
    snprintf(path, sizeof path, "%s/grid.bsdf", ll_test_dir());
    if (ll_bsdf_write_textured(path, layers, 1, 2, counts, g_grid_positions, NULL, NULL) != LL_OK ||
        ll_bsdf_open(path, NULL, &g_grid) != LL_OK)
        fail_msg("grid.bsdf: %s", ll_last_error_message());
    for (k = 0; k < 6; ++k)
        ll_layer_destroy(synthetic[k]);
    return 0;
}

static int teardown(void **state)
{
    ll_bsdf_release(g_golden);
    ll_bsdf_release(g_grid);
    return ll_test_dir_teardown(state);
}

/* The stored sums (Y[, R, B]) of basis k at node pair (i, o), phi. */
static void sums_at_nodes(const ll_bsdf_tables *t, size_t i, size_t o, size_t k, double phi,
                          double sums[3])
{
    size_t pair = i * t->n_nodes + o, c, j;
    uint32_t offset = t->pairs[2 * pair], length = t->pairs[2 * pair + 1];
    for (c = 0; c < 3; ++c)
        sums[c] = 0.0;
    for (c = 0; c < t->n_channels; ++c)
        for (j = 0; j < length; ++j)
            sums[c] += (double)t->coeffs[offset + (c * t->n_bases + k) * length + j] *
                       cos((double)j * phi);
}

/* f at the nodes from the tables against ll_bsdf_eval, for basis k. */
static void check_nodes(const ll_bsdf *b, size_t k)
{
    ll_bsdf_tables t = LL_BSDF_TABLES_INIT;
    float *weights;
    size_t i, o, checked = 0;
    assert_int_equal(ll_bsdf_get_tables(b, &t), LL_OK);
    weights = calloc(t.n_bases, sizeof *weights);
    assert_non_null(weights);
    weights[k] = 1.0f;
    for (i = 0; i < t.n_nodes; i += 3)
        for (o = 0; o < t.n_nodes; o += 2) {
            double mu_i = t.nodes[i], mu_o = t.nodes[o], phi = 0.1 + 0.37 * (double)(i + o);
            double rgb[3], sums[3], y, g, expect[3];
            int c;
            if (mu_o == 0.0 || mu_i == 0.0)
                continue;
            assert_int_equal(ll_bsdf_eval(b, mu_i, mu_o, phi, weights, rgb), LL_OK);
            sums_at_nodes(&t, i, o, k, phi, sums);
            /* to RGB as ll_bsdf.h documents: f = sums / |mu_o|, green rebuilt. */
            y = sums[0] > 0.0 ? sums[0] : 0.0;
            if (t.n_channels == 1) {
                expect[0] = expect[1] = expect[2] = y;
            } else {
                g = 1.39829 * y - 0.100913 * sums[2] - 0.297375 * sums[1];
                expect[0] = sums[1];
                expect[1] = g;
                expect[2] = sums[2];
            }
            for (c = 0; c < 3; ++c) {
                double e = expect[c] > 0.0 ? expect[c] / fabs(mu_o) : 0.0;
                assert_true(fabs(rgb[c] - e) <= 1e-9 * (1.0 + fabs(e)));
            }
            checked++;
        }
    assert_true(checked > 10);
    free(weights);
}

static void golden_counts_match_info(void **state)
{
    ll_bsdf_tables t = LL_BSDF_TABLES_INIT;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    size_t k, longest = 0;
    (void)state;
    assert_int_equal(ll_bsdf_get_tables(g_golden, &t), LL_OK);
    assert_int_equal(ll_bsdf_get_info(g_golden, &info), LL_OK);
    assert_int_equal(t.struct_size, sizeof t);
    assert_int_equal(t.n_nodes, info.n_nodes);
    assert_int_equal(t.n_channels, info.n_channels);
    assert_int_equal(t.n_bases, 1);
    assert_int_equal(t.max_order, info.max_order);
    assert_int_equal(t.n_coeffs, info.n_coeffs);
    assert_int_equal(t.n_parameters, 0);
    assert_null(t.parameter_counts);
    assert_null(t.parameter_positions);
    assert_true(t.eta == info.eta);
    assert_ptr_equal(t.nodes, ll_bsdf_nodes(g_golden));
    /* Every block inside the coefficients, the longest = max_order. */
    for (k = 0; k < t.n_nodes * t.n_nodes; ++k) {
        uint32_t offset = t.pairs[2 * k], length = t.pairs[2 * k + 1];
        assert_true((size_t)offset + (size_t)length * t.n_channels <= t.n_coeffs);
        if (length > longest)
            longest = length;
    }
    assert_int_equal(longest, t.max_order);
}

static void golden_nodes_evaluate_as_reader(void **state)
{
    (void)state;
    check_nodes(g_golden, 0);
}

/* pdf = Y / (2 pi * last CDF entry of row i) at a pair of nodes. */
static void golden_cdf_rows_normalise_pdf(void **state)
{
    ll_bsdf_tables t = LL_BSDF_TABLES_INIT;
    size_t i, o, n, checked = 0;
    (void)state;
    assert_int_equal(ll_bsdf_get_tables(g_golden, &t), LL_OK);
    n = t.n_nodes;
    for (i = 0; i < n; i += 5)
        for (o = 0; o < n; o += 3) {
            double mu_i = t.nodes[i], mu_o = t.nodes[o], phi = 0.3, sums[3], rho, pdf, expect;
            size_t j;
            if (mu_o == 0.0 || mu_i == 0.0)
                continue;
            rho = 2.0 * LL_TEST_PI * t.cdf[i * n + n - 1];
            for (j = 1; j < n; ++j)
                assert_true(t.cdf[i * n + j] >= t.cdf[i * n + j - 1]);
            /* a0 is the order-0 luminance coefficient of the pair. */
            if (t.pairs[2 * (i * n + o) + 1] > 0)
                assert_true(fabs(t.a0[i * n + o] - t.coeffs[t.pairs[2 * (i * n + o)]]) <= 1e-6);
            sums_at_nodes(&t, i, o, 0, phi, sums);
            pdf = ll_test_pdf(g_golden, mu_i, mu_o, phi, NULL);
            expect = rho > 0.0 && sums[0] > 0.0 ? sums[0] / rho : 0.0;
            assert_true(fabs(pdf - expect) <= 1e-9 * (1.0 + expect));
            checked++;
        }
    assert_true(checked > 10);
}

static void textured_parameters_and_bases(void **state)
{
    ll_bsdf_tables t = LL_BSDF_TABLES_INIT;
    size_t p, j, count, first = 0, k;
    const float *positions;
    (void)state;
    assert_int_equal(ll_bsdf_get_tables(g_grid, &t), LL_OK);
    assert_int_equal(t.n_parameters, 2);
    assert_int_equal(t.n_parameter_values, 5);
    assert_int_equal(t.n_bases, 6);
    for (p = 0; p < 2; ++p) {
        assert_int_equal(ll_bsdf_get_parameter(g_grid, p, &count, &positions), LL_OK);
        assert_int_equal(t.parameter_counts[p], count);
        assert_ptr_equal(t.parameter_positions + first, positions);
        for (j = 0; j < count; ++j)
            assert_true(t.parameter_positions[first + j] == (float)g_grid_positions[first + j]);
        first += count;
    }
    for (k = 0; k < t.n_bases; ++k)
        check_nodes(g_grid, k);
}

/* An older caller's struct (ending before n_bases) gets the fields it has
 * and nothing beyond; NULL and a too short struct fail. */
static void short_struct_and_errors(void **state)
{
    unsigned char bytes[sizeof(ll_bsdf_tables)];
    ll_bsdf_tables *t = (ll_bsdf_tables *)(void *)bytes, full = LL_BSDF_TABLES_INIT;
    size_t end = offsetof(ll_bsdf_tables, n_bases), k;
    (void)state;
    memset(bytes, 0xA5, sizeof bytes);
    t->struct_size = end;
    assert_int_equal(ll_bsdf_get_tables(g_golden, t), LL_OK);
    assert_int_equal(ll_bsdf_get_tables(g_golden, &full), LL_OK);
    assert_int_equal(t->n_nodes, full.n_nodes);
    assert_int_equal(t->n_channels, full.n_channels);
    for (k = end; k < sizeof bytes; ++k)
        assert_int_equal(bytes[k], 0xA5);
    assert_int_equal(ll_bsdf_get_tables(NULL, &full), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_get_tables(g_golden, NULL), LL_ERROR_INVALID_ARGUMENT);
    full.struct_size = 0;
    assert_int_equal(ll_bsdf_get_tables(g_golden, &full), LL_ERROR_INVALID_ARGUMENT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(golden_counts_match_info),
        cmocka_unit_test(golden_nodes_evaluate_as_reader),
        cmocka_unit_test(golden_cdf_rows_normalise_pdf),
        cmocka_unit_test(textured_parameters_and_bases),
        cmocka_unit_test(short_struct_and_errors),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
