/*
 * The probe directions of the resolution search (search/probe.h) and the
 * error measured on them. The grazing cosines mu_min, 1.5 mu_min and
 * 2 mu_min are where a rough interface's azimuthal lobe is narrowest (at
 * mu = 0.1 in the mirror direction, eta 1.5, alpha 0.5 gave 2.5 instead of
 * 4.76 at an earlier fit's 37 orders); the pseudo-random ones keep
 * the set from being tuned to a few directions.
 */
#include "search/probe.h"

#include <math.h>
#include <string.h>

/* Between 0.3 and pi the steps stay under 0.5 rad: a series truncated
 * after m terms ripples with a period of about 2 pi / m, and with 0.3,
 * 0.6, 1.0 alone the eta 1.5, alpha 0.8 transmission at mu_i 0.1 passed
 * the probes and was 1.04% off at phi 0.5 (bench/convergence.c full).
 * Between 0.3 and 0.6 they are 0.1: there a grazing mirror lobe of a
 * rough metal falls from half its peak to 1% of it, and with 0.45 alone
 * copper, alpha 0.8 passed the probes at 144 nodes and was 1.17% off at
 * phi 0.5 (tests/test_convergence.c). */
static const double azimuths[] = { 0.0, 0.01, 0.03, 0.06, 0.1, 0.2, 0.3, 0.4, 0.5,
                                   0.6, 0.8,  1.0,  1.3,  1.6, 2.0, 2.4, LL_PI };
static const double offsets[] = { 0.0,   -0.01, 0.01,  -0.02, 0.02, -0.03, 0.03, -0.05,
                                   0.05,  -0.1,  0.1,   -0.15, 0.15, -0.25, 0.25 };
static const double middle[] = { 0.35, 0.5, 0.6, 0.75, 0.85, 0.9, 0.95, 1.0 };
#define MIDDLE_COUNT (sizeof middle / sizeof middle[0])

#define RANDOM_INCIDENT 3
#define RANDOM_OUTGOING 2

/* A fixed linear congruential sequence (Knuth's MMIX constants) in [0, 1):
 * the same probes on every run and every machine. */
static double next_random(unsigned long long *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 9007199254740992.0;
}

static ll_status add_pair(ll_probe_set *set, double mu_o, double mu_i, size_t group)
{
    if (set->n_pairs == set->cap_pairs) {
        ll_probe_pair *p = ll_grow_array(set->pairs, &set->cap_pairs, 256, sizeof *p);
        if (!p)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        set->pairs = p;
    }
    set->pairs[set->n_pairs].mu_o = mu_o;
    set->pairs[set->n_pairs].mu_i = mu_i;
    set->pairs[set->n_pairs].group = group;
    ++set->n_pairs;
    return LL_OK;
}

/* The incident cosines (magnitudes), at most 3 + MIDDLE_COUNT + RANDOM_INCIDENT. */
static size_t incident_cosines(double mu_min, unsigned long long *state, double *out)
{
    size_t count = 0, k;
    out[count++] = mu_min;
    if (1.5 * mu_min <= 1.0)
        out[count++] = 1.5 * mu_min;
    if (2.0 * mu_min <= 1.0)
        out[count++] = 2.0 * mu_min;
    for (k = 0; k < sizeof middle / sizeof middle[0]; ++k)
        if (middle[k] > 2.0 * mu_min)
            out[count++] = middle[k];
    for (k = 0; k < RANDOM_INCIDENT; ++k)
        out[count++] = mu_min + (1.0 - mu_min) * next_random(state);
    return count;
}

static void start(ll_probe_set *set)
{
    memset(set, 0, sizeof *set);
    set->n_phi = sizeof azimuths / sizeof azimuths[0];
    memcpy(set->phi, azimuths, sizeof azimuths);
}

/* The outgoing cosines of one group around |centre| (sign: the outgoing
 * hemisphere), those within [mu_min, 1]. */
static ll_status add_group(ll_probe_set *set, double centre, double sign, double mu_i,
                           double mu_min, unsigned long long *state)
{
    size_t k;
    ll_status s = LL_OK;
    for (k = 0; k < sizeof offsets / sizeof offsets[0] && s == LL_OK; ++k) {
        double mu = centre + offsets[k];
        if (mu >= mu_min && mu <= 1.0)
            s = add_pair(set, sign * mu, mu_i, set->n_groups);
    }
    for (k = 0; k < RANDOM_OUTGOING && s == LL_OK; ++k)
        s = add_pair(set, sign * (mu_min + (1.0 - mu_min) * next_random(state)), mu_i,
                     set->n_groups);
    ++set->n_groups;
    return s;
}

