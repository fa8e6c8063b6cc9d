/*
 * Evaluating an opened .bsdf file in the layer convention (the file's own
 * axes; ll_bsdf.h): f and the sampling density, as pbrt-v3's FourierBSDF::f
 * and ::Pdf compute them (Jakob et al. 2014, sec. 7; formats.md,
 * "Evaluation").
 */
#include "reader/bsdf_internal.h"
#include "reader/tables_internal.h"
#include "reader/bsdf_format.h"

#include <math.h>

/* The bases with non-zero weight (bsdf_internal.h, LL_BSDF_ACTIVE_MAX). */
static void list_active_bases(ll_bsdf_series *s, size_t nb, const float *basis)
{
    size_t k;
    s->n_active = 0;
    s->all_bases = 0;
    for (k = 0; k < nb; ++k)
        if (basis[k] != 0.0f) {
            if (s->n_active == LL_BSDF_ACTIVE_MAX || nb == 1) {
                s->n_active = nb;
                s->all_bases = 1;
                return;
            }
            s->active[s->n_active++] = (uint32_t)k;
        }
}

int ll_bsdf_gather_weighted(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                            double mu_o, const float *basis, ll_bsdf_series *s)
{
    size_t n = b->n_nodes;
    ptrdiff_t off_o;
    double w_o[4];
    int a, c;

    s->count = 0;
    s->max_length = 0;
    s->n_bases = b->n_bases;
    s->basis = basis;
    s->dense = NULL;
    s->prefetch_rows = b->n_coeffs >= LL_BSDF_PREFETCH_ROWS_FROM;
    list_active_bases(s, b->n_bases, basis);
    if (!ll_bsdf_weights(b, mu_o, &off_o, w_o))
        return 0;
    /* Nodes outside the table have weight exactly 0 (spline.h), so every
     * index used below is inside it. */
    for (a = 0; a < 4; ++a) {
        const ll_bsdf_pair *row;
        if (w_i[a] == 0.0)
            continue;
        row = b->pairs + (size_t)(off_i + a) * n;
        for (c = 0; c < 4; ++c) {
            double w = w_i[a] * w_o[c];
            const ll_bsdf_pair *pr;
            if (w == 0.0)
                continue;
            pr = row + (off_o + c);
            if (pr->length == 0)
                continue;
            s->coeff[s->count] = b->coeffs + pr->offset;
            s->length[s->count] = pr->length;
            s->weight[s->count] = w;
            if (pr->length > s->max_length)
                s->max_length = pr->length;
            s->count++;
        }
    }
    return 1;
}

int ll_bsdf_gather(const ll_bsdf *b, double mu_i, double mu_o, const float *basis,
                   ll_bsdf_series *s)
{
    ptrdiff_t off_i;
    double w_i[4];
    s->count = 0;
    s->max_length = 0;
    s->dense = NULL;
    if (!ll_bsdf_weights(b, mu_i, &off_i, w_i))
        return 0;
    return ll_bsdf_gather_weighted(b, off_i, w_i, mu_o, basis, s);
}

double ll_bsdf_row_value(const ll_bsdf *b, const double *table, ptrdiff_t off_i,
                         const double w_i[4], size_t o, const float *basis)
{
    size_t n = b->n_nodes, nb = b->n_bases, k;
    double value = 0.0;
    int a;
    if (nb == 1 && basis[0] == 1.0f) {
        /* Untextured: the interpolation alone (spline weights outside the
         * table are exactly 0, the entries they would read stay unread). */
        for (a = 0; a < 4; ++a)
            if (w_i[a] != 0.0)
                value += w_i[a] * table[(size_t)(off_i + a) * n + o];
        return value;
    }
    /* Textured: the bases of non-zero weight only, listed once for the
     * four rows (skipping a zero term leaves the sum unchanged: the entries
     * are finite), so the few weighted bases of a large file are what the
     * sampler's CDF search reads; more than LL_BSDF_ACTIVE_MAX: all. */
    {
        uint32_t active[LL_BSDF_ACTIVE_MAX];
        size_t n_active = 0, q;
        for (k = 0; k < nb && n_active <= LL_BSDF_ACTIVE_MAX; ++k)
            if (basis[k] != 0.0f) {
                if (n_active < LL_BSDF_ACTIVE_MAX)
                    active[n_active] = (uint32_t)k;
                n_active++;
            }
        for (a = 0; a < 4; ++a) {
            const double *entry;
            double sum = 0.0;
            if (w_i[a] == 0.0)
                continue;
            entry = table + ((size_t)(off_i + a) * n + o) * nb;
            if (n_active <= LL_BSDF_ACTIVE_MAX)
                for (q = 0; q < n_active; ++q)
                    sum += (double)basis[active[q]] * entry[active[q]];
            else
                for (k = 0; k < nb; ++k)
                    sum += (double)basis[k] * entry[k];
            value += w_i[a] * sum;
        }
    }
    return value;
}

