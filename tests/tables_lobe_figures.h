/*
 * The figures of tests/tables_figures.h for a transmissive table file
 * (both sides, reflection and transmission apart), public API only:
 *  - albedo: R and T (the integrals of f |cos| over the reflected and the
 *    transmitted hemisphere) for a viewer above and below at elevations
 *    0..85 degrees, each file by its own sampler, stratified; the worst
 *    |table / source - 1| of either, per channel;
 *  - f: relative errors where f |cos| is above 1% of its largest value
 *    over the pairs of the same lobe and side (per channel), both
 *    elevations <= 80 degrees, half of the light directions uniform, half
 *    within 0.4 radians of the lobe's peak (the mirror direction, the
 *    refracted one, or the straight-through one where eta is 1); their
 *    median, 95th and 99th percentiles.
 * Header-only (static inline).
 */
#ifndef LL_TEST_TABLES_LOBE_FIGURES_H
#define LL_TEST_TABLES_LOBE_FIGURES_H

#include "tables_figures.h"

#define TL_STRATA 192
#define TL_PAIRS 60000

typedef struct tl_figures {
    double ratio[2][2][TF_ANGLES][3]; /* [side][0 R, 1 T][angle][channel]  */
    double worst_r, worst_t;          /* worst |ratio - 1| of R and of T   */
    double p50, p95, p99;
    double group_p99[4];              /* [2 bottom + transmit]            */
    size_t n_values;
    int failed;
} tl_figures;

/* R and T per channel for a viewer at cos theta = mu (negative: below). */
static inline int tl_albedo(const ll_bsdf *b, double mu, double r[3], double t[3])
{
    const int n = TL_STRATA;
    double s = sqrt(1.0 - mu * mu), wo[3];
    int i, j, c;
    wo[0] = s;
    wo[1] = 0.0;
    wo[2] = mu;
    for (c = 0; c < 3; ++c)
        r[c] = t[c] = 0.0;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            double u[2] = { (i + 0.5) / n, (j + 0.5) / n }, wi[3], pdf, f[3];
            if (ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f) != LL_OK)
                return 0;
            if (pdf > 0.0)
                for (c = 0; c < 3; ++c)
                    (wi[2] * mu > 0.0 ? r : t)[c] += f[c] * fabs(wi[2]) / pdf;
        }
    for (c = 0; c < 3; ++c) {
        r[c] /= (double)n * n;
        t[c] /= (double)n * n;
    }
    return 1;
}

/* The peak of the lobe (transmit or not) for the viewer wo (its side's
 * relative index eta_rel: far side over near); 0 if there is none
 * (total internal reflection). */
static inline int tl_peak(const double wo[3], int transmit, double eta_rel, double p[3])
{
    double sz = wo[2] > 0.0 ? 1.0 : -1.0, st, ct;
    if (!transmit) {
        p[0] = -wo[0];
        p[1] = -wo[1];
        p[2] = wo[2];
        return 1;
    }
    st = sqrt(wo[0] * wo[0] + wo[1] * wo[1]) / eta_rel;
    if (st >= 1.0)
        return 0;
    ct = sqrt(1.0 - st * st);
    p[0] = -wo[0] / eta_rel;
    p[1] = -wo[1] / eta_rel;
    p[2] = -sz * ct;
    return 1;
}

