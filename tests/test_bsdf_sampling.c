/*
 * Sampling is consistent with evaluation: the returned pdf is pdf() of the
 * returned direction, the returned f is eval() there, the sampled
 * directions follow pdf() (chi-square), pdf() integrates to 1 over the
 * sphere, and u at 0 and 1 (both allowed) gives a direction wherever light
 * is scattered.
 */
#include "test_bsdf_util.h"

#if defined(__SANITIZE_ADDRESS__)
#  define LL_TEST_SANITIZED 1
#elif defined(__has_feature)
#  if __has_feature(address_sanitizer)
#    define LL_TEST_SANITIZED 1
#  endif
#endif
#ifndef LL_TEST_SANITIZED
#  define LL_TEST_SANITIZED 0
#endif

/* 10^6 samples normally; fewer under the (much slower) sanitizers. */
#define LL_TEST_SAMPLES (LL_TEST_SANITIZED ? 200000 : 1000000)

static char g_dir[512];
static ll_bsdf *g_lobe, *g_white, *g_golden;

static ll_bsdf *write_open(const char *name, const ll_layer *l, double goal)
{
    char path[600];
    const ll_layer *layers[1];
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_bsdf *b = NULL;
    layers[0] = l;
    opts.error_goal = goal;
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    if (ll_bsdf_write(path, layers, 1, &opts, NULL) != LL_OK || ll_bsdf_open(path, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return b;
}

static int setup(void **state)
{
    ll_layer *l;
    double sharp = 8.0;
    (void)state;
    ll_test_mkdtemp(g_dir, sizeof g_dir);
    l = ll_test_layer(24, 40);
    ll_test_fill(l, ll_test_lobe_fn, &sharp);
    g_lobe = write_open("lobe.bsdf", l, 1e-3);
    ll_layer_destroy(l);
    l = ll_test_layer(16, 1);
    assert_int_equal(ll_layer_set_diffuse(l, 1.0, NULL), LL_OK);
    g_white = write_open("white.bsdf", l, 1e-3);
    ll_layer_destroy(l);
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &g_golden), LL_OK);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    ll_bsdf_release(g_lobe);
    ll_bsdf_release(g_white);
    ll_bsdf_release(g_golden);
    ll_test_rmdir(g_dir);
    return 0;
}

/* Layer convention: every sample's pdf and f against pdf() and eval(). */
static void consistency(void **state)
{
    uint64_t rng = 2024;
    long k, zero = 0;
    (void)state;
    for (k = 0; k < LL_TEST_SAMPLES; ++k) {
        double mu_i = 2.0 * ll_test_uniform(&rng) - 1.0, u[2], mu_o, phi, pdf, w[3], f[3], p;
        u[0] = ll_test_uniform(&rng);
        u[1] = ll_test_uniform(&rng);
        assert_int_equal(ll_bsdf_sample(g_lobe, mu_i, u, NULL, &mu_o, &phi, &pdf, w), LL_OK);
        if (pdf == 0.0) {
            ++zero;
            assert_true(w[0] == 0.0);
            continue;
        }
        assert_true(mu_o >= -1.0 && mu_o <= 1.0 && phi >= 0.0 && phi <= 2.0 * LL_TEST_PI);
        p = ll_test_pdf(g_lobe, mu_i, mu_o, phi, NULL);
        if (!ll_test_close(pdf, p, 1e-5, 1e-9))
            fail_msg("sample %ld: pdf %.9g, pdf() %.9g (mu_i %g mu_o %g phi %g)", k, pdf, p,
                     mu_i, mu_o, phi);
        assert_int_equal(ll_bsdf_eval(g_lobe, mu_i, mu_o, phi, NULL, f), LL_OK);
        if (!ll_test_close(w[0], f[0], 1e-5, 1e-9))
            fail_msg("sample %ld: f %.9g, eval() %.9g", k, w[0], f[0]);
    }
    /* Only directions with a zero CDF row (mu_i near 0) give no sample. */
    assert_true(zero < LL_TEST_SAMPLES / 100);
}

