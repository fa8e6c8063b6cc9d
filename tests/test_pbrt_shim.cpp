/*
 * Tests of the pbrt-v3 shim's adapter (shims/pbrt-v3/layerlab_pbrt_adapter.h),
 * compiled as C++11 against the shared library by tests/pbrt_shim.sh.
 * Usage: test_pbrt_shim SOURCE_DIR TEMP_DIR
 *
 * Three kinds of evidence:
 *  - the golden file: the numbers pbrt-v3's own FourierBSDF gives for it
 *    (its BSDFs.Fourier unit test; tests/data/README.md);
 *  - a synthetic file built here byte by byte, whose every value follows in
 *    closed form from pbrt-v3's FourierBSDF::f / Pdf formulas: it pins down
 *    which table index is which direction, the azimuth convention, and the
 *    eta^2 factor of pbrt's Radiance transport mode on both sides;
 *  - damaged files (truncated, an offset out of range): reported once
 *    through the callback, rendered black, never a crash;
 *  - a textured synthetic file: its named parameter, and f / Pdf / Sample_f
 *    at parameter values equal to the blend of its bases.
 */
#include "layerlab_pbrt_adapter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

const double kPi = 3.14159265358979323846;

int g_passed = 0, g_failed = 0;

void check(bool ok, const std::string &what) {
    if (ok) {
        ++g_passed;
    } else {
        ++g_failed;
        std::printf("FAIL: %s\n", what.c_str());
    }
}

bool near_rel(double value, double reference, double tolerance) {
    return std::fabs(value - reference) <= tolerance * std::fabs(reference);
}

void check_rel(double value, double reference, double tolerance, const std::string &what) {
    char detail[160];
    std::snprintf(detail, sizeof detail, " (got %.7g, want %.7g, rel. tol. %g)", value,
                  reference, tolerance);
    check(near_rel(value, reference, tolerance), what + detail);
}

ll_pbrt::Vec3 normalized(double x, double y, double z) {
    double length = std::sqrt(x * x + y * y + z * z);
    return ll_pbrt::Vec3{x / length, y / length, z / length};
}

/* The unit vector with zenith cosine z and azimuth phi. */
ll_pbrt::Vec3 spherical(double z, double phi) {
    double s = std::sqrt(1.0 - z * z);
    return ll_pbrt::Vec3{s * std::cos(phi), s * std::sin(phi), z};
}

std::vector<unsigned char> read_bytes(const std::string &path) {
    std::ifstream in(path.c_str(), std::ios::binary);
    return std::vector<unsigned char>(std::istreambuf_iterator<char>(in),
                                      std::istreambuf_iterator<char>());
}

