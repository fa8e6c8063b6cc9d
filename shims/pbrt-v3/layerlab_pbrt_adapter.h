/*
 * layerlab_pbrt_adapter.h — the renderer-side half of the pbrt-v3 shim,
 * written so that it needs nothing of pbrt (plain C++11 + <layerlab.h>):
 *
 *   ll_pbrt::Table       one counted reference to an opened .bsdf file
 *                        (copy = ll_bsdf_retain, destruction = ll_bsdf_release);
 *                        an empty Table is the black BSDF.
 *   ll_pbrt::TableCache  files opened once per name and shared by every
 *                        material that names them; failures are reported
 *                        once, through a callback (pbrt's Error()), and
 *                        cached as an empty Table so the material renders
 *                        black instead of crashing.
 *   ll_pbrt::Lobe        f / Pdf / Sample_f with pbrt-v3's FourierBSDF
 *                        conventions, over ll_bsdf_eval_dir, ll_bsdf_pdf_dir
 *                        and ll_bsdf_sample_dir, with the basis weights of
 *                        a textured file.
 *   ll_pbrt::Parameter   a textured file's parameter (name, sampled range),
 *   ll_pbrt::parameters_of, basis_weights: what the material needs to turn
 *                        its per-shading-point parameter values into basis
 *                        weights (ll_bsdf_basis_coefficients).
 *
 * Conventions (pbrt-v3's BxDF interface, which ll_bsdf.h's "renderer
 * convention" was made to match): vectors are in the local shading frame
 * (z = shading normal); wo points to the camera (or the previous vertex),
 * wi to the light, both away from the surface; f excludes the cosine
 * factor; Pdf(wo, wi) is per unit solid angle of wi. In Radiance mode a
 * transmitted value is scaled by eta^2 (pbrt-v3's FourierBSDF::f, the
 * non-symmetric scattering of Veach's thesis, sec. 5.2); Importance mode
 * (light paths) leaves it out.
 *
 * Thread safety: Lobe calls are const and may run on any number of threads
 * (an opened ll_bsdf is immutable); TableCache locks internally.
 */
#ifndef LAYERLAB_PBRT_ADAPTER_H
#define LAYERLAB_PBRT_ADAPTER_H

