/*
 * The energy compensation of a rough dielectric interface
 * (ll_layer_set_microfacet's conserve_energy): from the order-0 albedos of
 * the single-scattering layer, the rank-one order-0 terms that give back
 * what shadowing loses, split between reflection and transmission as the
 * light lost on the microsurface really leaves it.
 *
 * One code path for the layer and the resolution probes
 * (search/interface_probe_compensation.c): both call
 * ll_microfacet_compensate_dielectric with the albedos at their own nodes.
 */
#include "words/microfacet.h"
#include "words/microfacet_pair.h"

#include "layerlab/ll_layer.h"

#include <math.h>
#include <string.h>

/* Of the light that single scattering loses along a direction, the share
 * that leaves as reflection: light that a first facet sent into the
 * microsurface goes on bouncing until it escapes, and trapped light ends
 * in the denser medium, whose facets reflect it totally beyond the
 * critical angle. From the rarer side (eta 1 -> 1.5: "above") little of
 * the loss returns as reflection, from the denser side most of it. Per
 * distribution, side, alpha = 0.1, 0.2, .., 1 (rows) and incidence 0, 15,
 * .., 75 degrees (columns): (R_walk - R_1) / (1 - R_1 - T_1), with R_walk
 * the total reflectance of the random walk on the Smith microsurface
 * (tests/reference/ms_walk.c, `ms_walk table`: the D lines of
 * tests/data/ms_walk.txt, eta 1.5, 524288 paths each) and R_1, T_1 the
 * layer's own single-scattering albedos (160 nodes; `LL_WALK_FRACTIONS=1
 * build/tests/test_microfacet_walk_dielectric` prints them). The share is
 * of our loss, not the walk's: it also carries the difference between our
 * separable Smith G (rational G1) and the walk's first bounce (height-
 * correlated, exact Lambda), up to 0.17 in T at GGX alpha 1, 75 degrees.
 * Shares are clamped to [0, 1] (from the denser side at GGX alpha >= 0.7,
 * 75 degrees, the walk reflects more than all of our loss could give).
 *
 * P: our loss is below 0.002 there, too little to measure a share by (the
 * walk's standard error is 0.0003); what a layer loses there is mostly its
 * own quadrature's error at a coarse resolution, which goes back in
 * proportion to what the layer scatters, R / (R + T) of the direction. */
#define P (-1.0)
static const double share_beckmann[2][10][6] = {
    {
        {     P,     P,     P,     P,     P, 0.599 },
        {     P,     P,     P,     P, 0.396, 0.377 },
        {     P,     P,     P, 0.225, 0.252, 0.295 },
        {     P,     P, 0.192, 0.189, 0.208, 0.223 },
        { 0.117, 0.194, 0.196, 0.153, 0.174, 0.189 },
        { 0.182, 0.141, 0.152, 0.110, 0.127, 0.151 },
        { 0.154, 0.116, 0.124, 0.104, 0.111, 0.101 },
        { 0.116, 0.081, 0.100, 0.101, 0.088, 0.072 },
        { 0.096, 0.085, 0.073, 0.074, 0.061, 0.055 },
        { 0.084, 0.067, 0.069, 0.065, 0.045, 0.046 },
    },
    {
        {     P,     P,     P, 0.131,     P, 1.000 },
        {     P,     P,     P, 0.648, 0.923, 1.000 },
        {     P,     P, 0.872, 0.921, 0.895, 0.997 },
        { 0.983, 1.000, 1.000, 0.947, 0.901, 0.977 },
        { 1.000, 1.000, 0.987, 0.946, 0.908, 0.952 },
        { 0.997, 0.984, 0.976, 0.941, 0.915, 0.941 },
        { 0.972, 0.961, 0.952, 0.936, 0.919, 0.941 },
        { 0.947, 0.938, 0.924, 0.928, 0.927, 0.946 },
        { 0.911, 0.899, 0.897, 0.912, 0.934, 0.956 },
        { 0.870, 0.866, 0.875, 0.902, 0.940, 0.968 },
    },
};
static const double share_ggx[2][10][6] = {
    {
        {     P,     P,     P, 0.125, 0.284, 0.297 },
        { 0.000, 0.049, 0.137, 0.119, 0.157, 0.184 },
        { 0.095, 0.095, 0.070, 0.079, 0.104, 0.119 },
        { 0.070, 0.067, 0.067, 0.073, 0.068, 0.078 },
        { 0.058, 0.064, 0.040, 0.042, 0.046, 0.061 },
        { 0.043, 0.045, 0.042, 0.034, 0.037, 0.047 },
        { 0.046, 0.042, 0.036, 0.031, 0.031, 0.041 },
        { 0.034, 0.032, 0.033, 0.025, 0.027, 0.037 },
        { 0.033, 0.027, 0.024, 0.023, 0.025, 0.033 },
        { 0.026, 0.022, 0.019, 0.019, 0.021, 0.031 },
    },
    {
        { 0.873, 0.907, 0.881, 0.859, 0.914, 0.955 },
        { 0.842, 0.842, 0.878, 0.906, 0.931, 0.948 },
        { 0.813, 0.823, 0.861, 0.907, 0.932, 0.954 },
        { 0.798, 0.802, 0.836, 0.886, 0.926, 0.961 },
        { 0.772, 0.772, 0.811, 0.867, 0.928, 0.980 },
        { 0.745, 0.749, 0.784, 0.847, 0.923, 0.996 },
        { 0.720, 0.727, 0.758, 0.823, 0.921, 1.000 },
        { 0.696, 0.698, 0.729, 0.800, 0.917, 1.000 },
        { 0.673, 0.678, 0.703, 0.777, 0.914, 1.000 },
        { 0.652, 0.653, 0.677, 0.757, 0.909, 1.000 },
    },
};