bool write_bytes(const std::string &path, const std::vector<unsigned char> &bytes) {
    std::ofstream out(path.c_str(), std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char *>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    return static_cast<bool>(out);
}

/* Collects what the cache reports, as pbrt's Error() would print it. */
struct Messages {
    std::vector<std::string> list;
    ll_pbrt::TableCache::Reporter reporter() {
        return [this](const std::string &m) { list.push_back(m); };
    }
};

/* ------------------------------------------------------- golden file */

const double kGoldenWo[3] = {-0.5, -0.5, 0.8};
const double kGoldenWi[3] = {0.4, 0.52, 0.7};

void test_golden_values(const std::string &golden) {
    ll_pbrt::TableCache cache;
    Messages messages;
    ll_pbrt::Table table = cache.acquire(golden, messages.reporter());
    check(table.valid(), "golden file opens");
    check(messages.list.empty(), "golden file: nothing reported");
    if (!table.valid()) return;

    ll_pbrt::Vec3 wo = normalized(kGoldenWo[0], kGoldenWo[1], kGoldenWo[2]);
    ll_pbrt::Vec3 wi = normalized(kGoldenWi[0], kGoldenWi[1], kGoldenWi[2]);
    // pbrt-v3's unit test evaluates in Importance mode; with eta = 1 and a
    // reflection pair, Radiance mode must give the same value.
    for (int m = 0; m < 2; ++m) {
        ll_pbrt::Transport mode = m ? ll_pbrt::Transport::Radiance : ll_pbrt::Transport::Importance;
        std::string tag = m ? " (radiance)" : " (importance)";
        ll_pbrt::Lobe lobe(table.get(), mode);
        double rgb[3];
        check(lobe.f(wo, wi, rgb), "golden f succeeds" + tag);
        check_rel(ll_pbrt::luminance(rgb), 2.679294, 1e-3, "golden f(wo, wi).y()" + tag);
        check_rel(lobe.pdf(wo, wi), 2.438230, 1e-3, "golden Pdf(wo, wi)" + tag);
        check_rel(lobe.pdf(wi, wo), 2.503326, 1e-3, "golden Pdf(wi, wo)" + tag);

        ll_pbrt::Vec3 ws{0, 0, 0};
        double pdf = 0;
        check(lobe.sample(wo, 0.1, 0.8, &ws, &pdf, rgb), "golden Sample_f succeeds" + tag);
        check_rel(ll_pbrt::luminance(rgb), 2.596391, 1e-3, "golden Sample_f f.y()" + tag);
        check_rel(pdf, 1.855472, 1e-3, "golden Sample_f pdf" + tag);
        check_rel(ws.x, 0.539052, 1e-3, "golden Sample_f wi.x" + tag);
        check_rel(ws.y, 0.617347, 1e-3, "golden Sample_f wi.y" + tag);
        check_rel(ws.z, 0.572980, 1e-3, "golden Sample_f wi.z" + tag);
    }
}

/* The adapter normalises what pbrt hands it (unit only up to rounding) and
 * turns degenerate directions into black rather than errors. */
void test_golden_direction_handling(const std::string &golden) {
    ll_pbrt::TableCache cache;
    ll_pbrt::Table table = cache.acquire(golden, nullptr);
    if (!table.valid()) {
        check(false, "golden file opens (direction handling)");
        return;
    }
    ll_pbrt::Lobe lobe(table.get(), ll_pbrt::Transport::Radiance);
    ll_pbrt::Vec3 wo = normalized(kGoldenWo[0], kGoldenWo[1], kGoldenWo[2]);
    ll_pbrt::Vec3 wi = normalized(kGoldenWi[0], kGoldenWi[1], kGoldenWi[2]);
    ll_pbrt::Vec3 wo_long{3 * wo.x, 3 * wo.y, 3 * wo.z};
    ll_pbrt::Vec3 wi_short{0.5 * wi.x, 0.5 * wi.y, 0.5 * wi.z};
    double a[3], b[3];
    lobe.f(wo, wi, a);
    lobe.f(wo_long, wi_short, b);
    check(near_rel(b[0], a[0], 1e-9) && near_rel(b[1], a[1], 1e-9) &&
              near_rel(b[2], a[2], 1e-9),
          "f ignores the length of wo and wi");
    check(near_rel(lobe.pdf(wo_long, wi_short), lobe.pdf(wo, wi), 1e-9),
          "Pdf ignores the length of wo and wi");

    const ll_pbrt::Vec3 zero{0, 0, 0}, nan{std::nan(""), 0, 1};
    check(!lobe.f(zero, wi, a) && a[0] == 0 && a[1] == 0 && a[2] == 0,
          "zero-length wo gives black");
    check(!lobe.f(wo, nan, a) && a[0] == 0, "NaN wi gives black");
    check(lobe.pdf(nan, wi) == 0.0, "NaN wo gives pdf 0");
    ll_pbrt::Vec3 ws{7, 7, 7};
    double pdf = 1;
    check(!lobe.sample(zero, 0.5, 0.5, &ws, &pdf, a) && pdf == 0 && a[0] == 0 && ws.x == 7,
          "sampling from a zero-length wo gives nothing");
}

/* Sample_f and f / Pdf describe the same distribution: the sampled pdf and
 * value equal Pdf and f at the sampled direction, and the estimate of the
 * albedo by importance sampling agrees with one by uniform sampling. */
void test_golden_sampling_consistency(const std::string &golden) {
    ll_pbrt::TableCache cache;
    ll_pbrt::Table table = cache.acquire(golden, nullptr);
    if (!table.valid()) {
        check(false, "golden file opens (sampling)");
        return;
    }
    ll_pbrt::Lobe lobe(table.get(), ll_pbrt::Transport::Importance);
    ll_pbrt::Vec3 wo = spherical(0.7, 0.4);
    const int n = 64;
    int mismatched_pdf = 0, mismatched_f = 0, not_unit = 0;
    double importance = 0, uniform = 0;
    for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
            double u0 = (a + 0.5) / n, u1 = (b + 0.5) / n;
            ll_pbrt::Vec3 wi{0, 0, 0};
            double pdf, rgb[3], again[3];
            if (lobe.sample(wo, u0, u1, &wi, &pdf, rgb)) {
                double length = std::sqrt(wi.x * wi.x + wi.y * wi.y + wi.z * wi.z);
                if (std::fabs(length - 1) > 1e-6) ++not_unit;
                if (!near_rel(lobe.pdf(wo, wi), pdf, 2e-3)) ++mismatched_pdf;
                lobe.f(wo, wi, again);
                if (std::fabs(ll_pbrt::luminance(again) - ll_pbrt::luminance(rgb)) >
                    2e-3 * ll_pbrt::luminance(again) + 1e-6)
                    ++mismatched_f;
                importance += ll_pbrt::luminance(rgb) * std::fabs(wi.z) / pdf;
            }
            // Uniform over the upper hemisphere (pdf 1 / (2 pi)), stratified.
            ll_pbrt::Vec3 wu = spherical(u0, 2 * kPi * u1);
            double f[3];
            lobe.f(wo, wu, f);
            uniform += ll_pbrt::luminance(f) * wu.z * 2 * kPi;
        }
    }
    importance /= n * n;
    uniform /= n * n;
    check(not_unit == 0, "sampled directions have unit length");
    check(mismatched_pdf == 0, "sampled pdf equals Pdf(wo, wi) (" +
                                   std::to_string(mismatched_pdf) + " of 4096 differ)");
    check(mismatched_f == 0, "sampled value equals f(wo, wi) (" +
                                 std::to_string(mismatched_f) + " of 4096 differ)");
    check_rel(importance, uniform, 0.02, "albedo: importance-sampled vs uniform estimate");
    check(uniform > 0.7 && uniform < 0.9, "albedo of rough gold is about 0.81 (got " +
                                              std::to_string(uniform) + ")");
}

