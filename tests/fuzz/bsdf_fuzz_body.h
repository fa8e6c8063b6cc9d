/*
 * One fuzz input for the .bsdf reader: open it from memory and, if it
 * opens, evaluate, take densities and sample at fixed directions through
 * both conventions. Shared by the libFuzzer harness (fuzz_bsdf.c) and the
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

    if (ll_bsdf_open_memory(data, size, &b) != LL_OK) {
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
        ll_fuzz_require(ll_bsdf_get_parameter(b, k, &count, &positions) == LL_OK && count > 0);
    }
    for (i = 0; i < n_mu; ++i) {
        for (o = 0; o < n_mu; ++o) {
            double rgb[3], p, phi = 0.3 * (double)o;
            double wo[3], wi[3];
            ll_fuzz_require(ll_bsdf_eval(b, mus[i], mus[o], phi, basis, rgb) == LL_OK);
            ll_fuzz_check_rgb(rgb);
            p = ll_bsdf_pdf(b, mus[i], mus[o], phi, basis);
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
            p = ll_bsdf_pdf_dir(b, wo, wi, basis);
            ll_fuzz_require(isfinite(p) && p >= 0.0);
        }
        for (k = 0; k < n_u; ++k) {
            double mu_o, phi, p, weight[3], wo[3], wi[3], rgb[3];
            ll_fuzz_require(ll_bsdf_sample(b, mus[i], us[k], basis, &mu_o, &phi, &p, weight) ==
                            LL_OK);
            ll_fuzz_require(isfinite(p) && p >= 0.0);
            ll_fuzz_check_rgb(weight);
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
    free(basis);
    ll_bsdf_release(b);
    return 1;
}

#endif /* LL_BSDF_FUZZ_BODY_H */