/* 0 at 75 degrees, 1 at grazing incidence, linear in the angle. */
static double ramp(double mu)
{
    double theta = acos(fmin(1.0, fmax(0.0, mu))) * (180.0 / LL_PI);
    return fmin(1.0, fmax(0.0, (theta - 75.0) / 15.0));
}

/* The share for light from the denser side (denser = 1) or the rarer along
 * mu, where the layer reflects the fraction prop of what it scatters (for
 * P): linear in alpha and in the angle, held beyond the measured alphas
 * (0.1 .. 1). Beyond 75 degrees, where the walk was not run and a layer's
 * quadrature loses most (its lobes are sharpest there), the rarer side's
 * goes over to prop by the ramp, reaching it at grazing incidence; the
 * denser side's stays at its 75 degrees' value (near 1: there the lost
 * light is reflected totally). The walk was run for eta 1.5; other indices
 * use the same shares, by which side is the denser. */
static double entry(double v, double prop)
{
    return v < 0.0 ? prop : v;
}

static double share(const ll_microfacet_model *mf, int denser, double mu, double prop)
{
    const double(*t)[6] = mf->ggx ? share_ggx[denser] : share_beckmann[denser];
    double x = fmin(9.0, fmax(0.0, mf->alpha * 10.0 - 1.0));
    double y = fmin(5.0, acos(fmin(1.0, fmax(0.0, mu))) * (180.0 / LL_PI) / 15.0);
    size_t a = x >= 9.0 ? 8 : (size_t)x, b = y >= 5.0 ? 4 : (size_t)y;
    double fa = x - (double)a, fb = y - (double)b;
    double lo = entry(t[a][b], prop) + fb * (entry(t[a][b + 1], prop) - entry(t[a][b], prop));
    double hi = entry(t[a + 1][b], prop) +
                fb * (entry(t[a + 1][b + 1], prop) - entry(t[a + 1][b], prop));
    double v = lo + fa * (hi - lo);
    return denser ? v : v + ramp(mu) * (prop - v);
}

/* The reach of the last balancing step below: 0 up to 75 degrees (the
 * measured shares stay as they are), 1 from 80 degrees on, a smoothstep
 * in the angle between. Continuous, and so is its slope: a term that
 * jumps converges only to first order in the nodes around the jump (a
 * step at 75 degrees, GGX alpha 0.8 from above: the search's probes near
 * 75 degrees were 12% off twice the nodes at 2432 nodes), and one with a
 * kink to first order in the kink's size (a linear ramp over these 5
 * degrees: the search went to 1312 nodes; 568 with the smoothstep). A
 * wider one leaves more of the imbalance to the normalisation below,
 * which puts it into the denser side's reflection at every angle (ramped
 * over 75 .. 85 degrees: GGX alpha 1 from below at normal incidence 0.005
 * above the walk's R). */
#define REACH_FULL 80.0
static double reach(double mu)
{
    double theta = acos(fmin(1.0, fmax(0.0, mu))) * (180.0 / LL_PI);
    double t = fmin(1.0, fmax(0.0, (theta - 75.0) / (REACH_FULL - 75.0)));
    return t * t * (3.0 - 2.0 * t);
}

/* Moves a towards target, a[j] += lambda g(mu_j) (target[j] - a[j])
 * (target NULL: 0) with g the ramp above (wide: reach()), lambda at most
 * 1, so that W.a changes by up to `amount`; returns what is left of it. */
