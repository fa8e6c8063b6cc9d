/*
 * The energy compensation of ll_layer_set_microfacet against the random
 * walk on the Smith microsurface (tests/reference/ms_walk.c, its stored
 * results in tests/data/ms_walk.txt): the compensated directional albedo
 * of a conductor per channel (white, gold, copper, aluminium; Beckmann and
 * GGX, alpha 0.1 .. 1, incidence 0 .. 75 degrees) against the walk's total
 * plus the difference of the two single-scattering lobes (ours keeps the
 * separable Smith G, the walk's first bounce is the height-correlated one),
 * and what the term adds to f against the walk's multiple part (printed:
 * the term lives in order 0, flat in azimuth; checked: non-negative and
 * reciprocal); a dielectric's R and T from both sides (printed; checked:
 * R + T = 1). LL_WALK_TABLES=1 prints the tables (docs/method.md, "Energy
 * compensation against a random walk").
 */
#include "test_util.h"
#include "microfacet_check.h"

#define PI 3.14159265358979323846
#define WALK_FILE LL_SOURCE_DIR "/tests/data/ms_walk.txt"
#define CHANNELS 10
#define NODES 160
#define ORDERS 4

/* The complex indices of the walk's channels (its file's header). */
static const double channel_n[CHANNELS] = { 1e-4, 0.14314609816861512, 0.37311406987244777,
                                            1.4438126161131846, 0.19561986045500956,
                                            0.92562958214826851, 1.1021872800733044,
                                            1.6569217663319644, 0.880174210982267,
                                            0.52119897628501488 };
static const double channel_k[CHANNELS] = { 1e4, 3.982616727574015, 2.3873901555307997,
                                            1.6024531886875775, 3.9108930334980392,
                                            2.4512894683232123, 2.1426425004061507,
                                            9.2242300865681415, 6.2696646162045937,
                                            4.8369802370193939 };

typedef struct albedo_row {
    int dist;
    double alpha, theta, e1[CHANNELS], et[CHANNELS], se[CHANNELS];
} albedo_row;

static int print_tables(void)
{
    const char *v = getenv("LL_WALK_TABLES");
    return v && *v && strcmp(v, "0") != 0;
}

/* The stored albedo lines. */
static size_t read_albedo(albedo_row *rows, size_t cap)
{
    FILE *in = fopen(WALK_FILE, "r");
    char line[4096], dn[32];
    size_t count = 0;
    assert_non_null(in);
    while (fgets(line, sizeof line, in) && count < cap) {
        albedo_row *r = &rows[count];
        int pos, used, k;
        char *p;
        if (line[0] != 'A' || sscanf(line, "A %31s %lf %lf%n", dn, &r->alpha, &r->theta, &pos) != 3)
            continue;
        r->dist = strcmp(dn, "ggx") == 0 ? LL_MICROFACET_GGX : LL_MICROFACET_BECKMANN;
        p = line + pos;
        for (k = 0; k < CHANNELS; ++k) {
            assert_int_equal(sscanf(p, "%lf %lf %lf%n", &r->e1[k], &r->et[k], &r->se[k], &used), 3);
            p += used;
        }
        count++;
    }
    fclose(in);
    return count;
}

static ll_layer *conductor_orders(int dist, double alpha, int channel, int compensate,
                                  size_t orders)
{
    ll_layer *l = ll_test_layer(NODES, orders);
    assert_int_equal(ll_test_set_microfacet_dist(l, channel_n[channel], channel_k[channel], alpha,
                                                 dist, compensate, 0, NULL),
                     LL_OK);
    return l;
}

static ll_layer *conductor(int dist, double alpha, int channel, int compensate)
{
    return conductor_orders(dist, alpha, channel, compensate, ORDERS);
}

/* Ours (compensated) against the walk's total, per channel: within 1% of
 * it plus the difference of the two single-scattering lobes (ours with the
 * separable G1(wi) G1(wo), the walk's first bounce with the
 * height-correlated G2), which is the model's, not the term's (and three
 * standard errors of the walk) -- Beckmann and GGX, alpha 0.1 to 1,
 * incidence 0 to 75 degrees. */
