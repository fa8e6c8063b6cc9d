/*
 * Quadrature rules: the seed's Gauss-Lobatto numbers, closed forms,
 * exactness up to each rule's degree, accuracy at n in the thousands against
 * an independent long-double evaluation, and argument checks.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <layerlab.h>

typedef ll_status (*quad_rule)(size_t n, double *nodes, double *weights);

/* The Gauss rules without a monitor, in the shape of the others. */
static ll_status legendre_rule(size_t n, double *nodes, double *weights)
{
    return ll_quad_gauss_legendre(n, nodes, weights, NULL);
}

static ll_status lobatto_rule(size_t n, double *nodes, double *weights)
{
    return ll_quad_gauss_lobatto(n, nodes, weights, NULL);
}

typedef struct {
    const char *name;
    quad_rule rule;
    int gauss_legendre; /* else Gauss-Lobatto (for the large-n checks) */
} gauss_rule;

static const gauss_rule GAUSS_RULES[2] = {
    {"ll_quad_gauss_legendre", legendre_rule, 1},
    {"ll_quad_gauss_lobatto", lobatto_rule, 0},
};

/* Run a rule that must succeed; the caller frees both buffers. */
static void make_rule(quad_rule rule, size_t n, double **nodes, double **weights)
{
    *nodes = malloc(n * sizeof **nodes);
    *weights = malloc(n * sizeof **weights);
    assert_non_null(*nodes);
    assert_non_null(*weights);
    assert_int_equal(rule(n, *nodes, *weights), LL_OK);
}

/* Nodes strictly ascending inside [-1, 1], exactly antisymmetric, weights
 * positive and exactly symmetric (layers pair mu with -mu bit for bit). */
static void check_shape(const double *x, const double *w, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        assert_true(x[i] >= -1.0 && x[i] <= 1.0);
        assert_true(w[i] > 0.0);
        if (i > 0)
            assert_true(x[i] > x[i - 1]);
        assert_true(x[i] == -x[n - 1 - i]);
        assert_true(w[i] == w[n - 1 - i]);
    }
    if (n % 2 == 1)
        assert_true(x[n / 2] == 0.0 && !signbit(x[n / 2]));
}

/* ------------------------------------------------------------ seed values */

static void test_lobatto_seed_numbers(void **state)
{
    static const double nodes[5] = {-1.0, -0.91953391, -0.73877387, -0.47792495,
                                    -0.16527896};
    static const double weights[5] = {0.02222222, 0.13330599, 0.22488934, 0.29204268,
                                      0.32753976};
    double x[10], w[10];
    size_t i;
    (void)state;
    assert_int_equal(ll_quad_gauss_lobatto(10, x, w, NULL), LL_OK);
    check_shape(x, w, 10);
    for (i = 0; i < 5; ++i) {
        /* The seed prints 8 decimals. */
        assert_true(fabs(x[i] - nodes[i]) <= 5e-9);
        assert_true(fabs(x[9 - i] + nodes[i]) <= 5e-9);
        assert_true(fabs(w[i] - weights[i]) <= 5e-9);
    }
    assert_true(x[0] == -1.0 && x[9] == 1.0);
    assert_true(fabs(w[0] - 2.0 / 90.0) <= 1e-16);
}