static double balance(size_t h, const double *mu, const double *w, double amount,
                      const double *target, int wide, double *a)
{
    double room = 0.0, lambda;
    size_t j;
    for (j = 0; j < h; ++j)
        room += w[j] * (wide ? reach(mu[j]) : ramp(mu[j])) *
                fabs((target ? target[j] : 0.0) - a[j]);
    if (!(room > 0.0) || !(amount > 0.0))
        return fmax(0.0, amount);
    lambda = fmin(1.0, amount / room);
    for (j = 0; j < h; ++j)
        a[j] += lambda * (wide ? reach(mu[j]) : ramp(mu[j])) *
                ((target ? target[j] : 0.0) - a[j]);
    return amount - lambda * room;
}

/* The order-0 value of a transmission pair (the series' convention: the
 * layer's column j from above is (-mu_o, -mu_j), from below (mu_o, mu_j));
 * 0 where the pair does not scatter or the series fails. */
static double order0(const ll_microfacet_model *mf, double mu_o, double mu_i, double *scratch)
{
    double v = 0.0;
    size_t len = 0;
    if (ll_microfacet_series(mf, mu_o, mu_i, 1, &v, &len, NULL, scratch) != LL_OK || len == 0)
        return 0.0;
    return v;
}

/* (words/microfacet.h) */
double ll_microfacet_jump_error(const ll_microfacet_model *mf, size_t h, const double *mu,
                                const double *w, double eta, size_t j, int below,
                                double *scratch)
{
    double e = below ? 1.0 / eta : eta, jump = mu[j] / e, d, upper, lower, sign, cell;
    size_t i;
    if (!mf->ggx || !(jump < 1.0))
        return 0.0;
    d = 1e-4 * fmin(jump, 1.0 - jump);
    if (!(d > 0.0))
        return 0.0;
    /* The one-sided limits, extrapolated linearly from two cosines just
     * past the jump (at the jump itself h_z = 0). From above the series
     * takes (-mu_o, -mu_j), from below (mu_o, mu_j). */
    sign = below ? 1.0 : -1.0;
    upper = 2.0 * order0(mf, sign * (jump + d), sign * mu[j], scratch) -
            order0(mf, sign * (jump + 2.0 * d), sign * mu[j], scratch);
    lower = 2.0 * order0(mf, sign * (jump - d), sign * mu[j], scratch) -
            order0(mf, sign * (jump - 2.0 * d), sign * mu[j], scratch);
    cell = -LL_PI * (1.0 - jump * jump);
    for (i = h; i-- > 0 && mu[i] > jump;)
        cell += w[i];
    return (upper - lower) * cell;
}

/* Per incident direction the loss 1 - R - T is split by share(): the
 * transmitted part as the product of the two sides' (rank one, so that
 * T^bt = (T^tb)^T / eta^2 keeps reciprocity), then what is left of the
 * loss into reflection as a symmetric u u^T / (W.u), which makes R + T = 1
 * column by column. The loss is that of the albedos without GGX's jump
 * error (ll_microfacet_jump_error): with it, the loss carried the jump's
 * quadrature error, of either sign (GGX alpha 0.8, eta 1.5, from above:
 * up to 1.3% of the loss between 304 and 608 nodes), which the terms --
 * the small reflected one most, normalised by its own sum -- passed on to
 * f, so that their probes against twice the nodes stayed apart up to 2432
 * nodes; without it, 0.005% there. The node sums then keep R + T =
 * max(R_1 + T_1, 1 + the jump error): R + T = 1 for the albedo whose jump
 * is integrated exactly, the nodes' sum off by their own first-order
 * error there. */