/* ------------------------------------------------------ synthetic file */

/* A small file whose values are known in closed form. Nodes: +-0.2 .. +-1
 * and the two zero nodes; every pair of non-zero nodes holds the two-term
 * series a0 + a1 cos(phi), constant within each of the four sign blocks.
 * The blocks are named by pbrt-v3's own quantities muI = cos(-wi) (the fast
 * index of the table) and muO = cos(wo) (the slow index). */
struct Synthetic {
    std::vector<float> nodes{-1.0f, -0.8f, -0.6f, -0.4f, -0.2f, 0.0f,
                             0.0f,  0.2f,  0.4f,  0.6f,  0.8f,  1.0f};
    float eta = 1.5f;
    std::uint32_t n_bases = 1;  // 2: one textured parameter "coat.alpha" sampled at 0, 1

    /* Basis b holds the table times 1 + 2 b (textured files: the bases differ). */
    static double basis_scale(std::uint32_t b) { return 1.0 + 2.0 * b; }

    // [muI > 0][muO > 0]: a0 and a1. muI * muO > 0 is transmission.
    double a0[2][2] = {{0.20, 0.50}, {0.70, 0.30}};
    double a1[2][2] = {{0.05, 0.20}, {0.30, 0.10}};

    double coefficient(std::size_t o, std::size_t i, int k) const {
        int si = nodes[o] > 0, so = nodes[i] > 0;
        return k == 0 ? a0[si][so] : a1[si][so];
    }

    /* Integral over mu of the Catmull-Rom spline through (nodes, f), with
     * derivatives by central differences inside and one-sided differences
     * at the ends (the CDF the format stores); cumulative values. */
    std::vector<double> running_integral(const std::vector<double> &f) const {
        std::size_t n = nodes.size();
        std::vector<double> sum(n, 0.0);
        for (std::size_t j = 0; j + 1 < n; ++j) {
            double x0 = nodes[j], x1 = nodes[j + 1], width = x1 - x0;
            double f0 = f[j], f1 = f[j + 1];
            double d0 = j > 0 ? width * (f1 - f[j - 1]) / (x1 - nodes[j - 1]) : f1 - f0;
            double d1 = j + 2 < n ? width * (f[j + 2] - f0) / (nodes[j + 2] - x0) : f1 - f0;
            sum[j + 1] = sum[j] + ((d0 - d1) * (1.0 / 12.0) + (f0 + f1) * 0.5) * width;
        }
        return sum;
    }

    /* The integral of a0 over all mu_i for a muO node of the given sign. */
    double row_total(int muO_positive) const {
        std::size_t i = muO_positive ? nodes.size() - 1 : 0;
        std::vector<double> f(nodes.size());
        for (std::size_t o = 0; o < nodes.size(); ++o)
            f[o] = nodes[o] == 0 ? 0.0 : coefficient(o, i, 0);
        return running_integral(f).back();
    }

