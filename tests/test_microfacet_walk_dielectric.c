/*
 * The energy compensation of a rough dielectric (eta 1.5) against the
 * random walk on the Smith microsurface (tests/reference/ms_walk.c, its
 * stored results in tests/data/ms_walk.txt): for Beckmann and GGX, alpha
 * 0.1 .. 1, incidence 0 .. 75 degrees, light from above and from below,
 * the compensated R and T within 0.005 of the walk's totals (its standard
 * error is below 0.001), plus, where our single scattering alone already
 * reflects or transmits more than the walk's total, that excess (the
 * model's: no non-negative term can take it back). And what the
 * compensation must keep: R + T = 1 (for GGX, of the albedo whose
 * transmission jump is integrated exactly: the nodes' sum is 1 plus the
 * jump's quadrature error, ll_microfacet_jump_error, itself checked
 * against the integral), reciprocity (reflection symmetric, T^bt =
 * (T^tb)^T / eta^2) and a non-negative term; and what it is made to do:
 * converge with the nodes, so that the resolution search's probes of a
 * compensated GGX dielectric settle (ggx_probes_converge).
 *
 * The rows are those the shares of words/microfacet_compensation_dielectric.c
 * were made from, so this checks the whole chain (the layer's nodes, the
 * interpolation to them, the reciprocal balance, the clamps) rather than
 * the shares between the walk's angles. LL_WALK_TABLES=1 prints the table
 * (ours and the walk's R and T per row, and our single scattering against
 * the walk's first bounce); LL_WALK_FRACTIONS=1 the shares.
 */
#include "test_util.h"
#include "microfacet_check.h"
#include "search/probe.h"

#define PI 3.14159265358979323846
#define WALK_FILE LL_SOURCE_DIR "/tests/data/ms_walk.txt"
#define NODES 160
#define ORDERS 1
/* The Fourier orders the lobes are resolved with: no lobe widened. */
#define ORDERS_INTERNAL 200
#define ETA 1.5
#define TOLERANCE 0.005

typedef struct d_row {
    int dist, below;
    double alpha, theta, r1, r, t1, t;
} d_row;

static int env_set(const char *name)
{
    const char *v = getenv(name);
    return v && *v && strcmp(v, "0") != 0;
}

static int print_tables(void)
{
    return env_set("LL_WALK_TABLES");
}

/* The stored dielectric lines, in the file's order (grouped by
 * distribution and alpha). */
static size_t read_rows(d_row *rows, size_t cap)
{
    FILE *in = fopen(WALK_FILE, "r");
    char line[4096], dn[32], side[16];
    size_t count = 0;
    assert_non_null(in);
    while (fgets(line, sizeof line, in) && count < cap) {
        d_row *r = &rows[count];
        double se_r, se_t;
        if (line[0] != 'D' || sscanf(line, "D %31s %lf %15s %lf %lf %lf %lf %lf %lf %lf", dn,
                                     &r->alpha, side, &r->theta, &r->r1, &r->r, &r->t1, &r->t,
                                     &se_r, &se_t) != 10)
            continue;
        r->dist = strcmp(dn, "ggx") == 0 ? LL_MICROFACET_GGX : LL_MICROFACET_BECKMANN;
        r->below = strcmp(side, "below") == 0;
        /* (What the tolerance takes for granted.) */
        assert_true(se_r < 0.001 && se_t < 0.001);
        count++;
    }
    fclose(in);
    return count;
}

static ll_layer *dielectric(int dist, double alpha, int compensate)
{
    ll_layer *l = ll_test_layer(NODES, ORDERS);
    assert_int_equal(ll_test_set_microfacet_dist(l, ETA, 0.0, alpha, dist, compensate,
                                                 ORDERS_INTERNAL, NULL),
                     LL_OK);
    return l;
}

/* The compensated layer's order 0 minus the single-scattering one's is
 * nowhere below -1e-12 of the largest entry. */
static double most_negative_term(const ll_layer *on, const ll_layer *off, double *M, double *M0)
{
    size_t j, nn = (size_t)NODES * NODES;
    double scale = 0.0, low = 0.0;
    assert_int_equal(ll_layer_matrix(on, 0, M), LL_OK);
    assert_int_equal(ll_layer_matrix(off, 0, M0), LL_OK);
    for (j = 0; j < nn; ++j)
        scale = fmax(scale, fabs(M[j]));
    for (j = 0; j < nn; ++j)
        low = fmin(low, (M[j] - M0[j]) / scale);
    return low;
}