#include <layerlab.h>

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace ll_pbrt {

/* pbrt-v3's TransportMode, without needing pbrt's headers. */
enum class Transport { Radiance, Importance };

inline ll_transport to_ll_transport(Transport mode) {
    return mode == Transport::Radiance ? LL_TRANSPORT_RADIANCE : LL_TRANSPORT_IMPORTANCE;
}

/* A direction in the local shading frame. make_vec3 accepts pbrt's
 * Vector3f (or anything else with x, y, z members). */
struct Vec3 {
    double x, y, z;
};

template <typename V>
inline Vec3 make_vec3(const V &v) {
    return Vec3{static_cast<double>(v.x), static_cast<double>(v.y),
                static_cast<double>(v.z)};
}

/* Luminance with pbrt-v3's weights (RGBSpectrum::y(), linear sRGB). */
inline double luminance(const double rgb[3]) {
    return 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
}

/* One counted reference to an ll_bsdf, or none (the black BSDF). */
class Table {
  public:
    Table() noexcept : bsdf_(nullptr) {}
    /* Takes over one reference that the caller owns (from ll_bsdf_open). */
    explicit Table(ll_bsdf *owned) noexcept : bsdf_(owned) {}
    Table(const Table &other) noexcept
        : bsdf_(other.bsdf_ ? ll_bsdf_retain(other.bsdf_) : nullptr) {}
    Table(Table &&other) noexcept : bsdf_(other.bsdf_) { other.bsdf_ = nullptr; }
    Table &operator=(Table other) noexcept {
        std::swap(bsdf_, other.bsdf_);
        return *this;
    }
    ~Table() { ll_bsdf_release(bsdf_); }

    bool valid() const noexcept { return bsdf_ != nullptr; }
    const ll_bsdf *get() const noexcept { return bsdf_; }

  private:
    ll_bsdf *bsdf_;
};

/* Why a file cannot be used; "" when it can. A textured file is usable:
 * its parameters become material parameters of the same names (see
 * parameters_of), whose values at each shading point give the basis
 * weights. */
inline std::string unusable_reason(const ll_bsdf *bsdf) {
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (ll_bsdf_get_info(bsdf, &info) != LL_OK)
        return ll_last_error_message();
    if (info.n_bases != 1 && info.n_parameters == 0)
        return "the file has " + std::to_string(info.n_bases) +
               " basis functions but no parameters to weight them by";
    return std::string();
}

/* One textured parameter of a file, in the file's order: its name
 * (ll_bsdf_get_parameter_name: the metadata's, else "p0", "p1", ...) and the
 * range of its sample positions, to which values are clamped. */
struct Parameter {
    std::string name;
    double lo, hi;
    double middle() const { return 0.5 * (lo + hi); }
};

/* The textured parameters of bsdf (empty for an untextured file or a null
 * one). */
inline std::vector<Parameter> parameters_of(const ll_bsdf *bsdf) {
    std::vector<Parameter> out;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (!bsdf || ll_bsdf_get_info(bsdf, &info) != LL_OK) return out;
    for (std::size_t p = 0; p < info.n_parameters; ++p) {
        const char *name = nullptr;
        const float *positions = nullptr;
        std::size_t count = 0;
        if (ll_bsdf_get_parameter_name(bsdf, p, &name) != LL_OK ||
            ll_bsdf_get_parameter(bsdf, p, &count, &positions) != LL_OK || count == 0)
            return std::vector<Parameter>();
        out.push_back(Parameter{name, positions[0], positions[count - 1]});
    }
    return out;
}

/* Number of basis weights a Lobe of bsdf needs (1 for untextured files). */
inline std::size_t basis_count(const ll_bsdf *bsdf) {
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    return bsdf && ll_bsdf_get_info(bsdf, &info) == LL_OK ? info.n_bases : 0;
}

/* The basis weights (basis_count floats into coeffs) of the point whose
 * parameter values are values[0 .. count), count = parameters_of(bsdf).size(),
 * clamped to each parameter's range (ll_bsdf_basis_coefficients: products
 * of linear weights, >= 0, summing to 1). A non-finite value (a texture
 * gone wrong) takes the parameter's lowest sample, so that a shading point
 * never fails; scratch holds count doubles. false only for a null or
 * untextured bsdf or a wrong count. */
inline bool basis_weights(const ll_bsdf *bsdf, const double *values, std::size_t count,
                          double *scratch, float *coeffs) {
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (!bsdf || count == 0 || ll_bsdf_get_info(bsdf, &info) != LL_OK ||
        info.n_parameters != count)
        return false;
    for (std::size_t p = 0; p < count; ++p) {
        const float *positions = nullptr;
        std::size_t n = 0;
        if (ll_bsdf_get_parameter(bsdf, p, &n, &positions) != LL_OK || n == 0) return false;
        scratch[p] = std::isfinite(values[p]) ? values[p] : double(positions[0]);
    }
    return ll_bsdf_basis_coefficients(bsdf, scratch, coeffs) == LL_OK;
}

/* What the material reports when a scene gives no value for a textured
 * parameter (neither "float NAME" nor "texture NAME"): the parameter then
 * takes the middle of its sampled range. */
inline std::string missing_parameter_message(const std::string &path, const Parameter &p) {
    char range[96];
    std::snprintf(range, sizeof range, "%g (the middle of its samples %g .. %g)", p.middle(),
                  p.lo, p.hi);
    return "fourier material: \"" + path + "\" is textured over \"" + p.name +
           "\", which the material does not set (\"float " + p.name + "\" or \"texture " +
           p.name + "\"); using " + range;
}

/* Opens each file once and hands out shared references. */
class TableCache {
  public:
    using Reporter = std::function<void(const std::string &)>;

    /* The table for path, opened on first use. On failure, report (may be
     * empty) receives one message naming the file and layerlab's reason, and
     * the empty (black) Table is returned and remembered, so the message
     * appears once per file however many materials use it. */
    Table acquire(const std::string &path, const Reporter &report) {
        std::lock_guard<std::mutex> lock(mutex_);
        auto found = tables_.find(path);
        if (found != tables_.end()) return found->second;
        Table table = open(path, report);
        tables_.emplace(path, table);
        return table;
    }

    /* Files seen so far (opened or failed). */
    std::size_t size() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return tables_.size();
    }

    /* Drop the cache's own references; tables still used by materials stay
     * alive until those let go. */
    void clear() {
        std::lock_guard<std::mutex> lock(mutex_);
        tables_.clear();
    }

  private:
    static Table open(const std::string &path, const Reporter &report) {
        std::string reason;
        ll_bsdf *bsdf = nullptr;
        if (path.empty()) {
            reason = "no \"bsdffile\" parameter was given";
        } else if (ll_bsdf_open(path.c_str(), nullptr, &bsdf) != LL_OK) {
            /* Read at once: the message is per thread and per failure. */
            reason = ll_last_error_message();
        } else {
            reason = unusable_reason(bsdf);
        }
        Table table(bsdf);
        if (reason.empty()) return table;
        // layerlab's own messages name the file already; ours may not.
        if (path.empty() || reason.find(path) == std::string::npos)
            reason = "cannot use \"" + path + "\": " + reason;
        if (report) report("fourier material: " + reason + "; the material renders black");
        return Table();
    }

    mutable std::mutex mutex_;
    std::map<std::string, Table> tables_;
};