    std::vector<unsigned char> bytes() const {
        std::vector<unsigned char> out;
        auto u32 = [&out](std::uint32_t v) {
            for (int s = 0; s < 32; s += 8) out.push_back(static_cast<unsigned char>(v >> s));
        };
        auto f32 = [&u32](float v) {
            std::uint32_t bits;
            std::memcpy(&bits, &v, 4);
            u32(bits);
        };
        const std::uint32_t n = static_cast<std::uint32_t>(nodes.size());
        const std::uint32_t length = 2;
        std::uint32_t pairs = 0;
        for (float x : nodes) pairs += x != 0;
        pairs *= pairs;
        const std::string metadata =
            n_bases > 1 ? "{\"synthetic\": true, \"parameters\": [\"coat.alpha\"]}"
                        : "{\"synthetic\": true}";

        const char magic[8] = {'S', 'C', 'A', 'T', 'F', 'U', 'N', 1};
        out.insert(out.end(), magic, magic + 8);
        u32(1);                                   // flags: a BSDF
        u32(n);                                   // nNodes
        u32(pairs * length * n_bases);            // nCoeffs (one channel)
        u32(length);                              // nMaxOrder
        u32(1);                                   // nChannels
        u32(n_bases);                             // nBases
        u32(static_cast<std::uint32_t>(metadata.size()));
        u32(n_bases > 1 ? 1 : 0);                 // nParameters
        u32(n_bases > 1 ? n_bases : 0);           // nParameterValues
        f32(eta);
        f32(0.1f);
        f32(0.1f);                                // alpha (informational)
        f32(0.0f);
        f32(0.0f);                                // unused

        for (float x : nodes) f32(x);
        if (n_bases > 1) {
            u32(n_bases);
            for (std::uint32_t b = 0; b < n_bases; ++b) f32(float(b) / float(n_bases - 1));
        }
        for (std::uint32_t i = 0; i < n; ++i) {  // CDF rows, per incident node
            std::vector<double> f(n);
            for (std::uint32_t o = 0; o < n; ++o)
                f[o] = nodes[o] == 0 || nodes[i] == 0 ? 0.0 : coefficient(o, i, 0);
            std::vector<double> cdf = running_integral(f);
            for (std::uint32_t o = 0; o < n; ++o)
                for (std::uint32_t b = 0; b < n_bases; ++b) f32(float(cdf[o] * basis_scale(b)));
        }
        std::uint32_t offset = 0;
        for (std::uint32_t i = 0; i < n; ++i) {  // offset table, entry o + i n
            for (std::uint32_t o = 0; o < n; ++o) {
                bool stored = nodes[o] != 0 && nodes[i] != 0;
                u32(stored ? offset : 0);
                u32(stored ? length : 0);
                if (stored) offset += length * n_bases;
            }
        }
        for (std::uint32_t i = 0; i < n; ++i)
            for (std::uint32_t o = 0; o < n; ++o)
                if (nodes[o] != 0 && nodes[i] != 0)
                    for (std::uint32_t b = 0; b < n_bases; ++b)
                        for (std::uint32_t k = 0; k < length; ++k)
                            f32(float(coefficient(o, i, int(k)) * basis_scale(b)));
        out.insert(out.end(), metadata.begin(), metadata.end());
        return out;
    }

    /* pbrt-v3's FourierBSDF::f for this table, by its own formulas. */
    double expected_f(const ll_pbrt::Vec3 &wo, const ll_pbrt::Vec3 &wi,
                      ll_pbrt::Transport mode) const {
        double muI = -wi.z, muO = wo.z;
        double cos_phi = (-wi.x * wo.x - wi.y * wo.y) /
                         std::sqrt((wi.x * wi.x + wi.y * wi.y) * (wo.x * wo.x + wo.y * wo.y));
        int si = muI > 0, so = muO > 0;
        double y = std::max(0.0, a0[si][so] + a1[si][so] * cos_phi);
        double scale = 1.0 / std::fabs(muI);
        if (mode == ll_pbrt::Transport::Radiance && muI * muO > 0) {
            double e = muI > 0 ? 1.0 / double(eta) : double(eta);
            scale *= e * e;
        }
        return y * scale;
    }