/* Renderer convention on the golden file (RGB). */
static void consistency_golden(void **state)
{
    uint64_t rng = 77;
    long k, n = LL_TEST_SAMPLES / 5;
    (void)state;
    for (k = 0; k < n; ++k) {
        double ct = ll_test_uniform(&rng), ph = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        double wo[3] = { sqrt(1.0 - ct * ct) * cos(ph), sqrt(1.0 - ct * ct) * sin(ph), ct };
        double u[2], wi[3], pdf, f[3], g[3], p;
        int c;
        u[0] = ll_test_uniform(&rng);
        u[1] = ll_test_uniform(&rng);
        assert_int_equal(
            ll_bsdf_sample_dir(g_golden, wo, u, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f), LL_OK);
        assert_true(fabs(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2] - 1.0) < 1e-12);
        if (pdf == 0.0)
            continue;
        p = ll_test_pdf_dir(g_golden, wo, wi, NULL);
        if (!ll_test_close(pdf, p, 1e-5, 1e-9))
            fail_msg("sample %ld: pdf %.9g, pdf_dir %.9g", k, pdf, p);
        assert_int_equal(ll_bsdf_eval_dir(g_golden, wo, wi, LL_TRANSPORT_RADIANCE, NULL, g),
                         LL_OK);
        for (c = 0; c < 3; ++c)
            if (!ll_test_close(f[c], g[c], 1e-5, 1e-9))
                fail_msg("sample %ld channel %d: f %.9g, eval_dir %.9g", k, c, f[c], g[c]);
    }
}

/* integral of pdf(mu_i, .) over the sphere, by Gauss-Legendre in phi and a
 * composite rule in mu_o whose panels end at the file's nodes (the pdf is a
 * cubic in mu_o between them). */
static double pdf_integral(const ll_bsdf *b, double mu_i)
{
    static const double gx[4] = { -0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                  0.8611363115940526 };
    static const double gw[4] = { 0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                  0.3478548451374538 };
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    const float *nodes = ll_bsdf_nodes(b);
    double total = 0.0;
    size_t k, a, c, j;
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    for (k = 0; k + 1 < info.n_nodes; ++k) {
        double x0 = nodes[k], x1 = nodes[k + 1];
        if (!(x1 > x0))
            continue;
        for (a = 0; a < 4; ++a) {
            double mu = 0.5 * (x0 + x1) + 0.5 * (x1 - x0) * gx[a], sum = 0.0;
            /* 64 panels in phi, 4 points each: the series is smooth. */
            for (j = 0; j < 64; ++j)
                for (c = 0; c < 4; ++c) {
                    double phi = LL_TEST_PI / 64.0 * ((double)j + 0.5 + 0.5 * gx[c]);
                    sum += gw[c] * 0.5 * ll_test_pdf(b, mu_i, mu, phi, NULL);
                }
            /* phi over [0, pi], doubled (the series is even). */
            total += gw[a] * 0.5 * (x1 - x0) * 2.0 * sum * LL_TEST_PI / 64.0;
        }
    }
    return total;
}

static void pdf_integrates_to_one(void **state)
{
    static const double mus[] = { 1.0, 0.73, 0.31, -0.5, -0.95 };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof mus / sizeof mus[0]; ++k) {
        double white = pdf_integral(g_white, mus[k]), lobe = pdf_integral(g_lobe, mus[k]);
        if (fabs(white - 1.0) > 1e-4 || fabs(lobe - 1.0) > 2e-3)
            fail_msg("mu_i %g: integral of pdf %.6f (white), %.6f (lobe)", mus[k], white, lobe);
    }
    /* The non-absorbing file reflects everything: integral f |mu_o| = 1
     * (away from grazing incidence, see the round-trip test). */
    {
        double mu_i = 0.8, total = 0.0, rgb[3];
        size_t j, n = 4000;
        for (j = 0; j < n; ++j) {
            double mu_o = -((double)j + 0.5) / (double)n;
            assert_int_equal(ll_bsdf_eval(g_white, mu_i, mu_o, 0.0, NULL, rgb), LL_OK);
            total += rgb[0] * fabs(mu_o) * 2.0 * LL_TEST_PI / (double)n;
        }
        assert_true(fabs(total - 1.0) < 1e-6);
    }
    /* The golden file: 0.81 albedo is the README's "about", the pdf is 1. */
    {
        double p = pdf_integral(g_golden, 0.6);
        assert_true(fabs(p - 1.0) < 2e-3);
    }
}