/* Closed forms (Abramowitz & Stegun 25.4.29/25.4.32 tables). */
static void test_closed_forms(void **state)
{
    double x[5], w[5];
    double a = sqrt(5.0 - 2.0 * sqrt(10.0 / 7.0)) / 3.0;
    double b = sqrt(5.0 + 2.0 * sqrt(10.0 / 7.0)) / 3.0;
    (void)state;

    assert_int_equal(ll_quad_gauss_legendre(1, x, w, NULL), LL_OK);
    assert_true(x[0] == 0.0 && w[0] == 2.0);

    assert_int_equal(ll_quad_gauss_legendre(2, x, w, NULL), LL_OK);
    assert_true(fabs(x[1] - 1.0 / sqrt(3.0)) <= 2e-16);
    assert_true(fabs(w[0] - 1.0) <= 4e-16);

    assert_int_equal(ll_quad_gauss_legendre(5, x, w, NULL), LL_OK);
    check_shape(x, w, 5);
    assert_true(fabs(x[3] - a) <= 2e-16 && fabs(x[4] - b) <= 2e-16);
    assert_true(fabs(w[2] - 128.0 / 225.0) <= 4e-16);
    assert_true(fabs(w[3] - (322.0 + 13.0 * sqrt(70.0)) / 900.0) <= 4e-16);
    assert_true(fabs(w[4] - (322.0 - 13.0 * sqrt(70.0)) / 900.0) <= 4e-16);

    assert_int_equal(ll_quad_gauss_lobatto(2, x, w, NULL), LL_OK);
    assert_true(x[0] == -1.0 && x[1] == 1.0 && w[0] == 1.0 && w[1] == 1.0);

    assert_int_equal(ll_quad_gauss_lobatto(3, x, w, NULL), LL_OK);
    assert_true(x[1] == 0.0);
    assert_true(fabs(w[0] - 1.0 / 3.0) <= 2e-16 && fabs(w[1] - 4.0 / 3.0) <= 4e-16);

    assert_int_equal(ll_quad_gauss_lobatto(5, x, w, NULL), LL_OK);
    check_shape(x, w, 5);
    assert_true(fabs(x[3] - sqrt(3.0 / 7.0)) <= 2e-16);
    assert_true(fabs(w[0] - 0.1) <= 2e-16 && fabs(w[3] - 49.0 / 90.0) <= 4e-16);
    assert_true(fabs(w[2] - 32.0 / 45.0) <= 4e-16);

    assert_int_equal(ll_quad_composite_simpson(5, x, w), LL_OK);
    assert_true(x[0] == -1.0 && x[1] == -0.5 && x[2] == 0.0 && x[3] == 0.5 && x[4] == 1.0);
    assert_true(fabs(w[0] - 1.0 / 6.0) <= 1e-16 && fabs(w[1] - 4.0 / 6.0) <= 2e-16);
    assert_true(fabs(w[2] - 2.0 / 6.0) <= 1e-16);

    assert_int_equal(ll_quad_composite_simpson38(4, x, w), LL_OK);
    assert_true(x[0] == -1.0 && x[3] == 1.0);
    assert_true(fabs(x[1] + 1.0 / 3.0) <= 1e-16);
    assert_true(fabs(w[0] - 0.25) <= 1e-16 && fabs(w[1] - 0.75) <= 1e-16);
}

/* -------------------------------------------------------------- exactness */

/* Integral of x^k over [-1, 1]. */
static double monomial_integral(unsigned k) { return k % 2 ? 0.0 : 2.0 / (k + 1.0); }

static double rule_error_on_monomial(const double *x, const double *w, size_t n, unsigned k)
{
    long double sum = 0.0L;
    size_t i;
    for (i = 0; i < n; ++i)
        sum += (long double)w[i] * powl((long double)x[i], (long double)k);
    return (double)(sum - monomial_integral(k));
}

/* Exact for every x^k, k <= degree; the first degree above is not exact
 * (for the sizes where that error is large enough to see), so the degree
 * claimed is really the rule's. */
static void check_degree(quad_rule rule, size_t n, unsigned degree)
{
    double *x, *w;
    unsigned k;
    make_rule(rule, n, &x, &w);
    check_shape(x, w, n);
    for (k = 0; k <= degree; ++k)
        assert_true(fabs(rule_error_on_monomial(x, w, n, k)) <= 1e-14);
    if (n <= 6 || degree == 3)
        /* x^(degree+1) is odd for Gauss rules (integrated exactly by symmetry),
         * so the next even power shows the degree. */
        assert_true(fabs(rule_error_on_monomial(x, w, n, degree + 1 + (degree + 1) % 2)) >
                    1e-9);
    free(x);
    free(w);
}

static void test_exact_degrees(void **state)
{
    size_t n;
    (void)state;
    for (n = 1; n <= 24; ++n)
        check_degree(legendre_rule, n, (unsigned)(2 * n - 1));
    for (n = 2; n <= 24; ++n)
        check_degree(lobatto_rule, n, (unsigned)(2 * n - 3));
    for (n = 3; n <= 41; n += 2)
        check_degree(ll_quad_composite_simpson, n, 3);
    for (n = 4; n <= 40; n += 3)
        check_degree(ll_quad_composite_simpson38, n, 3);
}

/* Composite rules: equidistant nodes and the textbook weight patterns. */
static void test_composite_patterns(void **state)
{
    double x[13], w[13];
    size_t i;
    (void)state;
    assert_int_equal(ll_quad_composite_simpson(13, x, w), LL_OK);
    check_shape(x, w, 13);
    for (i = 0; i < 13; ++i) {
        double h = 2.0 / 12.0;
        double c = (i == 0 || i == 12) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        assert_true(fabs(x[i] - (-1.0 + (double)i * h)) <= 2e-16);
        assert_true(fabs(w[i] - c * h / 3.0) <= 1e-16);
    }
    assert_int_equal(ll_quad_composite_simpson38(13, x, w), LL_OK);
    check_shape(x, w, 13);
    for (i = 0; i < 13; ++i) {
        double h = 2.0 / 12.0;
        double c = (i == 0 || i == 12) ? 1.0 : (i % 3 ? 3.0 : 2.0);
        assert_true(fabs(x[i] - (-1.0 + (double)i * h)) <= 2e-16);
        assert_true(fabs(w[i] - c * 3.0 * h / 8.0) <= 1e-16);
    }
}