/* Scale v to unit length; false for a zero, infinite or NaN vector. pbrt
 * hands BxDFs vectors that are unit only up to rounding (world-to-local
 * transforms), and the library is entitled to insist on unit ones. */
inline bool normalize_into(const Vec3 &v, double out[3]) {
    double length = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    if (!(length > 0.0) || !std::isfinite(length)) return false;
    out[0] = v.x / length;
    out[1] = v.y / length;
    out[2] = v.z / length;
    return true;
}

inline void set_black(double rgb[3]) { rgb[0] = rgb[1] = rgb[2] = 0.0; }

/* pbrt-v3's FourierBSDF in terms of the library. Holds a borrowed pointer:
 * the material's Table keeps the file alive for as long as the scene (and
 * so every BxDF allocated from it) exists, which keeps atomic reference
 * counting out of the per-intersection path. A null bsdf is black.
 * coeffs: the basis weights of a textured file (basis_weights; borrowed,
 * e.g. from pbrt's per-intersection arena), nullptr for an untextured one;
 * a textured file without weights evaluates to black (the library refuses). */
class Lobe {
  public:
    Lobe(const ll_bsdf *bsdf, Transport mode, const float *coeffs = nullptr) noexcept
        : bsdf_(bsdf), mode_(mode), coeffs_(coeffs) {}

    Transport mode() const noexcept { return mode_; }

    /* f(wo, wi), RGB, without cosine. Black (and false) for an empty table,
     * a degenerate direction or a failed evaluation. */
    bool f(const Vec3 &wo, const Vec3 &wi, double rgb[3]) const {
        set_black(rgb);
        double o[3], i[3];
        if (!bsdf_ || !normalize_into(wo, o) || !normalize_into(wi, i)) return false;
        if (ll_bsdf_eval_dir(bsdf_, o, i, to_ll_transport(mode_), coeffs_, rgb) != LL_OK) {
            set_black(rgb);
            return false;
        }
        return true;
    }

    /* Density (per solid angle) with which sample() picks wi given wo. */
    double pdf(const Vec3 &wo, const Vec3 &wi) const {
        double o[3], i[3];
        if (!bsdf_ || !normalize_into(wo, o) || !normalize_into(wi, i)) return 0.0;
        double p = 0.0;
        if (ll_bsdf_pdf_dir(bsdf_, o, i, coeffs_, &p) != LL_OK) return 0.0;
        return p > 0.0 && std::isfinite(p) ? p : 0.0;
    }

    /* Sample wi given wo from u = (u0, u1) in [0, 1]^2, the way pbrt-v3's
     * FourierBSDF::Sample_f uses its Point2f. Writes wi, its pdf and f(wo,
     * wi) (RGB, no cosine). false, a zero pdf and black when nothing can be
     * sampled; then wi is left as it was. */
    bool sample(const Vec3 &wo, double u0, double u1, Vec3 *wi, double *pdf,
                double rgb[3]) const {
        set_black(rgb);
        *pdf = 0.0;
        double o[3], u[2] = {u0, u1}, w[3], p = 0.0;
        if (!bsdf_ || !normalize_into(wo, o)) return false;
        if (ll_bsdf_sample_dir(bsdf_, o, u, to_ll_transport(mode_), coeffs_, w, &p, rgb) !=
                LL_OK ||
            !(p > 0.0) || !std::isfinite(p)) {
            set_black(rgb);
            return false;
        }
        *wi = Vec3{w[0], w[1], w[2]};
        *pdf = p;
        return true;
    }

  private:
    const ll_bsdf *bsdf_;
    Transport mode_;
    const float *coeffs_;
};

}  // namespace ll_pbrt

#endif  // LAYERLAB_PBRT_ADAPTER_H