/* Wilson-Hilferty: is chi2 with dof degrees of freedom below the
 * 1 - 1e-5 quantile? */
static int chi2_accept(double chi2, double dof)
{
    double z = (pow(chi2 / dof, 1.0 / 3.0) - (1.0 - 2.0 / (9.0 * dof))) / sqrt(2.0 / (9.0 * dof));
    return z < 4.27;
}

/* Sampled (mu_o, phi) histogram against the integral of pdf() per bin. */
static void chi_square_case(const ll_bsdf *b, double mu_i, uint64_t seed)
{
    enum { NM = 20, NP = 16, SUB = 6 };
    static double expected[NM * NP];
    static long observed[NM * NP];
    long k, n = LL_TEST_SAMPLES / 4;
    uint64_t rng = seed;
    double chi2 = 0.0, pooled_e = 0.0, pooled_o = 0.0, total = 0.0;
    size_t bin, dof = 0;
    memset(observed, 0, sizeof observed);
    for (bin = 0; bin < NM * NP; ++bin) {
        size_t im = bin / NP, ip = bin % NP, a, c;
        double sum = 0.0, dm = 2.0 / NM, dp = 2.0 * LL_TEST_PI / NP;
        for (a = 0; a < SUB; ++a)
            for (c = 0; c < SUB; ++c) {
                double mu = -1.0 + dm * ((double)im + ((double)a + 0.5) / SUB);
                double phi = dp * ((double)ip + ((double)c + 0.5) / SUB);
                sum += ll_test_pdf(b, mu_i, mu, phi, NULL);
            }
        expected[bin] = sum * dm * dp / (SUB * SUB) * (double)n;
        total += expected[bin];
    }
    assert_true(fabs(total / (double)n - 1.0) < 5e-3);
    for (k = 0; k < n; ++k) {
        double u[2], mu_o, phi, pdf, w[3];
        size_t im, ip;
        u[0] = ll_test_uniform(&rng);
        u[1] = ll_test_uniform(&rng);
        assert_int_equal(ll_bsdf_sample(b, mu_i, u, NULL, &mu_o, &phi, &pdf, w), LL_OK);
        assert_true(pdf > 0.0);
        im = (size_t)((mu_o + 1.0) / 2.0 * NM);
        ip = (size_t)(phi / (2.0 * LL_TEST_PI) * NP);
        if (im >= NM) im = NM - 1;
        if (ip >= NP) ip = NP - 1;
        observed[im * NP + ip]++;
    }
    /* Bins expecting fewer than 5 samples are pooled into one. */
    for (bin = 0; bin < NM * NP; ++bin) {
        if (expected[bin] < 5.0) {
            pooled_e += expected[bin];
            pooled_o += (double)observed[bin];
            continue;
        }
        chi2 += ((double)observed[bin] - expected[bin]) * ((double)observed[bin] - expected[bin]) /
                expected[bin];
        ++dof;
    }
    if (pooled_e >= 5.0) {
        chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        ++dof;
    }
    if (!chi2_accept(chi2, (double)(dof - 1)))
        fail_msg("mu_i %g: chi-square %.1f with %zu bins", mu_i, chi2, dof);
}

static void chi_square(void **state)
{
    (void)state;
    chi_square_case(g_lobe, 0.7, 1);
    chi_square_case(g_lobe, -0.35, 2);
    chi_square_case(g_golden, 0.6, 3);
    chi_square_case(g_golden, 0.15, 4);
}

/* The direction, density and f that ll_bsdf_sample_dir returns on the
 * golden file for fixed (wo, u), as the library computes them: the map
 * from u to the direction is pbrt-v3's (u[1] inverts the mu CDF, u[0] the Fourier
 * series in phi), and a renderer that mixes our reader with pbrt-v3's, or
 * compares images, needs it to stay that map, not merely a correct
 * sampler. A faster sampler may reorder sums (the last bits change), not
 * move the direction: 1e-12. wo = (sin t cos a, sin t sin a, cos t) with
 * t = theta[row], a = 0.7 + 1.3 k, u = us[k]. */