/* --------------------------------------------------- large n, independently */

/* P_n(x) and P_{n-1}(x) in long double by the plain three-term recurrence,
 * a different evaluation from the library's (double, delta form in theta). */
static void legendre_long(size_t n, long double x, long double *p_n, long double *p_n_minus_1)
{
    long double previous = 1.0L, current = x;
    size_t k;
    for (k = 1; k < n; ++k) {
        long double next = ((2.0L * k + 1.0L) * x * current - (long double)k * previous) /
                           (k + 1.0L);
        previous = current;
        current = next;
    }
    *p_n = current;
    *p_n_minus_1 = previous;
}

/* Refine node x_i in long double (Newton on P_n for Gauss-Legendre, on
 * (1 - x^2) P_m' with m = n - 1 for Gauss-Lobatto, whose x-derivative is
 * -m (m + 1) P_m) and return the exact-formula weight there. */
static void reference_node(int gauss_legendre, size_t n, double x_in, long double *x_out,
                           long double *w_out)
{
    size_t m = gauss_legendre ? n : n - 1;
    long double x = x_in, p, q, md = (long double)m;
    int it;
    for (it = 0; it < 3; ++it) {
        legendre_long(m, x, &p, &q);
        if (gauss_legendre)
            x -= p * (x * x - 1.0L) / (md * (x * p - q));
        else
            x -= md * (q - x * p) / (-md * (md + 1.0L) * p);
    }
    legendre_long(m, x, &p, &q);
    *x_out = x;
    if (gauss_legendre)
        *w_out = 2.0L * (1.0L - x * x) / (md * md * (x * p - q) * (x * p - q));
    else
        *w_out = 2.0L / ((long double)n * (long double)m * p * p);
}

static void check_large(const gauss_rule *r, size_t n)
{
    double *x, *w;
    long double sum = 0.0L, exp_sum = 0.0L;
    double worst_node = 0.0, worst_weight = 0.0, worst_relative = 0.0;
    double e = exp(1.0);
    size_t i;

    make_rule(r->rule, n, &x, &w);
    check_shape(x, w, n);
    if (!r->gauss_legendre)
        assert_true(x[0] == -1.0 && x[n - 1] == 1.0);
    for (i = 0; i < n; ++i) {
        sum += w[i];
        exp_sum += (long double)w[i] * expl((long double)x[i]);
    }
    assert_true(fabsl(sum - 2.0L) <= 1e-14L);
    assert_true(fabs((double)exp_sum - (e - 1.0 / e)) <= 1e-14);

    /* The long-double reference is O(n) per node: check both ends densely
     * (where rules usually degrade) and a spread of interior nodes. */
    for (i = 0; i < n; ++i) {
        long double xr, wr;
        double dx, dw;
        int end = (!r->gauss_legendre && (i == 0 || i == n - 1));
        if (!(i < 40 || i + 40 >= n || i % 17 == 0) || end)
            continue;
        reference_node(r->gauss_legendre, n, x[i], &xr, &wr);
        dx = (double)fabsl(xr - x[i]);
        dw = (double)fabsl(wr - w[i]);
        worst_node = fmax(worst_node, dx);
        worst_weight = fmax(worst_weight, dw);
        worst_relative = fmax(worst_relative, dw / (double)wr);
    }
    print_message("%s(%zu): |node error| <= %.1e, |weight error| <= %.1e "
                  "(relative %.1e), |sum - 2| = %.1e\n",
                  r->name, n, worst_node, worst_weight, worst_relative,
                  (double)fabsl(sum - 2.0L));
    assert_true(worst_node <= 1e-14);
    assert_true(worst_weight <= 1e-14);
    /* Relative accuracy of the tiny end weights (the reference's own 1 - x^2
     * limits this check to ~1e-13 at n = 4096). */
    assert_true(worst_relative <= 1e-12);
    free(x);
    free(w);
}

/* Exactness at large n: sum_i w_i P_j(x_i) = 2 [j == 0] for every j up to
 * the degree (2n - 1 or 2n - 3), all j at once by one recurrence per node. */