static void conductor_albedo_matches_the_walk(void **state)
{
    albedo_row rows[256];
    size_t count = read_albedo(rows, 256), i, beyond = 0, cases = 0;
    double worst = 0.0, worst_relative = 0.0;
    int k;
    (void)state;
    assert_true(count >= 120);
    if (print_tables())
        print_message("ours / walk - 1 (%%), per channel: white Au.R Au.G Au.B Cu.R Cu.G Cu.B "
                      "Al.R Al.G Al.B\n");
    for (i = 0; i < count; i += 6) {
        double err[CHANNELS][6];
        size_t t;
        for (k = 0; k < CHANNELS; ++k) {
            ll_layer *on = conductor(rows[i].dist, rows[i].alpha, k, 1);
            ll_layer *off = conductor(rows[i].dist, rows[i].alpha, k, 0);
            for (t = 0; t < 6 && i + t < count; ++t) {
                const albedo_row *r = &rows[i + t];
                double mu = cos(r->theta * PI / 180.0), e_on = 0.0, e_off = 0.0, allowed;
                assert_int_equal(ll_layer_albedo(on, mu, &e_on, NULL), LL_OK);
                assert_int_equal(ll_layer_albedo(off, mu, &e_off, NULL), LL_OK);
                allowed = 0.01 * r->et[k] + fabs(e_off - r->e1[k]) + 3.0 * r->se[k];
                err[k][t] = e_on / r->et[k] - 1.0;
                worst_relative = fmax(worst_relative, fabs(err[k][t]));
                cases++;
                if (fabs(e_on - r->et[k]) > allowed) {
                    print_message("beyond: %s alpha %.1f %2.0f deg channel %d: ours %.4f walk "
                                  "%.4f (single %.4f against %.4f)\n",
                                  r->dist == LL_MICROFACET_GGX ? "ggx" : "beckmann", r->alpha,
                                  r->theta, k, e_on, r->et[k], e_off, r->e1[k]);
                    worst = fmax(worst, fabs(e_on - r->et[k]) - allowed);
                    beyond++;
                }
            }
            ll_layer_destroy(on);
            ll_layer_destroy(off);
        }
        if (print_tables()) {
            size_t t2;
            for (t2 = 0; t2 < 6; ++t2) {
                char line[512];
                size_t len = 0;
                for (k = 0; k < CHANNELS; ++k)
                    len += (size_t)snprintf(line + len, sizeof line - len, " %+6.2f",
                                            100.0 * err[k][t2]);
                print_message("%s %.1f %2.0f:%s\n",
                              rows[i].dist == LL_MICROFACET_GGX ? "ggx" : "beckmann",
                              rows[i].alpha, rows[i + t2].theta, line);
            }
        }
    }
    print_message("conductor albedo (alpha <= 1): %zu of %zu cases beyond 1%% + the lobes' "
                  "difference, worst by %.4f; at most %.2f%% from the walk's total\n",
                  beyond, cases, worst, 100.0 * worst_relative);
    assert_true(beyond == 0);
}

/* What the term adds to f against the walk's multiple part, on the walk's
 * grid (incidence 0, 30, 60 degrees, exitance 0 .. 75, azimuths 0 .. 180
 * from the incident one): per (distribution, alpha, channel), at least
 * SHAPE_SHARE of the points above 1% of the walk's peak where the two
 * agree within 20% (the walk's standard error there is a few percent).
 * The layer has SHAPE_ORDERS orders: the term's spread over the azimuth
 * is held to what the layer's orders resolve. */
#define SHAPE_ORDERS 64
#define SHAPE_SHARE 0.8
typedef struct f_row {
    int dist;
    double alpha, ti, to, phi, fm[CHANNELS];
} f_row;

static size_t read_f(f_row *rows, size_t cap)
{
    FILE *in = fopen(WALK_FILE, "r");
    char line[4096], dn[32];
    size_t count = 0;
    assert_non_null(in);
    while (fgets(line, sizeof line, in) && count < cap) {
        f_row *r = &rows[count];
        int pos, used, k;
        double se;
        char *p;
        if (line[0] != 'F' || sscanf(line, "F %31s %lf %lf %lf %lf%n", dn, &r->alpha, &r->ti,
                                     &r->to, &r->phi, &pos) != 5)
            continue;
        r->dist = strcmp(dn, "ggx") == 0 ? LL_MICROFACET_GGX : LL_MICROFACET_BECKMANN;
        p = line + pos;
        for (k = 0; k < CHANNELS; ++k) {
            assert_int_equal(sscanf(p, "%lf %lf%n", &r->fm[k], &se, &used), 2);
            p += used;
        }
        count++;
    }
    fclose(in);
    return count;
}

