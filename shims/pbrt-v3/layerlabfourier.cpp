/*
 * layerlabfourier.cpp — pbrt-v3's "fourier" material over liblayerlab.
 * The direction and transport-mode logic lives in layerlab_pbrt_adapter.h
 * (tested without pbrt); this file only converts pbrt's types.
 */
#include "materials/layerlabfourier.h"

#include "interaction.h"
#include "memory.h"
#include "paramset.h"
#include "spectrum.h"
#include "texture.h"

namespace pbrt {

namespace {

// Every file is opened once per run and shared by all materials naming it.
// The cache holds one reference per file until exit; each material holds
// its own, so a file stays valid for as long as any material uses it.
ll_pbrt::TableCache &LoadedTables() {
    static ll_pbrt::TableCache cache;
    return cache;
}

Spectrum ToSpectrum(const double rgb[3]) {
    Float c[3] = {Float(rgb[0]), Float(rgb[1]), Float(rgb[2])};
    return Spectrum::FromRGB(c).Clamp();
}

}  // namespace

Spectrum LayerlabFourierBSDF::f(const Vector3f &wo, const Vector3f &wi) const {
    double rgb[3];
    lobe.f(ll_pbrt::make_vec3(wo), ll_pbrt::make_vec3(wi), rgb);
    return ToSpectrum(rgb);
}

Spectrum LayerlabFourierBSDF::Sample_f(const Vector3f &wo, Vector3f *wi,
                                       const Point2f &u, Float *pdf,
                                       BxDFType *sampledType) const {
    ll_pbrt::Vec3 w;
    double rgb[3], p;
    if (sampledType) *sampledType = type;
    if (!lobe.sample(ll_pbrt::make_vec3(wo), u[0], u[1], &w, &p, rgb)) {
        *pdf = 0;
        return Spectrum(0.f);
    }
    *wi = Vector3f(Float(w.x), Float(w.y), Float(w.z));
    *pdf = Float(p);
    return ToSpectrum(rgb);
}

Float LayerlabFourierBSDF::Pdf(const Vector3f &wo, const Vector3f &wi) const {
    return Float(lobe.pdf(ll_pbrt::make_vec3(wo), ll_pbrt::make_vec3(wi)));
}

std::string LayerlabFourierBSDF::ToString() const {
    return std::string("[ LayerlabFourierBSDF mode: ") +
           (lobe.mode() == ll_pbrt::Transport::Radiance ? "RADIANCE" : "IMPORTANCE") +
           " ]";
}

LayerlabFourierMaterial::LayerlabFourierMaterial(
    const std::string &filename, const std::shared_ptr<Texture<Float>> &bumpMap)
    : table(LoadedTables().acquire(
          filename, [](const std::string &message) { Error("%s", message.c_str()); })),
      bumpMap(bumpMap) {}

void LayerlabFourierMaterial::ComputeScatteringFunctions(
    SurfaceInteraction *si, MemoryArena &arena, TransportMode mode,
    bool /* allowMultipleLobes: one lobe either way */) const {
    if (bumpMap) Bump(bumpMap, si);
    si->bsdf = ARENA_ALLOC(arena, BSDF)(*si);
    // No BxDF at all for an unusable file: the surface is black, as with
    // pbrt-v3's own loader after a failed read.
    if (table.valid())
        si->bsdf->Add(ARENA_ALLOC(arena, LayerlabFourierBSDF)(table.get(), mode));
}

LayerlabFourierMaterial *CreateLayerlabFourierMaterial(const TextureParams &mp) {
    std::shared_ptr<Texture<Float>> bumpMap = mp.GetFloatTextureOrNull("bumpmap");
    return new LayerlabFourierMaterial(mp.FindFilename("bsdffile"), bumpMap);
}

}  // namespace pbrt