    /* pbrt-v3's FourierBSDF::Pdf: the series over 2 pi times the row total. */
    double expected_pdf(const ll_pbrt::Vec3 &wo, const ll_pbrt::Vec3 &wi) const {
        double muI = -wi.z, muO = wo.z;
        double cos_phi = (-wi.x * wo.x - wi.y * wo.y) /
                         std::sqrt((wi.x * wi.x + wi.y * wi.y) * (wo.x * wo.x + wo.y * wo.y));
        int si = muI > 0, so = muO > 0;
        double y = a0[si][so] + a1[si][so] * cos_phi;
        double rho = 2 * kPi * row_total(so);
        return y > 0 && rho > 0 ? y / rho : 0.0;
    }
};

void test_synthetic_conventions(const std::string &dir) {
    Synthetic synthetic;
    std::string path = dir + "/synthetic.bsdf";
    check(write_bytes(path, synthetic.bytes()), "write the synthetic file");
    ll_pbrt::TableCache cache;
    Messages messages;
    ll_pbrt::Table table = cache.acquire(path, messages.reporter());
    check(table.valid(), "synthetic file opens" +
                             (messages.list.empty() ? std::string() : ": " + messages.list[0]));
    if (!table.valid()) return;

    // |z| of 0.45 .. 0.55 keeps every spline neighbour inside one block
    // (nodes 0.2 .. 0.8), where the interpolation reproduces the constants
    // exactly; azimuths chosen to exercise both signs of cos(phi).
    const double zs[2] = {0.45, 0.55};
    const double phis[3] = {0.3, 1.9, 3.6};
    int cases = 0, wrong_f[2] = {0, 0}, wrong_pdf = 0, wrong_sample = 0;
    std::string first_failure, sample_failure;
    for (int mode_index = 0; mode_index < 2; ++mode_index) {
        ll_pbrt::Transport mode =
            mode_index ? ll_pbrt::Transport::Radiance : ll_pbrt::Transport::Importance;
        ll_pbrt::Lobe lobe(table.get(), mode);
        for (int so = -1; so <= 1; so += 2)
            for (int si = -1; si <= 1; si += 2)
                for (double zo : zs)
                    for (double zi : zs)
                        for (double phi_o : phis)
                            for (double phi_i : phis) {
                                ll_pbrt::Vec3 wo = spherical(so * zo, phi_o);
                                ll_pbrt::Vec3 wi = spherical(si * zi, phi_i + 0.7);
                                double rgb[3];
                                lobe.f(wo, wi, rgb);
                                double want = synthetic.expected_f(wo, wi, mode);
                                ++cases;
                                if (!(near_rel(rgb[0], want, 1e-4) && rgb[1] == rgb[0] &&
                                      rgb[2] == rgb[0])) {
                                    ++wrong_f[mode_index];
                                    if (first_failure.empty()) {
                                        char text[200];
                                        std::snprintf(text, sizeof text,
                                                      "wo.z %+.2f wi.z %+.2f %s: f %.6g, "
                                                      "pbrt-v3 gives %.6g",
                                                      wo.z, wi.z,
                                                      mode_index ? "radiance" : "importance",
                                                      rgb[0], want);
                                        first_failure = text;
                                    }
                                }
                                if (!near_rel(lobe.pdf(wo, wi), synthetic.expected_pdf(wo, wi),
                                              1e-3))
                                    ++wrong_pdf;
                            }
        // Samples agree with f and Pdf, on both sides of the surface. u[1]
        // (which picks the zenith) stays off 0 and 1: there wi is the pole,
        // where this unphysical table's a1 != 0 leaves f without a defined
        // azimuth.
        for (int so = -1; so <= 1; so += 2)
            for (int k = 0; k < 16; ++k) {
                ll_pbrt::Vec3 wo = spherical(so * 0.5, 0.4 * k);
                ll_pbrt::Vec3 wi{0, 0, 0};
                double pdf, rgb[3], f[3];
                double u0 = (k + 0.5) / 16, u1 = 0.05 + 0.9 * std::fmod(0.37 * k, 1.0);
                if (!lobe.sample(wo, u0, u1, &wi, &pdf, rgb)) {
                    ++wrong_sample;
                    continue;
                }
                lobe.f(wo, wi, f);
                double again = lobe.pdf(wo, wi);
                if (!near_rel(pdf, again, 2e-3) || !near_rel(rgb[0], f[0], 2e-3)) {
                    ++wrong_sample;
                    char text[200];
                    std::snprintf(text, sizeof text,
                                  "wo.z %+.2f -> wi (%.4f %.4f %.4f): pdf %.6g vs Pdf %.6g, "
                                  "f %.6g vs %.6g",
                                  wo.z, wi.x, wi.y, wi.z, pdf, again, rgb[0], f[0]);
                    if (sample_failure.empty()) sample_failure = text;
                }
            }
    }
    check(wrong_f[0] == 0, "synthetic f matches pbrt-v3's formula, importance mode (" +
                               std::to_string(wrong_f[0]) + " of " + std::to_string(cases / 2) +
                               " differ" + (first_failure.empty() ? "" : "; " + first_failure) +
                               ")");
    check(wrong_f[1] == 0, "synthetic f matches pbrt-v3's formula incl. eta^2, radiance mode (" +
                               std::to_string(wrong_f[1]) + " of " + std::to_string(cases / 2) +
                               " differ" + (first_failure.empty() ? "" : "; " + first_failure) +
                               ")");
    check(wrong_pdf == 0, "synthetic Pdf matches pbrt-v3's formula (" +
                              std::to_string(wrong_pdf) + " of " + std::to_string(cases) +
                              " differ)");
    check(wrong_sample == 0, "synthetic samples agree with f and Pdf (" +
                                 std::to_string(wrong_sample) + " of 64 differ" +
                                 (sample_failure.empty() ? "" : "; " + sample_failure) + ")");

    // The ratio radiance / importance is exactly pbrt-v3's eta^2 factor.
    ll_pbrt::Lobe radiance(table.get(), ll_pbrt::Transport::Radiance);
    ll_pbrt::Lobe importance(table.get(), ll_pbrt::Transport::Importance);
    ll_pbrt::Vec3 up = spherical(0.5, 0.2), down = spherical(-0.5, 2.0);
    double r[3], i[3];
    radiance.f(up, down, r);
    importance.f(up, down, i);
    check_rel(r[0] / i[0], 1 / (1.5 * 1.5), 1e-5, "radiance/importance, wo above, wi below");
    radiance.f(down, up, r);
    importance.f(down, up, i);
    check_rel(r[0] / i[0], 1.5 * 1.5, 1e-5, "radiance/importance, wo below, wi above");
    radiance.f(up, spherical(0.5, 2.0), r);
    importance.f(up, spherical(0.5, 2.0), i);
    check(r[0] == i[0], "reflection: radiance and importance agree");
}