void ll_bsdf_to_rgb(const ll_bsdf *b, const double sums[3], double scale, double rgb[3])
{
    /* Luminance is clamped first (pbrt-v3: Y = max(0, Fourier(...))), then
     * green is rebuilt from Y, R, B and every channel clamped at 0. */
    double y = sums[0] > 0.0 ? sums[0] : 0.0;
    int c;
    if (b->n_channels == 1) {
        rgb[0] = rgb[1] = rgb[2] = y * scale;
    } else {
        double r = sums[1], bl = sums[2];
        double g = LL_BSDF_G_FROM_Y * y + LL_BSDF_G_FROM_B * bl + LL_BSDF_G_FROM_R * r;
        rgb[0] = r * scale;
        rgb[1] = g * scale;
        rgb[2] = bl * scale;
    }
    for (c = 0; c < 3; ++c)
        if (!(rgb[c] > 0.0))
            rgb[c] = 0.0;
}

double ll_bsdf_cosine_scale(double mu_o)
{
    double a = fabs(mu_o);
    if (a == 0.0)
        return 0.0;
    return 1.0 / (a > LL_BSDF_MU_FLOOR ? a : LL_BSDF_MU_FLOOR);
}

void ll_bsdf_eval_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                      const float *basis, double extra_scale, double rgb[3])
{
    ll_bsdf_series s;
    double sums[3];
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (b->measured) {
        ll_measured_eval_cos(b, mu_i, mu_o, cos_phi, basis, extra_scale, rgb);
        return;
    }
    /* The stored series is f * |mu_o| (formats.md); at mu_o = 0 the
     * value is taken as 0, as pbrt-v3 does. */
    if (mu_o == 0.0 || !ll_bsdf_gather(b, mu_i, mu_o, basis, &s) || s.count == 0)
        return;
    ll_bsdf_series_eval(&s, b->n_channels, cos_phi, sums);
    ll_bsdf_to_rgb(b, sums, extra_scale * ll_bsdf_cosine_scale(mu_o), rgb);
}

double ll_bsdf_pdf_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                       const float *basis)
{
    ll_bsdf_series s;
    ptrdiff_t off_i;
    double w_i[4], sums[3], rho;
    size_t idx;
    if (b->measured)
        return ll_measured_pdf_cos(b, mu_i, mu_o, cos_phi, basis);
    if (!ll_bsdf_weights(b, mu_i, &off_i, w_i) ||
        !ll_bsdf_gather_weighted(b, off_i, w_i, mu_o, basis, &s) || s.count == 0)
        return 0.0;
    /* The last CDF entry of a row is the integral of a_0 over mu_o: times
     * 2 pi it is the albedo that normalises the density f |mu_o| / albedo. */
    rho = 2.0 * LL_PI * ll_bsdf_row_value(b, b->cdf, off_i, w_i, b->n_nodes - 1, basis);
    ll_bsdf_series_eval(&s, 1, cos_phi, sums);
    if (!(rho > 0.0 && sums[0] > 0.0))
        return 0.0;
    /* In a segment where a CDF row was flattened (bsdf_cdf.c) mu_o has the
     * flattened CDF's density, and phi the series' own (pdf_phi = f /
     * (2 pi a_0)), as the sampler draws them. */
    if (ll_bsdf_cdf_flat_segment(b, off_i, w_i, mu_o, &idx)) {
        double a0 = ll_bsdf_series_mean(&s), pdf;
        if (!(a0 > 0.0))
            return 0.0;
        pdf = ll_bsdf_cdf_flat_density(b, off_i, w_i, basis, idx) * sums[0] / (2.0 * LL_PI * a0);
        return ll_is_finite(pdf) ? pdf : 0.0;
    }
    /* A total that cancels to almost nothing under the spline weights
     * could overflow the ratio; sampling then returns no direction either
     * (ll_bsdf_sample_core), so the two stay consistent. */
    return ll_is_finite(sums[0] / rho) ? sums[0] / rho : 0.0;
}

/* ---------------------------------------------------------- public calls */

/* Clamp a cosine into [-1, 1] (rounding can push a unit vector's z past
 * 1); NaN and infinities are rejected by the callers. */
static double clamp_cosine(double mu) { return mu > 1.0 ? 1.0 : (mu < -1.0 ? -1.0 : mu); }

ll_status ll_bsdf_eval(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                       const float *basis_coeffs, double rgb[3])
{
    const float *basis;
    ll_status s;
    if (!b || !rgb)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_eval: bsdf or f_rgb is NULL");
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!ll_is_finite(mu_i) || !ll_is_finite(mu_o) || !ll_is_finite(phi_d))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_eval: mu_i = %g, mu_o = %g, phi_d = %g must be finite", mu_i,
                       mu_o, phi_d);
    s = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_eval", &basis);
    if (s != LL_OK)
        return s;
    ll_bsdf_eval_cos(b, clamp_cosine(mu_i), clamp_cosine(mu_o), cos(phi_d), basis, 1.0, rgb);
    return LL_OK;
}

ll_status ll_bsdf_pdf(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                      const float *basis_coeffs, double *pdf)
{
    const float *basis;
    ll_status s;
    if (!b || !pdf)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_pdf: bsdf or pdf is NULL");
    *pdf = 0.0;
    if (!ll_is_finite(mu_i) || !ll_is_finite(mu_o) || !ll_is_finite(phi_d))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_pdf: mu_i = %g, mu_o = %g, phi_d = %g must be finite", mu_i,
                       mu_o, phi_d);
    s = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_pdf", &basis);
    if (s != LL_OK)
        return s;
    *pdf = ll_bsdf_pdf_cos(b, clamp_cosine(mu_i), clamp_cosine(mu_o), cos(phi_d), basis);
    return LL_OK;
}
