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
#include "textures/constant.h"

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

namespace {

ll_pbrt::Table AcquireTable(const std::string &filename) {
    return LoadedTables().acquire(
        filename, [](const std::string &message) { Error("%s", message.c_str()); });
}

}  // namespace

LayerlabFourierMaterial::LayerlabFourierMaterial(
    const std::string &filename, const std::shared_ptr<Texture<Float>> &bumpMap)
    : LayerlabFourierMaterial(AcquireTable(filename), {}, bumpMap) {}

LayerlabFourierMaterial::LayerlabFourierMaterial(
    const ll_pbrt::Table &table,
    const std::vector<std::shared_ptr<Texture<Float>>> &parameters,
    const std::shared_ptr<Texture<Float>> &bumpMap)
    : table(table), parameters(parameters), bumpMap(bumpMap) {
    nBases = ll_pbrt::basis_count(table.get());
    // A textured file's parameters must all have a texture (the factory
    // below gives each one); anything else would evaluate without weights.
    if (!this->table.valid() ||
        ll_pbrt::parameters_of(this->table.get()).size() != this->parameters.size())
        this->table = ll_pbrt::Table();
}

void LayerlabFourierMaterial::ComputeScatteringFunctions(
    SurfaceInteraction *si, MemoryArena &arena, TransportMode mode,
    bool /* allowMultipleLobes: one lobe either way */) const {
    if (bumpMap) Bump(bumpMap, si);
    si->bsdf = ARENA_ALLOC(arena, BSDF)(*si);
    // No BxDF at all for an unusable file: the surface is black, as with
    // pbrt-v3's own loader after a failed read.
    if (!table.valid()) return;
    const float *coeffs = nullptr;
    if (!parameters.empty()) {
        // The parameters' values here (after bump mapping, as pbrt's own
        // materials evaluate their textures), then the bases' weights; both
        // live in the intersection's arena, as the BxDF does.
        std::size_t n = parameters.size();
        double *values = arena.Alloc<double>(2 * n);
        float *weights = arena.Alloc<float>(nBases);
        for (std::size_t p = 0; p < n; ++p) values[p] = parameters[p]->Evaluate(*si);
        if (!ll_pbrt::basis_weights(table.get(), values, n, values + n, weights)) return;
        coeffs = weights;
    }
    si->bsdf->Add(ARENA_ALLOC(arena, LayerlabFourierBSDF)(table.get(), mode, coeffs));
}

LayerlabFourierMaterial *CreateLayerlabFourierMaterial(const TextureParams &mp) {
    std::shared_ptr<Texture<Float>> bumpMap = mp.GetFloatTextureOrNull("bumpmap");
    std::string filename = mp.FindFilename("bsdffile");
    ll_pbrt::Table table = AcquireTable(filename);
    // Each textured parameter of the file is a material parameter of the
    // same name: "float NAME" (a constant) or "texture NAME" (any float
    // texture, evaluated at the shading point).
    std::vector<std::shared_ptr<Texture<Float>>> parameters;
    for (const ll_pbrt::Parameter &p : ll_pbrt::parameters_of(table.get())) {
        std::shared_ptr<Texture<Float>> texture = mp.GetFloatTextureOrNull(p.name);
        if (!texture) {
            Warning("%s", ll_pbrt::missing_parameter_message(filename, p).c_str());
            texture = std::make_shared<ConstantTexture<Float>>(Float(p.middle()));
        }
        parameters.push_back(texture);
    }
    return new LayerlabFourierMaterial(table, parameters, bumpMap);
}

}  // namespace pbrt
