/*
 * One fuzz input for the .bsdf reader: open it from memory and, if it
 * opens, evaluate, take densities and sample through both conventions at
 * fixed directions, then at random ones (a generator seeded from the input,
 * so a finding replays) that include the cosines next to 0 where f is the
 * stored f |mu_o| divided by |mu_o| (5e-324, 1e-300, 1e-9). Shared by the libFuzzer harness (fuzz_bsdf.c) and the
 * corpus replay that CI runs (tests/test_bsdf_fuzz_replay.c).
 *
 * A file that opens is valid by definition, so everything it yields must
 * be finite and non-negative, and sampled directions unit vectors: any
 * violation aborts, which the fuzzer reports as a finding.
 */
#ifndef LL_BSDF_FUZZ_BODY_H
#define LL_BSDF_FUZZ_BODY_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <layerlab.h>

static void ll_fuzz_require(int ok)
{
    if (!ok)
        abort();
}

static void ll_fuzz_check_rgb(const double rgb[3])
{
    int c;
    for (c = 0; c < 3; ++c)
        ll_fuzz_require(isfinite(rgb[c]) && rgb[c] >= 0.0);
}

static void ll_fuzz_check_direction(const double w[3])
{
    double len2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    ll_fuzz_require(fabs(len2 - 1.0) < 1e-9);
}

/* splitmix64: a small generator with no state outside the caller. */
static uint64_t ll_fuzz_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1]. */
static double ll_fuzz_uniform(uint64_t *state)
{
    return (double)(ll_fuzz_next(state) >> 11) * (1.0 / 9007199254740991.0);
}

/* A cosine in [-1, 1]: mostly uniform, often one of the extremes next to 0
 * or +-1, of either sign. */
static double ll_fuzz_cosine(uint64_t *state)
{
    static const double special[] = { 5e-324, 1e-300, 1e-160, 1e-30, 1e-9, 1e-6, 0.0,
                                      1.0, 1.0 - 1e-16 };
    uint64_t r = ll_fuzz_next(state);
    double sign = (r & 1) ? -1.0 : 1.0;
    if ((r >> 1) % 3 == 0)
        return sign * special[(r >> 8) % (sizeof special / sizeof special[0])];
    return 2.0 * ll_fuzz_uniform(state) - 1.0;
}

/* A direction with z = mu, random azimuth, random length (not unit). */
static void ll_fuzz_direction(uint64_t *state, double mu, double w[3])
{
    double phi = 6.283185307179586 * ll_fuzz_uniform(state), s = 1.0 - mu * mu;
    double len = 0.25 + 4.0 * ll_fuzz_uniform(state);
    s = s > 0.0 ? sqrt(s) : 0.0;
    w[0] = len * s * cos(phi);
    w[1] = len * s * sin(phi);
    w[2] = len * mu;
}

static void ll_fuzz_bsdf_random(const ll_bsdf *b, const float *basis, const uint8_t *data,
                                size_t size)
{
    uint64_t state = 0x243F6A8885A308D3ull;
    size_t k;
    for (k = 0; k < size; ++k)
        state = (state ^ data[k]) * 0x100000001B3ull; /* FNV-1a of the input */
    for (k = 0; k < 64; ++k) {
        double mu_i = ll_fuzz_cosine(&state), mu_o = ll_fuzz_cosine(&state);
        double phi = 6.283185307179586 * ll_fuzz_uniform(&state);
        double u[2], rgb[3], f_sampled[3], p, mu_s, phi_s, wo[3], wi[3];
        u[0] = ll_fuzz_uniform(&state);
        u[1] = ll_fuzz_uniform(&state);
        ll_fuzz_require(ll_bsdf_eval(b, mu_i, mu_o, phi, basis, rgb) == LL_OK);
        ll_fuzz_check_rgb(rgb);
        ll_fuzz_require(ll_bsdf_pdf(b, mu_i, mu_o, phi, basis, &p) == LL_OK);
        ll_fuzz_require(isfinite(p) && p >= 0.0);
        ll_fuzz_require(ll_bsdf_sample(b, mu_i, u, basis, &mu_s, &phi_s, &p, f_sampled) ==
                        LL_OK);
        ll_fuzz_require(isfinite(p) && p >= 0.0);
        ll_fuzz_check_rgb(f_sampled);
        ll_fuzz_direction(&state, mu_i, wo);
        ll_fuzz_direction(&state, mu_o, wi);
        ll_fuzz_require(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, basis, rgb) == LL_OK);
        ll_fuzz_check_rgb(rgb);
        ll_fuzz_require(ll_bsdf_pdf_dir(b, wo, wi, basis, &p) == LL_OK);
        ll_fuzz_require(isfinite(p) && p >= 0.0);
        ll_fuzz_require(ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE, basis, wi, &p,
                                           rgb) == LL_OK);
        ll_fuzz_require(isfinite(p) && p >= 0.0);
        ll_fuzz_check_rgb(rgb);
        ll_fuzz_check_direction(wi);
    }
}