void ll_microfacet_compensate_dielectric(const ll_microfacet_model *mf, size_t h,
                                         const double *mu, const double *w, double eta,
                                         const double *const albedo[4], double *work,
                                         ll_microfacet_compensation *out)
{
    const double *rt = albedo[LL_BLOCK_RT], *rb = albedo[LL_BLOCK_RB];
    const double *ttb = albedo[LL_BLOCK_TTB], *tbt = albedo[LL_BLOCK_TBT];
    double *a_tb = work, *a_bt = work + h, *r_t = work + 2 * h, *r_b = work + 3 * h;
    double eta2 = eta * eta, norm, w_tb, w_bt, wa, scratch[MICROFACET_SCRATCH(1)];
    int top_denser = eta < 1.0;
    size_t j;

    memset(out, 0, sizeof *out);
    for (j = 0; j < h; ++j) {
        double t_tb = ttb[j] - ll_microfacet_jump_error(mf, h, mu, w, eta, j, 0, scratch);
        double t_bt = tbt[j] - ll_microfacet_jump_error(mf, h, mu, w, eta, j, 1, scratch);
        double sum_t = rt[j] + t_tb, sum_b = rb[j] + t_bt;
        double prop_t = sum_t > 0.0 ? rt[j] / sum_t : 0.0;
        double prop_b = sum_b > 0.0 ? rb[j] / sum_b : 0.0;
        r_t[j] = fmax(0.0, 1.0 - sum_t); /* the losses, top and bottom */
        r_b[j] = fmax(0.0, 1.0 - sum_b);
        a_tb[j] = r_t[j] * (1.0 - share(mf, top_denser, mu[j], prop_t));
        a_bt[j] = r_b[j] * (1.0 - share(mf, !top_denser, mu[j], prop_b));
    }
    /* Reciprocity asks W.a_tb = eta^2 W.a_bt. The walk's own transmission
     * holds it, but the shares hold it only where they were measured, and
     * from the denser side at GGX alpha >= 0.7 no share reaches the walk
     * (our single scattering alone transmits more there than the walk's
     * total), which leaves the denser side with too much. That is settled
     * beyond 75 degrees, where the walk was not run: the denser side gives
     * up transmitted light there by the ramp (continuous where the
     * measurements end), then the rarer side's transmission takes from its
     * reflection there, by the ramp and, if that is not enough, by the
     * reach (reach(): all of it from 80 degrees on; from the rarer side at
     * grazing incidence the lost light mostly enters the denser medium).
     * Where the rarer side has too much (mostly a coarse layer's own
     * quadrature losses), the normalisation below scales it down, as a
     * term in proportion to R / (R + T) would. */
    w_bt = ll_microfacet_dot(w, a_bt, h);
    w_tb = ll_microfacet_dot(w, a_tb, h);
    if (!top_denser && w_bt > w_tb / eta2) {
        double left = balance(h, mu, w, w_bt - w_tb / eta2, NULL, 0, a_bt);
        left = balance(h, mu, w, left * eta2, r_t, 0, a_tb);
        (void)balance(h, mu, w, left, r_t, 1, a_tb);
    } else if (top_denser && w_tb > w_bt * eta2) {
        double left = balance(h, mu, w, w_tb - w_bt * eta2, NULL, 0, a_tb);
        left = balance(h, mu, w, left / eta2, r_b, 0, a_bt);
        (void)balance(h, mu, w, left, r_b, 1, a_bt);
    }
    /* C^tb = a_bt a_tb^T / norm; column j of W C^tb sums to a_tb[j] (W.a_bt)
     * / norm <= a_tb[j], and C^bt = (C^tb)^T / eta^2 sums to at most
     * a_bt[j]: the larger of the two normalisations keeps both below their
     * side's transmitted share (what the ramps could not settle goes into
     * reflection at every angle). */
    w_bt = ll_microfacet_dot(w, a_bt, h);
    w_tb = ll_microfacet_dot(w, a_tb, h);
    norm = fmax(w_bt, w_tb / eta2);
    if (norm > 0.0) {
        out->u[LL_BLOCK_TTB] = a_bt;
        out->v[LL_BLOCK_TTB] = a_tb;
        out->scale[LL_BLOCK_TTB] = 1.0 / norm;
        out->u[LL_BLOCK_TBT] = a_tb;
        out->v[LL_BLOCK_TBT] = a_bt;
        out->scale[LL_BLOCK_TBT] = 1.0 / (norm * eta2);
    }
    /* What is left for reflection: the transmission albedos now include
     * the terms above, column j of W C^tb being a_tb[j] (W.a_bt) / norm. */
    for (j = 0; j < h; ++j) {
        double t_tb = ttb[j] - ll_microfacet_jump_error(mf, h, mu, w, eta, j, 0, scratch);
        double t_bt = tbt[j] - ll_microfacet_jump_error(mf, h, mu, w, eta, j, 1, scratch);
        if (norm > 0.0) {
            t_tb += a_tb[j] * w_bt / norm;
            t_bt += a_bt[j] * w_tb / (norm * eta2);
        }
        r_t[j] = fmax(0.0, 1.0 - rt[j] - t_tb); /* reflection deficit, top    */
        r_b[j] = fmax(0.0, 1.0 - rb[j] - t_bt); /* reflection deficit, bottom */
    }
    wa = ll_microfacet_dot(w, r_t, h);
    if (wa > 0.0) {
        out->u[LL_BLOCK_RT] = out->v[LL_BLOCK_RT] = r_t;
        out->scale[LL_BLOCK_RT] = 1.0 / wa;
    }
    wa = ll_microfacet_dot(w, r_b, h);
    if (wa > 0.0) {
        out->u[LL_BLOCK_RB] = out->v[LL_BLOCK_RB] = r_b;
        out->scale[LL_BLOCK_RB] = 1.0 / wa;
    }
}