static const double g_theta[4] = { 0.05, 0.5, 1.0, 1.45 };
static const double g_us[6][2] = { { 0.02, 0.5 }, { 0.25, 0.1 }, { 0.49, 0.93 },
                                   { 0.5, 0.5 },  { 0.77, 0.31 }, { 0.999, 0.66 } };
static const struct {
    int row, k;
    double wi[3], pdf, rgb[3];
} g_sampled[] = {
    { 0, 0, { -0.22546778039638779, -0.23569257398075616, 0.94531121360822334 },
      1.2096205600797509, { 1.236851996795669, 1.0249282423805337, 0.4155149307190994 } },
    { 0, 1, { 0.12140310688629996, 0.046896370698924834, 0.99149483914623715 },
      1.785921481183149, { 1.7410648281892138, 1.4427562382474428, 0.58484341571171894 } },
    { 0, 2, { -0.59195975131858358, -0.041161907749066556, 0.8049157410370964 },
      0.11858434666716919, { 0.14240366165777824, 0.11800083920968522, 0.047868493078407778 } },
    { 0, 3, { -0.036580762293132105, -0.32411195173365837, 0.94531121360822334 },
      0.88170516400704835, { 0.90155409398337694, 0.74708296881832525, 0.30285462140166503 } },
    { 0, 4, { 0.034842977151788433, 0.23915575426529867, 0.97035585851016326 },
      1.4263878729016961, { 1.42085499437106, 1.1774087200037651, 0.47729124533536876 } },
    { 0, 5, { -0.2455258161782429, -0.31691487091588633, 0.916123374978706 },
      0.88278972820885337, { 0.93142299716637744, 0.77182730481684458, 0.31294567553596253 } },
    { 1, 0, { -0.39188623560865105, -0.34822570614214055, 0.85156563805868102 },
      2.2283995254354489, { 2.5287202304612593, 2.0950304501007357, 0.85514617039043395 } },
    { 1, 1, { 0.20976619945526823, -0.12169339386034488, 0.9701488852010518 },
      1.1638853253578609, { 1.1593669951223753, 0.96066825974071024, 0.38997316769626889 } },
    { 1, 2, { 0.43119840734171605, 0.67985242217879971, 0.59318514610835171 },
      0.044660215384841113, { 0.072736293507909763, 0.060257247618255662, 0.024843326577533745 } },
    { 1, 3, { -0.05879573778808439, -0.52094051992110035, 0.85156563805868102 },
      0.00041549264247758448, { 0.000471663304096857, 0.00039093913367344463, 0.00015582195072580773 } },
    { 1, 4, { -0.29689490688050973, 0.28771989543624732, 0.91053318228308866 },
      1.7806088238120319, { 1.8897998447754876, 1.5657985725309786, 0.63712874469067615 } },
    { 1, 5, { -0.37306677802624871, -0.48553320137334055, 0.79061918108357876 },
      1.9586706822978055, { 2.3938223832033096, 1.9831722225511874, 0.81225441832992673 } },
    { 2, 0, { -0.62387037791047695, -0.5362175948085095, 0.56855645505403918 },
      3.6487300552911681, { 6.1912232482563017, 5.1514530663526843, 2.3067191053928555 } },
    { 2, 1, { 0.34222057716861753, -0.47733251689372402, 0.80934463912370547 },
      1.2853184166547682, { 1.5392417326554195, 1.2758243039266406, 0.53952060810699276 } },
    { 2, 2, { -0.67887019577623708, 0.69528445588782861, 0.23603979047503776 },
      0.0067832852619185867, { 0.027627187701306382, 0.023088152542237689, 0.010419946868920863 } },
    { 2, 3, { -0.0922616310896818, -0.81745418761240429, 0.56855645505403918 },
      0.0032943254800037692, { 0.0055685847797264376, 0.0046546322125361386, 0.002110246169865652 } },
    { 2, 4, { -0.64151355136642474, 0.37010610382702724, 0.67192398031564204 },
      2.5860925164234132, { 3.722571975056578, 3.0904118937436751, 1.3461602525828638 } },
    { 2, 5, { -0.53541647797247272, -0.69787063298865604, 0.47571606524014426 },
      3.5704277150202088, { 7.2185221348861415, 6.0237350988689817, 2.7724681567485576 } },
    { 3, 0, { -0.71722851445888269, -0.60885736976996929, 0.3389335647643934 },
      10.938291216821863, { 30.909404203920893, 27.363432364747062, 16.827144022528049 } },
    { 3, 1, { 0.39878897166163052, -0.70677427869962794, 0.5843265140738354 },
      2.3634351270098422, { 4.0214943758697608, 3.4196153359862795, 1.7712799092025544 } },
    { 3, 2, { -0.6690377723024018, 0.73513072982170213, 0.10941329583031162 },
      0.012151895135090201, { 0.11264577890990919, 0.093905879136668535, 0.042034159551835842 } },
    { 3, 3, { -0.10551425358976523, -0.9348747407891046, 0.33893356476439346 },
      0.031461182602174023, { 0.093889037708152961, 0.078513399515862781, 0.035593294637205612 } },
    { 3, 4, { -0.81422400127641825, 0.38506549677612317, 0.43446960646054056 },
      6.100693844975754, { 13.682690742926868, 11.889466523882584, 6.7924726914832316 } },
    { 3, 5, { -0.58696485980963564, -0.76551524039800634, 0.26355012818634216 },
      13.192265128530423, { 47.199412013387757, 42.489184957011659, 27.81488346007248 } },
};