static void term_shape_against_the_walk(void **state)
{
    static f_row rows[600];
    size_t count = read_f(rows, 600), i, j, short_cases = 0;
    (void)state;
    assert_true(count >= 540);
    for (i = 0; i < count; i = j) {
        int k;
        for (j = i; j < count && rows[j].dist == rows[i].dist && rows[j].alpha == rows[i].alpha;)
            ++j;
        for (k = 0; k < CHANNELS; ++k) {
            ll_layer *on = conductor_orders(rows[i].dist, rows[i].alpha, k, 1, SHAPE_ORDERS);
            ll_layer *off = conductor_orders(rows[i].dist, rows[i].alpha, k, 0, SHAPE_ORDERS);
            double peak = 0.0, flat_ratio_min = HUGE_VAL, flat_ratio_max = 0.0;
            size_t q, counted = 0, within = 0;
            for (q = i; q < j; ++q)
                peak = fmax(peak, rows[q].fm[k]);
            for (q = i; q < j; ++q) {
                double mu_i = cos(rows[q].ti * PI / 180.0), mu_o = -cos(rows[q].to * PI / 180.0);
                double phi_d = PI - rows[q].phi * PI / 180.0, added;
                if (rows[q].fm[k] <= 0.01 * peak)
                    continue;
                added = ll_test_layer_eval(on, mu_i, mu_o, phi_d) -
                        ll_test_layer_eval(off, mu_i, mu_o, phi_d);
                /* The term is reciprocal and non-negative everywhere. */
                assert_true(added >= -1e-12);
                assert_true(fabs(added - (ll_test_layer_eval(on, -mu_o, -mu_i, phi_d) -
                                          ll_test_layer_eval(off, -mu_o, -mu_i, phi_d))) <=
                            1e-9 * fmax(1.0, added));
                counted++;
                within += fabs(added / rows[q].fm[k] - 1.0) <= 0.2;
                flat_ratio_min = fmin(flat_ratio_min, added / rows[q].fm[k]);
                flat_ratio_max = fmax(flat_ratio_max, added / rows[q].fm[k]);
            }
            if (print_tables() || (double)within < SHAPE_SHARE * (double)counted)
                print_message("f shape %s alpha %.1f channel %d: %zu of %zu points within 20%% "
                              "(ours / walk from %.3g to %.3g)\n",
                              rows[i].dist == LL_MICROFACET_GGX ? "ggx" : "beckmann",
                              rows[i].alpha, k, within, counted, flat_ratio_min, flat_ratio_max);
            short_cases += (double)within < SHAPE_SHARE * (double)counted;
            ll_layer_destroy(on);
            ll_layer_destroy(off);
        }
    }
    print_message("f shape: %zu (distribution, alpha, channel) cases below %.0f%% of the points "
                  "within 20%%\n", short_cases, 100.0 * SHAPE_SHARE);
    assert_true(short_cases == 0);
}

/* A dielectric (eta 1.5) from above and below against the walk: R and T
 * (and each against the walk's first bounce alone), R + T = 1 for ours
 * (GGX: plus the jump error of its nodes, words/microfacet.h). */
static void dielectric_against_the_walk(void **state)
{
    FILE *in = fopen(WALK_FILE, "r");
    char line[4096], dn[32], side[16];
    ll_layer *on = NULL, *off = NULL;
    int last_dist = -1;
    double last_alpha = -1.0, worst_r = 0.0, jump[NODES], largest_jump = 0.0;
    size_t k;
    (void)state;
    assert_non_null(in);
    while (fgets(line, sizeof line, in)) {
        double alpha, t, v[6], mu, r_on, t_on, r_off, t_off;
        int dist;
        if (line[0] != 'D' || sscanf(line, "D %31s %lf %15s %lf %lf %lf %lf %lf %lf %lf", dn,
                                     &alpha, side, &t, &v[0], &v[1], &v[2], &v[3], &v[4],
                                     &v[5]) != 10)
            continue;
        dist = strcmp(dn, "ggx") == 0 ? LL_MICROFACET_GGX : LL_MICROFACET_BECKMANN;
        if (dist != last_dist || alpha != last_alpha) {
            ll_layer_destroy(on);
            ll_layer_destroy(off);
            on = ll_test_layer(NODES, ORDERS);
            off = ll_test_layer(NODES, ORDERS);
            assert_int_equal(ll_test_set_microfacet_dist(on, 1.5, 0.0, alpha, dist, 1, 0, NULL),
                             LL_OK);
            assert_int_equal(ll_test_set_microfacet_dist(off, 1.5, 0.0, alpha, dist, 0, 0, NULL),
                             LL_OK);
            jump_errors(on, 1.5, alpha, dist, jump);
            for (k = 0, largest_jump = 0.0; k < NODES; ++k)
                largest_jump = fmax(largest_jump, fabs(jump[k]));
            last_dist = dist;
            last_alpha = alpha;
        }
        mu = cos(t * PI / 180.0) * (strcmp(side, "below") == 0 ? -1.0 : 1.0);
        assert_int_equal(ll_layer_albedo(on, mu, &r_on, &t_on), LL_OK);
        assert_int_equal(ll_layer_albedo(off, mu, &r_off, &t_off), LL_OK);
        /* (Between the nodes, whose sums are 1 + their jump error.) */
        assert_true(fabs(r_on + t_on - 1.0) < 1e-3 + largest_jump);
        worst_r = fmax(worst_r, fabs(r_on - v[1]));
        if (print_tables())
            print_message("dielectric %s %.1f %s %2.0f: R %.4f (walk %.4f), T %.4f (walk %.4f); "
                          "first bounce R %+.4f T %+.4f\n",
                          dn, alpha, side, t, r_on, v[1], t_on, v[3], r_off - v[0], t_off - v[2]);
    }
    fclose(in);
    ll_layer_destroy(on);
    ll_layer_destroy(off);
    print_message("dielectric: R differs from the walk's by at most %.4f\n", worst_r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(conductor_albedo_matches_the_walk),
        cmocka_unit_test(term_shape_against_the_walk),
        cmocka_unit_test(dielectric_against_the_walk),
    };
    ll_set_thread_count(1);
    return cmocka_run_group_tests_name("microfacet_walk", tests, NULL, NULL);
}