ll_status ll_probe_interface(double eta_re, double eta_im, double mu_min, ll_probe_set *out)
{
    unsigned long long state = 14;
    double incident[3 + MIDDLE_COUNT + RANDOM_INCIDENT];
    size_t count, k;
    int side;
    ll_status s = LL_OK;
    start(out);
    count = incident_cosines(mu_min, &state, incident);
    for (side = 0; side < (eta_im > 0.0 ? 1 : 2) && s == LL_OK; ++side) {
        /* Layer convention (ll_layer.h): mu_i > 0 travels down, arriving
         * from above, where the relative index below is eta. */
        double sign = side == 0 ? 1.0 : -1.0, eta = side == 0 ? eta_re : 1.0 / eta_re;
        for (k = 0; k < count && s == LL_OK; ++k) {
            double mu_i = sign * incident[k], sin_t;
            /* Reflection: the mirror direction travels the other way. Not
             * on the dense side of a dielectric (the relative index ahead
             * below 1): there the reflection holds the Fresnel edge of
             * total internal reflection, a square-root step along the
             * critical angle that no spline in mu resolves to 1% (eta 1.5,
             * alpha 0.5, from below: 31% off at 60 nodes, 13% at 240,
             * still 0.35% at 1920). Inside a stack (R^b of a coat) that
             * light is seen only through the adding integrals. */
            if (eta_im > 0.0 || eta > 1.0)
                s = add_group(out, incident[k], -sign, mu_i, mu_min, &state);
            if (s != LL_OK || eta_im > 0.0 || eta == 1.0)
                continue;
            /* Transmission (Snell), unless totally reflected. */
            sin_t = sqrt(fmax(0.0, 1.0 - incident[k] * incident[k])) / eta;
            if (sin_t < 1.0)
                s = add_group(out, sqrt(1.0 - sin_t * sin_t), sign, mu_i, mu_min, &state);
        }
    }
    if (s != LL_OK)
        ll_probe_free(out);
    return s;
}

ll_status ll_probe_medium(double mu_min, ll_probe_set *out)
{
    unsigned long long state = 15;
    double incident[3 + MIDDLE_COUNT + RANDOM_INCIDENT];
    size_t count, k;
    ll_status s = LL_OK;
    start(out);
    count = incident_cosines(mu_min, &state, incident);
    /* A medium is the same from both sides: from above only. Its forward
     * peak lies at mu_o = mu_i (transmission), the backward one at
     * mu_o = -mu_i (reflection). */
    for (k = 0; k < count && s == LL_OK; ++k) {
        s = add_group(out, incident[k], 1.0, incident[k], mu_min, &state);
        if (s == LL_OK)
            s = add_group(out, incident[k], -1.0, incident[k], mu_min, &state);
    }
    if (s != LL_OK)
        ll_probe_free(out);
    return s;
}

ll_status ll_probe_opaque(double mu_min, ll_probe_set *out)
{
    /* A conductor's probes are those of any surface that only reflects
     * light arriving from above: around the mirror direction (the
     * specular peak of a measured BRDF is there too) out to 0.25 in mu,
     * plus the pseudo-random ones for the rest of the hemisphere. */
    return ll_probe_interface(1.0, 1.0, mu_min, out);
}

void ll_probe_free(ll_probe_set *set)
{
    ll_free(set->pairs);
    memset(set, 0, sizeof *set);
}

double ll_probe_error(const ll_probe_set *set, const double *v, const double *ref)
{
    double *peak = ll_calloc_array(set->n_groups ? set->n_groups : 1, sizeof(double));
    double worst = 0.0;
    size_t p, k, nphi = set->n_phi;
    if (!peak)
        return HUGE_VAL; /* (callers treat it as "not converged") */
    /* (fmax ignores a NaN: the values left out are out of the peaks.) */
    for (p = 0; p < set->n_pairs; ++p)
        for (k = 0; k < nphi; ++k)
            peak[set->pairs[p].group] = fmax(peak[set->pairs[p].group], ref[p * nphi + k]);
    for (p = 0; p < set->n_pairs; ++p) {
        double floor = LL_PROBE_FLOOR * peak[set->pairs[p].group];
        for (k = 0; k < nphi; ++k) {
            double r = ref[p * nphi + k];
            /* A value left out in either (ll_probe_mark_jump): NaN. */
            if (isnan(r) || isnan(v[p * nphi + k]))
                continue;
            if (r > floor && r > 0.0)
                worst = fmax(worst, fabs(v[p * nphi + k] - r) / r);
        }
    }
    ll_free(peak);
    return worst;
}