static void dielectric_matches_the_walk(void **state)
{
    static d_row rows[256];
    size_t count = read_rows(rows, 256), i, j, beyond = 0;
    double *M = malloc((size_t)NODES * NODES * sizeof *M);
    double *M0 = malloc((size_t)NODES * NODES * sizeof *M0);
    double worst_r = 0.0, worst_t = 0.0, worst_sum = 0.0, worst_rec_r = 0.0, worst_rec_t = 0.0;
    double lowest = 0.0, single_excess = 0.0, worst_jump = 0.0, jump[NODES];
    (void)state;
    assert_non_null(M);
    assert_non_null(M0);
    assert_true(count >= 240);
    if (print_tables())
        print_message("dist alpha side theta: R ours walk (single: ours walk) | T ours walk "
                      "(single: ours walk)\n");
    for (i = 0; i < count; i = j) {
        ll_layer *on = dielectric(rows[i].dist, rows[i].alpha, 1);
        ll_layer *off = dielectric(rows[i].dist, rows[i].alpha, 0);
        size_t q;
        for (j = i; j < count && rows[j].dist == rows[i].dist && rows[j].alpha == rows[i].alpha;)
            ++j;
        reciprocity_error(on, NODES, ORDERS, ETA * ETA, M, &worst_rec_r, &worst_rec_t);
        lowest = fmin(lowest, most_negative_term(on, off, M, M0));
        /* R + T = 1 from every node, either side, wherever single
         * scattering loses energy; where it alone exceeds 1 (its
         * quadrature over the outgoing nodes, near the critical angle of a
         * sharp lobe) the term adds nothing. For GGX, 1 is that of the
         * albedo whose transmission jump is integrated exactly: the
         * nodes' sum is 1 + the jump's quadrature error (jump_errors()). */
        assert_int_equal(ll_layer_get_nodes(on, M0, NULL), LL_OK);
        jump_errors(on, ETA, rows[i].alpha, rows[i].dist, jump);
        for (q = 0; q < NODES; ++q) {
            double r_n, t_n, r1, t1;
            assert_int_equal(ll_layer_albedo(on, M0[q], &r_n, &t_n), LL_OK);
            assert_int_equal(ll_layer_albedo(off, M0[q], &r1, &t1), LL_OK);
            worst_sum = fmax(worst_sum, fabs(r_n + t_n - fmax(1.0 + jump[q], r1 + t1)));
            worst_jump = fmax(worst_jump, fabs(jump[q]));
            single_excess = fmax(single_excess, r1 + t1 - 1.0);
        }
        for (q = i; q < j; ++q) {
            const d_row *r = &rows[q];
            double mu = cos(r->theta * PI / 180.0) * (r->below ? -1.0 : 1.0);
            double r_on, t_on, r_off, t_off, allowed;
            assert_int_equal(ll_layer_albedo(on, mu, &r_on, &t_on), LL_OK);
            assert_int_equal(ll_layer_albedo(off, mu, &r_off, &t_off), LL_OK);
            /* Where our single scattering alone reflects (transmits) more
             * than the walk's total, no non-negative term can reach the
             * walk: the excess is the model's (the separable Smith G with
             * the rational G1 against the walk's height-correlated exact
             * one; from the denser side at GGX alpha >= 0.7, 75 degrees). */
            allowed = TOLERANCE + fmax(0.0, t_off - r->t) + fmax(0.0, r_off - r->r);
            worst_r = fmax(worst_r, fabs(r_on - r->r));
            worst_t = fmax(worst_t, fabs(t_on - r->t));
            if (fabs(r_on - r->r) > TOLERANCE || fabs(t_on - r->t) > TOLERANCE)
                print_message("beyond %.3f: %s alpha %.1f %s %2.0f deg: R %.4f (walk %.4f), "
                              "T %.4f (walk %.4f); single scattering alone R %.4f, T %.4f: "
                              "%s\n",
                              TOLERANCE, r->dist == LL_MICROFACET_GGX ? "ggx" : "beckmann",
                              r->alpha, r->below ? "below" : "above", r->theta, r_on, r->r,
                              t_on, r->t, r_off, t_off,
                              fabs(r_on - r->r) > allowed || fabs(t_on - r->t) > allowed
                                  ? "FAILS"
                                  : "within that excess");
            if (fabs(r_on - r->r) > allowed || fabs(t_on - r->t) > allowed)
                beyond++;
            if (print_tables())
                print_message("%s %.1f %s %2.0f: R %.4f %.4f (%.4f %.4f) | T %.4f %.4f "
                              "(%.4f %.4f)\n",
                              r->dist == LL_MICROFACET_GGX ? "ggx" : "beckmann", r->alpha,
                              r->below ? "below" : "above", r->theta, r_on, r->r, r_off, r->r1,
                              t_on, r->t, t_off, r->t1);
        }
        ll_layer_destroy(on);
        ll_layer_destroy(off);
    }
    print_message("dielectric: %zu of %zu rows beyond %.3f (+ what single scattering alone "
                  "exceeds the walk's total by); worst |R - walk| %.4f, |T - walk| %.4f\n",
                  beyond, count, TOLERANCE, worst_r, worst_t);
    print_message("dielectric: single scattering alone exceeds R + T = 1 by up to %.2e\n",
                  single_excess);
    print_message("dielectric: |R + T - max(1 + jump error, R1 + T1)| <= %.2e (jump errors "
                  "up to %.2e); reciprocity: reflection %.2e, transmission %.2e of the largest "
                  "entry; term >= %.2e of the largest entry\n",
                  worst_sum, worst_jump, worst_rec_r, worst_rec_t, lowest);
    free(M);
    free(M0);
    assert_true(beyond == 0);
    assert_true(worst_sum < 1e-9);
    assert_true(worst_rec_r < 1e-12);
    assert_true(worst_rec_t < 1e-9);
    assert_true(lowest >= -1e-12);
}