/* Returns 1 if the input opened. */
static int ll_fuzz_bsdf_one(const uint8_t *data, size_t size)
{
    static const double mus[] = { -1.0, -0.7, -0.2, -1e-3, 0.0, 0.05, 0.5, 0.99, 1.0 };
    static const double us[][2] = { { 0.0, 0.0 }, { 0.3, 0.7 }, { 0.5, 0.5 }, { 0.9, 0.1 },
                                    { 1.0, 1.0 } };
    const size_t n_mu = sizeof mus / sizeof mus[0], n_u = sizeof us / sizeof us[0];
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    float *basis = NULL;
    size_t i, o, k;

    if (ll_bsdf_open_memory(data, size, NULL, &b) != LL_OK) {
        ll_fuzz_require(b == NULL);
        return 0;
    }
    ll_fuzz_require(ll_bsdf_get_info(b, &info) == LL_OK);
    ll_fuzz_require(info.file_size == size && info.metadata != NULL);
    if (info.n_bases > 1) {
        /* n_bases is validated against the file size: this is bounded. */
        basis = malloc(info.n_bases * sizeof *basis);
        ll_fuzz_require(basis != NULL);
        for (k = 0; k < info.n_bases; ++k)
            basis[k] = (float)(k % 3) * 0.5f;
    }
    for (k = 0; k < info.n_parameters; ++k) {
        size_t count;
        const float *positions;
        const char *name = NULL;
        ll_fuzz_require(ll_bsdf_get_parameter(b, k, &count, &positions) == LL_OK && count > 0);
        /* Every parameter has a name (from the metadata or "p<k>"), a C
         * string of at most 255 bytes (strlen reads it whole under ASan). */
        ll_fuzz_require(ll_bsdf_get_parameter_name(b, k, &name) == LL_OK && name != NULL &&
                        strlen(name) >= 1 && strlen(name) <= 255);
    }
    for (i = 0; i < n_mu; ++i) {
        for (o = 0; o < n_mu; ++o) {
            double rgb[3], p, phi = 0.3 * (double)o;
            double wo[3], wi[3];
            ll_fuzz_require(ll_bsdf_eval(b, mus[i], mus[o], phi, basis, rgb) == LL_OK);
            ll_fuzz_check_rgb(rgb);
            ll_fuzz_require(ll_bsdf_pdf(b, mus[i], mus[o], phi, basis, &p) == LL_OK);
            ll_fuzz_require(isfinite(p) && p >= 0.0);
            wo[0] = sqrt(1.0 - mus[i] * mus[i]);
            wo[1] = 0.0;
            wo[2] = mus[i];
            wi[0] = sqrt(1.0 - mus[o] * mus[o]) * cos(phi);
            wi[1] = sqrt(1.0 - mus[o] * mus[o]) * sin(phi);
            wi[2] = mus[o];
            ll_fuzz_require(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, basis, rgb) ==
                            LL_OK);
            ll_fuzz_check_rgb(rgb);
            ll_fuzz_require(ll_bsdf_pdf_dir(b, wo, wi, basis, &p) == LL_OK);
            ll_fuzz_require(isfinite(p) && p >= 0.0);
        }
        for (k = 0; k < n_u; ++k) {
            double mu_o, phi, p, f_sampled[3], wo[3], wi[3], rgb[3];
            ll_fuzz_require(ll_bsdf_sample(b, mus[i], us[k], basis, &mu_o, &phi, &p, f_sampled) ==
                            LL_OK);
            ll_fuzz_require(isfinite(p) && p >= 0.0);
            ll_fuzz_check_rgb(f_sampled);
            if (p > 0.0)
                ll_fuzz_require(mu_o >= -1.0 && mu_o <= 1.0 && phi >= 0.0 &&
                                phi <= 6.283185307179587);
            wo[0] = sqrt(1.0 - mus[i] * mus[i]);
            wo[1] = 0.0;
            wo[2] = mus[i];
            ll_fuzz_require(ll_bsdf_sample_dir(b, wo, us[k], LL_TRANSPORT_IMPORTANCE, basis, wi,
                                               &p, rgb) == LL_OK);
            ll_fuzz_require(isfinite(p) && p >= 0.0);
            ll_fuzz_check_rgb(rgb);
            ll_fuzz_check_direction(wi);
        }
    }
    ll_fuzz_bsdf_random(b, basis, data, size);
    free(basis);
    ll_bsdf_release(b);
    return 1;
}

#endif /* LL_BSDF_FUZZ_BODY_H */