static void check_large_exactness(const gauss_rule *r, size_t n)
{
    size_t degree = r->gauss_legendre ? 2 * n - 1 : 2 * n - 3, i, j;
    double *x, *w, worst = 0.0;
    double *moments = calloc(degree + 1, sizeof *moments);
    assert_non_null(moments);
    make_rule(r->rule, n, &x, &w);
    for (i = 0; i < n; ++i) {
        double previous = 1.0, current = x[i];
        moments[0] += w[i];
        moments[1] += w[i] * current;
        for (j = 1; j < degree; ++j) {
            double next = ((2.0 * j + 1.0) * x[i] * current - (double)j * previous) / (j + 1.0);
            previous = current;
            current = next;
            moments[j + 1] += w[i] * current;
        }
    }
    assert_true(fabs(moments[0] - 2.0) <= 1e-14);
    for (j = 1; j <= degree; ++j)
        worst = fmax(worst, fabs(moments[j]));
    print_message("%s(%zu): max_j<=%zu |sum w P_j| = %.1e\n", r->name, n, degree, worst);
    assert_true(worst <= 1e-14);
    free(moments);
    free(x);
    free(w);
}

static void test_large_n(void **state)
{
    static const size_t sizes[] = {1000, 1001, 2048, 4096};
    size_t s, k;
    (void)state;
    if (LDBL_MANT_DIG <= DBL_MANT_DIG)
        skip(); /* no wider type for an independent reference */
    for (k = 0; k < 2; ++k)
        for (s = 0; s < sizeof sizes / sizeof sizes[0]; ++s)
            check_large(&GAUSS_RULES[k], sizes[s]);
}

static void test_large_n_exactness(void **state)
{
    size_t k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        check_large_exactness(&GAUSS_RULES[k], 1000);
        check_large_exactness(&GAUSS_RULES[k], 4096);
    }
}

/* ------------------------------------------------------ invalid arguments */

/* The call fails with LL_ERROR_INVALID_ARGUMENT, names itself and `what` in
 * the message, and writes nothing. */
static void expect_invalid(quad_rule rule, const char *name, size_t n, int null_nodes,
                           int null_weights, int same_buffer, const char *what)
{
    double x[8], w[8];
    size_t i;
    for (i = 0; i < 8; ++i)
        x[i] = w[i] = 42.0;
    assert_int_equal(rule(n, null_nodes ? NULL : x,
                          null_weights ? NULL : (same_buffer ? x : w)),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), name));
    assert_non_null(strstr(ll_last_error_message(), what));
    for (i = 0; i < 8; ++i)
        assert_true(x[i] == 42.0 && w[i] == 42.0);
}

static void test_invalid_arguments(void **state)
{
    static const struct {
        quad_rule rule;
        const char *name;
        size_t smallest;
    } rules[4] = {
        {legendre_rule, "ll_quad_gauss_legendre", 1},
        {lobatto_rule, "ll_quad_gauss_lobatto", 2},
        {ll_quad_composite_simpson, "ll_quad_composite_simpson", 3},
        {ll_quad_composite_simpson38, "ll_quad_composite_simpson38", 4},
    };
    size_t k, n;
    (void)state;
    for (k = 0; k < 4; ++k) {
        for (n = 0; n < rules[k].smallest; ++n)
            expect_invalid(rules[k].rule, rules[k].name, n, 0, 0, 0, "n = ");
        n = k == 3 ? 7 : 5;
        expect_invalid(rules[k].rule, rules[k].name, n, 1, 0, 0, "nodes");
        expect_invalid(rules[k].rule, rules[k].name, n, 0, 1, 0, "weights");
        expect_invalid(rules[k].rule, rules[k].name, n, 1, 1, 0, "NULL");
        expect_invalid(rules[k].rule, rules[k].name, n, 0, 0, 1, "different buffers");
    }
    for (n = 4; n <= 8; n += 2)
        expect_invalid(ll_quad_composite_simpson, "ll_quad_composite_simpson", n, 0, 0, 0,
                       "odd");
    for (n = 5; n <= 8; ++n)
        if ((n - 1) % 3 != 0)
            expect_invalid(ll_quad_composite_simpson38, "ll_quad_composite_simpson38", n, 0,
                           0, 0, "divisible by 3");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lobatto_seed_numbers),
        cmocka_unit_test(test_closed_forms),
        cmocka_unit_test(test_exact_degrees),
        cmocka_unit_test(test_composite_patterns),
        cmocka_unit_test(test_large_n),
        cmocka_unit_test(test_large_n_exactness),
        cmocka_unit_test(test_invalid_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