/* The order-0 value of the transmission from positive node cosine mu_i
 * (from above unless below) to mu_o, in the series' convention. */
static double transmission0(const ll_microfacet_model *mf, double mu_o, double mu_i, int below,
                            double *scratch)
{
    double v = 0.0, sign = below ? 1.0 : -1.0;
    size_t len = 0;
    assert_int_equal(ll_microfacet_series(mf, sign * mu_o, sign * mu_i, 1, &v, &len, NULL, scratch),
                     LL_OK);
    return len == 0 ? 0.0 : v;
}

/* The jump error is what it says: the nodes' sum of a GGX transmission
 * albedo less it agrees with the albedo integrated on either side of the
 * jump (composite Gauss-Legendre, 8 panels of 16 points each side) far
 * better than the sum alone, from every node of a 160-node layer. */
static void jump_error_is_the_quadrature_error(void **state)
{
    static const double alphas[2] = { 0.3, 0.8 };
    size_t h = NODES / 2, a, j, i, below, p, k;
    double rule[2 * NODES], mu[NODES / 2], w[NODES / 2], gl[32];
    double *scratch = malloc(ll_microfacet_scratch_size(1) * sizeof *scratch);
    (void)state;
    assert_non_null(scratch);
    assert_int_equal(ll_quad_gauss_lobatto(NODES, rule, rule + NODES, NULL), LL_OK);
    assert_int_equal(ll_quad_gauss_legendre(16, gl, gl + 16, NULL), LL_OK);
    for (j = 0; j < h; ++j) {
        mu[j] = rule[h + j];
        w[j] = 2.0 * PI * rule[NODES + h + j] * mu[j];
    }
    for (a = 0; a < 2; ++a) {
        ll_microfacet_model *mf = NULL;
        double raw = 0.0, corrected = 0.0;
        assert_int_equal(ll_microfacet_create_distribution(ETA, 0.0, alphas[a], LL_MICROFACET_GGX,
                                                           ORDERS_INTERNAL, 1, &mf),
                         LL_OK);
        for (below = 0; below < 2; ++below)
            for (j = 0; j < h; ++j) {
                double jump = below ? mu[j] * ETA : mu[j] / ETA, sum = 0.0, exact = 0.0;
                for (i = 0; i < h; ++i)
                    sum += w[i] * transmission0(mf, mu[i], mu[j], (int)below, scratch);
                /* Panels on [0, J] and [J, 1] (or [0, 1] without a jump). */
                for (p = 0; p < 16; ++p) {
                    double edge = jump < 1.0 ? jump : 0.5;
                    double lo = p < 8 ? 0.0 : edge, hi = p < 8 ? edge : 1.0;
                    double step = (hi - lo) / 8.0, start = lo + (double)(p % 8) * step;
                    for (k = 0; k < 16; ++k) {
                        double x = start + 0.5 * step * (gl[k] + 1.0);
                        exact += 0.5 * step * gl[16 + k] * 2.0 * PI * x *
                                 transmission0(mf, x, mu[j], (int)below, scratch);
                    }
                }
                raw = fmax(raw, fabs(sum - exact));
                corrected = fmax(corrected,
                                 fabs(sum - ll_microfacet_jump_error(mf, h, mu, w, ETA, j,
                                                                     (int)below, scratch) -
                                      exact));
            }
        print_message("ggx alpha %.1f, %d nodes: the transmission albedo's node sum against "
                      "its integral %.2e, less the jump error %.2e\n",
                      alphas[a], NODES, raw, corrected);
        assert_true(raw > 1e-3);
        assert_true(corrected < 0.05 * raw);
        ll_microfacet_destroy(mf);
    }
    free(scratch);
}