/* ------------------------------------------------ cache and failures */

void test_cache_shares_and_counts(const std::string &golden) {
    ll_pbrt::TableCache cache;
    Messages messages;
    ll_pbrt::Table a = cache.acquire(golden, messages.reporter());
    ll_pbrt::Table b = cache.acquire(golden, messages.reporter());
    check(a.valid() && a.get() == b.get(), "one file name, one shared ll_bsdf");
    check(cache.size() == 1, "the cache holds one entry per file");

    // The cache's reference and the materials' are independent: dropping
    // the cache leaves the tables usable (ASan would see a use after free).
    cache.clear();
    check(cache.size() == 0, "clear empties the cache");
    ll_pbrt::Table c = a;            // retain
    a = ll_pbrt::Table();            // release
    ll_pbrt::Table d(std::move(b));  // moves, no count change
    check(!b.valid() && c.get() == d.get(), "copies and moves keep one ll_bsdf");
    ll_pbrt::Lobe lobe(d.get(), ll_pbrt::Transport::Importance);
    double rgb[3];
    lobe.f(normalized(kGoldenWo[0], kGoldenWo[1], kGoldenWo[2]),
           normalized(kGoldenWi[0], kGoldenWi[1], kGoldenWi[2]), rgb);
    check_rel(ll_pbrt::luminance(rgb), 2.679294, 1e-3, "a table outlives the cache");
    ll_pbrt::Table reopened = cache.acquire(golden, messages.reporter());
    check(reopened.valid(), "a cleared cache opens the file again");
    check(messages.list.empty(), "no messages for a good file");
}

