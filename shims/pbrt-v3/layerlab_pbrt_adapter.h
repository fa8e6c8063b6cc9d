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
 *                        and ll_bsdf_sample_dir.
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
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <utility>

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

/* Why a file cannot be used; "" when it can. pbrt-v3's fourier material has
 * no parameters that would give the basis weights of a textured file, so
 * such a file is refused here rather than evaluated with made-up weights. */
inline std::string unusable_reason(const ll_bsdf *bsdf) {
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    if (ll_bsdf_get_info(bsdf, &info) != LL_OK)
        return ll_last_error_message();
    if (info.n_bases != 1)
        return "the file is textured (" + std::to_string(info.n_bases) +
               " basis functions), which pbrt-v3's \"fourier\" material cannot "
               "parameterise";
    return std::string();
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
        } else if (ll_bsdf_open(path.c_str(), &bsdf) != LL_OK) {
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
 * counting out of the per-intersection path. A null bsdf is black. */
class Lobe {
  public:
    Lobe(const ll_bsdf *bsdf, Transport mode) noexcept : bsdf_(bsdf), mode_(mode) {}

    Transport mode() const noexcept { return mode_; }

    /* f(wo, wi), RGB, without cosine. Black (and false) for an empty table,
     * a degenerate direction or a failed evaluation. */
    bool f(const Vec3 &wo, const Vec3 &wi, double rgb[3]) const {
        set_black(rgb);
        double o[3], i[3];
        if (!bsdf_ || !normalize_into(wo, o) || !normalize_into(wi, i)) return false;
        if (ll_bsdf_eval_dir(bsdf_, o, i, to_ll_transport(mode_), nullptr, rgb) != LL_OK) {
            set_black(rgb);
            return false;
        }
        return true;
    }

    /* Density (per solid angle) with which sample() picks wi given wo. */
    double pdf(const Vec3 &wo, const Vec3 &wi) const {
        double o[3], i[3];
        if (!bsdf_ || !normalize_into(wo, o) || !normalize_into(wi, i)) return 0.0;
        double p = ll_bsdf_pdf_dir(bsdf_, o, i, nullptr);
        return p > 0.0 && std::isfinite(p) ? p : 0.0;
    }

    /* Sample wi given wo from u = (u0, u1) in [0, 1)^2, the way pbrt-v3's
     * FourierBSDF::Sample_f uses its Point2f. Writes wi, its pdf and f(wo,
     * wi) (RGB, no cosine). false, a zero pdf and black when nothing can be
     * sampled; then wi is left as it was. */
    bool sample(const Vec3 &wo, double u0, double u1, Vec3 *wi, double *pdf,
                double rgb[3]) const {
        set_black(rgb);
        *pdf = 0.0;
        double o[3], u[2] = {u0, u1}, w[3], p = 0.0;
        if (!bsdf_ || !normalize_into(wo, o)) return false;
        if (ll_bsdf_sample_dir(bsdf_, o, u, to_ll_transport(mode_), nullptr, w, &p, rgb) !=
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
};

}  // namespace ll_pbrt

#endif  // LAYERLAB_PBRT_ADAPTER_H