/* Where the compensation's terms converge, the resolution search's
 * probes of a compensated GGX dielectric agree with twice the nodes as
 * within the tolerance it is searched with (1%): alpha 0.8, eta 1.5 and
 * 1 / 1.5, 320 against 640 nodes, compared as the search compares them
 * (its jump line left out). Terms made from albedos with the jump's
 * quadrature error in them and cut off at 75 degrees by a step were 139%
 * apart at 256 against 512 nodes, and the search went to 2432 nodes. */
static void ggx_probes_converge(void **state)
{
    static const double etas[2] = { ETA, 1.0 / ETA };
    size_t e, n = 320, m = 64;
    (void)state;
    for (e = 0; e < 2; ++e) {
        ll_probe_set set;
        ll_probe_compensation c1, c2;
        ll_microfacet_model *mf = NULL, *mf0 = NULL;
        double *v1, *v2, error;
        assert_int_equal(ll_probe_interface(etas[e], 0.0, 0.1, &set), LL_OK);
        v1 = malloc(LL_PROBE_VALUES(&set) * sizeof *v1);
        v2 = malloc(LL_PROBE_VALUES(&set) * sizeof *v2);
        assert_non_null(v1);
        assert_non_null(v2);
        assert_int_equal(ll_probe_interface_model_distribution(etas[e], 0.0, 0.8,
                                                               LL_DISTRIBUTION_GGX, &mf),
                         LL_OK);
        assert_int_equal(ll_probe_compensation_model_distribution(etas[e], 0.0, 0.8,
                                                                  LL_DISTRIBUTION_GGX, &mf0),
                         LL_OK);
        assert_int_equal(ll_probe_compensation_make(mf0, etas[e], 0.0, n, NULL, &c1), LL_OK);
        assert_int_equal(ll_probe_compensation_make(mf0, etas[e], 0.0, 2 * n, NULL, &c2), LL_OK);
        assert_int_equal(ll_probe_interface_eval(mf, &c1, n, m, &set, NULL, v1), LL_OK);
        assert_int_equal(ll_probe_interface_eval(mf, &c2, 2 * n, m, &set, NULL, v2), LL_OK);
        assert_int_equal(ll_probe_mark_jump(&set, n, etas[e], v1), LL_OK);
        assert_int_equal(ll_probe_mark_jump(&set, 2 * n, etas[e], v2), LL_OK);
        error = ll_probe_error(&set, v1, v2);
        print_message("ggx alpha 0.8, eta %.3f, compensated: probes at %zu nodes against %zu: "
                      "%.4f\n",
                      etas[e], n, 2 * n, error);
        assert_true(error < 0.01);
        ll_probe_compensation_free(&c1);
        ll_probe_compensation_free(&c2);
        ll_microfacet_destroy(mf);
        ll_microfacet_destroy(mf0);
        ll_probe_free(&set);
        free(v1);
        free(v2);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(dielectric_matches_the_walk),
        cmocka_unit_test(jump_error_is_the_quadrature_error),
        cmocka_unit_test(ggx_probes_converge),
    };
    ll_set_thread_count(1);
    return cmocka_run_group_tests_name("microfacet_walk_dielectric", tests, NULL, NULL);
}