/* An unusable file: reported once, naming the file; black afterwards. */
void expect_black(ll_pbrt::TableCache &cache, const std::string &path, const std::string &what,
                  const std::string &reason_part) {
    Messages messages;
    ll_pbrt::Table first = cache.acquire(path, messages.reporter());
    ll_pbrt::Table second = cache.acquire(path, messages.reporter());
    check(!first.valid() && !second.valid(), what + ": the table is empty (black)");
    check(messages.list.size() == 1, what + ": reported exactly once (" +
                                         std::to_string(messages.list.size()) + " times)");
    if (messages.list.empty()) return;
    const std::string &m = messages.list[0];
    check(m.find(path) != std::string::npos, what + ": the message names the file: " + m);
    check(reason_part.empty() || m.find(reason_part) != std::string::npos,
          what + ": the message says why (" + reason_part + "): " + m);

    ll_pbrt::Lobe lobe(first.get(), ll_pbrt::Transport::Radiance);
    ll_pbrt::Vec3 wo = spherical(0.5, 0.0), wi = spherical(0.5, 3.0), ws{1, 2, 3};
    double rgb[3] = {1, 1, 1}, pdf = 1;
    check(!lobe.f(wo, wi, rgb) && rgb[0] == 0 && rgb[1] == 0 && rgb[2] == 0,
          what + ": f is black");
    check(lobe.pdf(wo, wi) == 0, what + ": Pdf is 0");
    check(!lobe.sample(wo, 0.3, 0.6, &ws, &pdf, rgb) && pdf == 0 && rgb[0] == 0,
          what + ": Sample_f gives nothing");
}

void test_unusable_files(const std::string &golden, const std::string &dir) {
    ll_pbrt::TableCache cache;
    expect_black(cache, dir + "/does-not-exist.bsdf", "missing file", "");
    expect_black(cache, "", "no file name", "bsdffile");

    std::vector<unsigned char> good = read_bytes(golden);
    check(good.size() == 207354, "golden file has its documented size");
    if (good.size() != 207354) return;
    // Cuts inside the header, the nodes, the CDF, the offset table, the
    // coefficients and the metadata, and one byte short.
    const std::size_t cuts[] = {0, 5, 40, 100, 5000, 14000, 100000, 206700, 207353};
    for (std::size_t cut : cuts) {
        std::string path = dir + "/truncated_" + std::to_string(cut) + ".bsdf";
        write_bytes(path, std::vector<unsigned char>(good.begin(), good.begin() + cut));
        expect_black(cache, path, "golden file cut to " + std::to_string(cut) + " bytes", "");
    }

    // Offset of the pair (o, i) = (17, 40), a stored reflection series,
    // far beyond the coefficients: the damage that makes pbrt-v3's own
    // loader read out of bounds. The table
    // starts after the header, 58 nodes and the 58 x 58 CDF.
    std::vector<unsigned char> bad = good;
    std::size_t entry = 64 + 58 * 4 + 58 * 58 * 4 + 8 * (17 + 40 * 58);
    const unsigned char huge[4] = {0x00, 0x00, 0x00, 0x70};
    std::copy(huge, huge + 4, bad.begin() + static_cast<std::ptrdiff_t>(entry));
    write_bytes(dir + "/bad_offset.bsdf", bad);
    expect_black(cache, dir + "/bad_offset.bsdf", "offset out of range", "");

    bad = good;  // an over-long series: length 0x10000 > nMaxOrder
    bad[entry + 4] = 0x00;
    bad[entry + 5] = 0x00;
    bad[entry + 6] = 0x01;
    bad[entry + 7] = 0x00;
    write_bytes(dir + "/bad_length.bsdf", bad);
    expect_black(cache, dir + "/bad_length.bsdf", "series longer than nMaxOrder", "");
}

/* ---------------------------------------------------- textured files */

/* A textured file (the synthetic table, basis b scaled by 1 + 2 b, one
 * parameter "coat.alpha" sampled at 0 and 1): usable, its parameter named
 * and ranged, and f / Pdf / Sample_f at a parameter value equal to the
 * linear blend of the bases, as pbrt's material evaluates it at a shading
 * point. */