static inline void tl_measure(const ll_bsdf *src, const ll_bsdf *table, double eta,
                              tl_figures *fig)
{
    const double lim = 80.0 * TF_PI / 180.0;
    double(*ref)[3] = malloc(TL_PAIRS * sizeof *ref), (*got)[3] = malloc(TL_PAIRS * sizeof *got);
    double *cosl = malloc(TL_PAIRS * sizeof *cosl), *err = malloc(3 * TL_PAIRS * sizeof *err);
    int *group = malloc(TL_PAIRS * sizeof *group);
    double top[4][3];
    uint64_t rng = 31;
    size_t k, n = 0;
    int a, c, side, g;
    memset(fig, 0, sizeof *fig);
    memset(top, 0, sizeof top);
    if (!ref || !got || !cosl || !err || !group) {
        fig->failed = 1;
        goto done;
    }
    for (side = 0; side < 2; ++side)
        for (a = 0; a < TF_ANGLES; ++a) {
            double mu = cos(tf_angles_deg[a] * TF_PI / 180.0) * (side ? -1.0 : 1.0);
            double rt[3], tt[3], rs[3], ts[3];
            if (!tl_albedo(table, mu, rt, tt) || !tl_albedo(src, mu, rs, ts)) {
                fig->failed = 1;
                goto done;
            }
            for (c = 0; c < 3; ++c) {
                double x = rs[c] > 0.0 ? rt[c] / rs[c] : 1.0, y = ts[c] > 0.0 ? tt[c] / ts[c] : 1.0;
                fig->ratio[side][0][a][c] = x;
                fig->ratio[side][1][a][c] = y;
                if (!(fabs(x - 1.0) <= fig->worst_r))
                    fig->worst_r = fabs(x - 1.0);
                if (!(fabs(y - 1.0) <= fig->worst_t))
                    fig->worst_t = fabs(y - 1.0);
            }
        }
    for (k = 0; k < TL_PAIRS; ++k) {
        double wo[3], wi[3], p[3], tv = acos(1.0 - tf_uniform(&rng) * (1.0 - cos(lim)));
        int bottom = (int)(k % 4) / 2, transmit = (int)(k / 4) % 2;
        double eta_rel = bottom ? 1.0 / eta : eta, sz = bottom ? -1.0 : 1.0;
        tf_direction(tv, 0.0, wo);
        wo[2] *= sz;
        g = bottom * 2 + transmit;
        for (;;) {
            if (k % 2 == 0 || !tl_peak(wo, transmit, eta_rel, p)) {
                double tl = acos(1.0 - tf_uniform(&rng) * (1.0 - cos(lim)));
                tf_direction(tl, 2.0 * TF_PI * tf_uniform(&rng), wi);
                wi[2] *= transmit ? -sz : sz;
            } else {
                double tp = acos(fabs(p[2])), pp = atan2(p[1], p[0]);
                double dt = 0.4 * (2.0 * tf_uniform(&rng) - 1.0);
                double dp = 0.4 * (2.0 * tf_uniform(&rng) - 1.0) / (sin(tp) + 0.2);
                tf_direction(fabs(tp + dt), pp + dp, wi);
                wi[2] *= p[2] < 0.0 ? -1.0 : 1.0;
            }
            if (acos(fabs(wi[2])) <= lim)
                break;
        }
        if (ll_bsdf_eval_dir(src, wo, wi, LL_TRANSPORT_RADIANCE, NULL, ref[k]) != LL_OK ||
            ll_bsdf_eval_dir(table, wo, wi, LL_TRANSPORT_RADIANCE, NULL, got[k]) != LL_OK) {
            fig->failed = 1;
            goto done;
        }
        cosl[k] = fabs(wi[2]);
        group[k] = g;
        for (c = 0; c < 3; ++c)
            if (ref[k][c] * cosl[k] > top[g][c])
                top[g][c] = ref[k][c] * cosl[k];
    }
    for (g = 0; g < 4; ++g) {
        size_t from = n, m;
        for (k = 0; k < TL_PAIRS; ++k)
            for (c = 0; c < 3; ++c)
                if (group[k] == g && ref[k][c] * cosl[k] > 0.01 * top[g][c])
                    err[n++] = fabs(got[k][c] / ref[k][c] - 1.0);
        m = n - from;
        if (m > 0) {
            qsort(err + from, m, sizeof *err, tf_compare);
            fig->group_p99[g] = err[from + (size_t)(0.99 * (double)m)];
        }
    }
    if (n == 0) {
        fig->failed = 1;
        goto done;
    }
    qsort(err, n, sizeof *err, tf_compare);
    fig->p50 = err[n / 2];
    fig->p95 = err[(size_t)(0.95 * (double)n)];
    fig->p99 = err[(size_t)(0.99 * (double)n)];
    fig->n_values = n;
done:
    free(ref);
    free(got);
    free(cosl);
    free(err);
    free(group);
}

static inline void tl_print(const char *label, const tl_figures *fig)
{
    int side, lobe, a;
    for (side = 0; side < 2; ++side)
        for (lobe = 0; lobe < 2; ++lobe) {
            printf("%s: %s from the %s, table/source (R G B) at", label, lobe ? "T" : "R",
                   side ? "bottom" : "top");
            for (a = 0; a < TF_ANGLES; ++a)
                printf(" %.0f:%.4f/%.4f/%.4f", tf_angles_deg[a], fig->ratio[side][lobe][a][0],
                       fig->ratio[side][lobe][a][1], fig->ratio[side][lobe][a][2]);
            printf("\n");
        }
    printf("%s: worst R %.3f%%, worst T %.3f%% (each file's sampler); f over %zu values: "
           "median %.4f%% 95th "
           "%.3f%% 99th %.3f%%\n",
           label, 100 * fig->worst_r, 100 * fig->worst_t, fig->n_values, 100 * fig->p50,
           100 * fig->p95, 100 * fig->p99);
    printf("%s: 99th by lobe: R top %.3f%%, T top %.3f%%, R bottom %.3f%%, T bottom %.3f%%\n",
           label, 100 * fig->group_p99[0], 100 * fig->group_p99[1], 100 * fig->group_p99[2],
           100 * fig->group_p99[3]);
}

#endif /* LL_TEST_TABLES_LOBE_FIGURES_H */