static void golden_directions_unchanged(void **state)
{
    size_t n;
    (void)state;
    for (n = 0; n < sizeof g_sampled / sizeof g_sampled[0]; ++n) {
        double t = g_theta[g_sampled[n].row], a = 0.7 + 1.3 * g_sampled[n].k;
        double wo[3], wi[3], pdf, rgb[3];
        int c;
        wo[0] = sin(t) * cos(a);
        wo[1] = sin(t) * sin(a);
        wo[2] = cos(t);
        assert_int_equal(ll_bsdf_sample_dir(g_golden, wo, g_us[g_sampled[n].k],
                                            LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, rgb),
                         LL_OK);
        for (c = 0; c < 3; ++c)
            if (fabs(wi[c] - g_sampled[n].wi[c]) > 1e-12 ||
                !ll_test_close(rgb[c], g_sampled[n].rgb[c], 1e-12, 1e-300))
                fail_msg("case %zu, component %d: wi %.17g (was %.17g), f %.17g (was "
                         "%.17g)", n, c, wi[c], g_sampled[n].wi[c], rgb[c],
                         g_sampled[n].rgb[c]);
        if (!ll_test_close(pdf, g_sampled[n].pdf, 1e-12, 1e-300))
            fail_msg("case %zu: pdf %.17g (was %.17g)", n, pdf, g_sampled[n].pdf);
    }
}

/* The ends of the unit interval: u[0] and u[1] at 0 and 1 (pbrt-v3's
 * samplers stop short of 1; ours accept it) give a direction of positive
 * pdf and f, equal to pdf() and eval() there, wherever a u inside gives
 * one: in both conventions and through the batch. At u[1] = 1 the CDF
 * search used to land past the row's mass and return no direction. */
static const double g_ends[4][2] = { { 0.0, 0.0 }, { 0.0, 1.0 }, { 1.0, 0.0 }, { 1.0, 1.0 } };

static void layer_ends(const ll_bsdf *b, const char *name, double mu_i)
{
    const double inside[2] = { 0.3, 0.6 };
    double mu_o, phi, pdf, f[3], g[3];
    int e, c;
    assert_int_equal(ll_bsdf_sample(b, mu_i, inside, NULL, &mu_o, &phi, &pdf, f), LL_OK);
    if (pdf == 0.0)
        return; /* no light scattered from mu_i */
    for (e = 0; e < 4; ++e) {
        assert_int_equal(ll_bsdf_sample(b, mu_i, g_ends[e], NULL, &mu_o, &phi, &pdf, f), LL_OK);
        if (!(pdf > 0.0 && f[0] + f[1] + f[2] > 0.0))
            fail_msg("%s: mu_i %g, u (%g, %g): no direction (pdf %g)", name, mu_i, g_ends[e][0],
                     g_ends[e][1], pdf);
        assert_true(ll_test_close(pdf, ll_test_pdf(b, mu_i, mu_o, phi, NULL), 1e-5, 1e-9));
        assert_int_equal(ll_bsdf_eval(b, mu_i, mu_o, phi, NULL, g), LL_OK);
        for (c = 0; c < 3; ++c)
            assert_true(ll_test_close(f[c], g[c], 1e-5, 1e-9));
    }
}