void test_textured_files(const std::string &dir) {
    Synthetic textured;
    textured.n_bases = 2;
    std::string path = dir + "/textured.bsdf";
    check(write_bytes(path, textured.bytes()), "write the textured file");
    ll_pbrt::TableCache cache;
    Messages messages;
    ll_pbrt::Table table = cache.acquire(path, messages.reporter());
    check(table.valid() && messages.list.empty(),
          "a textured file is usable" +
              (messages.list.empty() ? std::string() : ": " + messages.list[0]));
    if (!table.valid()) return;
    std::vector<ll_pbrt::Parameter> params = ll_pbrt::parameters_of(table.get());
    check(params.size() == 1 && params[0].name == "coat.alpha" && params[0].lo == 0.0 &&
              params[0].hi == 1.0,
          "the file's parameter: \"coat.alpha\" over [0, 1]");
    check(ll_pbrt::basis_count(table.get()) == 2, "two bases");
    check(ll_pbrt::parameters_of(nullptr).empty(), "no parameters for a null file");

    const ll_pbrt::Vec3 wo = spherical(0.5, 0.3), wi = spherical(0.45, 1.9 + 0.7);
    const double want = textured.expected_f(wo, wi, ll_pbrt::Transport::Radiance);
    const double want_pdf = textured.expected_pdf(wo, wi);
    // value -> the blend 0.75 x 1 + 0.25 x 3 etc.; outside the range and
    // not finite: clamped, the lowest sample.
    const double values[5] = {0.25, 0.0, 1.0, -5.0, 7.0};
    const double blends[5] = {1.5, 1.0, 3.0, 1.0, 3.0};
    for (int k = 0; k < 5; ++k) {
        float w[2] = {-1, -1};
        double scratch[1];
        std::string at = "coat.alpha = " + std::to_string(values[k]);
        check(ll_pbrt::basis_weights(table.get(), &values[k], 1, scratch, w), at + ": weights");
        ll_pbrt::Lobe lobe(table.get(), ll_pbrt::Transport::Radiance, w);
        double rgb[3];
        lobe.f(wo, wi, rgb);
        check_rel(rgb[0], want * blends[k], 1e-4, at + ": f is the blend of the bases");
        // The pdf is f |cos| over the albedo, both blended alike.
        check_rel(lobe.pdf(wo, wi), want_pdf, 1e-3, at + ": Pdf as the untextured table's");
        ll_pbrt::Vec3 ws{0, 0, 0};
        double pdf = 0, f[3];
        bool sampled = lobe.sample(wo, 0.3, 0.6, &ws, &pdf, rgb);
        lobe.f(wo, ws, f);
        check(sampled && near_rel(pdf, lobe.pdf(wo, ws), 2e-3) && near_rel(rgb[0], f[0], 2e-3),
              at + ": Sample_f agrees with f and Pdf");
    }
    {
        const double nan = std::nan("");
        float w[2] = {-1, -1};
        double scratch[1];
        check(ll_pbrt::basis_weights(table.get(), &nan, 1, scratch, w) && w[0] == 1 && w[1] == 0,
              "a NaN value takes the lowest sample");
        check(!ll_pbrt::basis_weights(table.get(), values, 2, scratch, w) &&
                  !ll_pbrt::basis_weights(nullptr, values, 1, scratch, w),
              "weights refused for a wrong count or no file");
    }
    // A textured table without weights is black, not evaluated with guesses.
    ll_pbrt::Lobe unweighted(table.get(), ll_pbrt::Transport::Radiance);
    double rgb[3] = {1, 1, 1};
    check(!unweighted.f(wo, wi, rgb) && rgb[0] == 0, "no weights: black");
    std::string m = ll_pbrt::missing_parameter_message(path, params[0]);
    check(m.find(path) != std::string::npos && m.find("\"float coat.alpha\"") != std::string::npos &&
              m.find("using 0.5") != std::string::npos,
          "the message for an unset parameter names file, parameter and value: " + m);

    // An untextured file: no parameters, one basis, as before.
    Synthetic untextured;
    std::vector<unsigned char> bytes = untextured.bytes();
    check(write_bytes(dir + "/untextured.bsdf", bytes), "write the untextured file");
    ll_pbrt::Table plain = cache.acquire(dir + "/untextured.bsdf", messages.reporter());
    check(plain.valid() && ll_pbrt::parameters_of(plain.get()).empty() &&
              ll_pbrt::basis_count(plain.get()) == 1,
          "an untextured file has no parameters and one basis");
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s SOURCE_DIR TEMP_DIR\n", argv[0]);
        return 2;
    }
    const std::string golden =
        std::string(argv[1]) + "/tests/data/roughgold_alpha_0.2.bsdf";
    const std::string dir = argv[2];

    test_golden_values(golden);
    test_golden_direction_handling(golden);
    test_golden_sampling_consistency(golden);
    test_synthetic_conventions(dir);
    test_cache_shares_and_counts(golden);
    test_unusable_files(golden, dir);
    test_textured_files(dir);

    std::printf("%d passed, %d failed\n", g_passed, g_failed);
    return g_failed == 0 ? 0 : 1;
}