static void dir_ends(const ll_bsdf *b, const char *name, const double wo[3])
{
    const double inside[2] = { 0.3, 0.6 };
    double wi[3], pdf, f[3], g[3], wos[4 * 3], us[4 * 2], wis[4 * 3], pdfs[4], fs[4 * 3];
    int e, c;
    assert_int_equal(ll_bsdf_sample_dir(b, wo, inside, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f),
                     LL_OK);
    if (pdf == 0.0)
        return;
    for (e = 0; e < 4; ++e) {
        assert_int_equal(
            ll_bsdf_sample_dir(b, wo, g_ends[e], LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f), LL_OK);
        if (!(pdf > 0.0 && f[0] + f[1] + f[2] > 0.0))
            fail_msg("%s: wo (%g, %g, %g), u (%g, %g): no direction (pdf %g)", name, wo[0],
                     wo[1], wo[2], g_ends[e][0], g_ends[e][1], pdf);
        assert_true(ll_test_close(pdf, ll_test_pdf_dir(b, wo, wi, NULL), 1e-5, 1e-9));
        assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, NULL, g), LL_OK);
        for (c = 0; c < 3; ++c)
            assert_true(ll_test_close(f[c], g[c], 1e-5, 1e-9));
        /* The batch gives each element the scalar call's result. */
        for (c = 0; c < 3; ++c)
            wos[3 * e + c] = wo[c];
        us[2 * e] = g_ends[e][0];
        us[2 * e + 1] = g_ends[e][1];
        for (c = 0; c < 3; ++c)
            g[c] = wi[c];
        assert_int_equal(ll_bsdf_sample_dir_batch(b, 1, wo, g_ends[e], LL_TRANSPORT_RADIANCE,
                                                  NULL, 0, wis, pdfs, fs),
                         LL_OK);
        assert_true(pdfs[0] == pdf && wis[0] == g[0] && wis[1] == g[1] && wis[2] == g[2]);
    }
    assert_int_equal(ll_bsdf_sample_dir_batch(b, 4, wos, us, LL_TRANSPORT_RADIANCE, NULL, 0, wis,
                                              pdfs, fs),
                     LL_OK);
    for (e = 0; e < 4; ++e)
        if (!(pdfs[e] > 0.0 && fs[3 * e] + fs[3 * e + 1] + fs[3 * e + 2] > 0.0))
            fail_msg("%s: batch, u (%g, %g): no direction", name, g_ends[e][0], g_ends[e][1]);
}

static void unit_interval_ends(void **state)
{
    static const char *const names[3] = { "golden", "lobe", "white" };
    const ll_bsdf *files[3];
    size_t f;
    int k;
    (void)state;
    files[0] = g_golden;
    files[1] = g_lobe;
    files[2] = g_white;
    for (f = 0; f < 3; ++f)
        for (k = 0; k <= 20; ++k) {
            double mu_i = -1.0 + 0.1 * k, s = sqrt(1.0 - mu_i * mu_i);
            double wo[3] = { 0.8 * s, 0.6 * s, mu_i };
            layer_ends(files[f], names[f], mu_i);
            dir_ends(files[f], names[f], wo);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(consistency),
        cmocka_unit_test(consistency_golden),
        cmocka_unit_test(golden_directions_unchanged),
        cmocka_unit_test(unit_interval_ends),
        cmocka_unit_test(pdf_integrates_to_one),
        cmocka_unit_test(chi_square),
    };
    return cmocka_run_group_tests_name("bsdf_sampling", tests, setup, teardown);
}
