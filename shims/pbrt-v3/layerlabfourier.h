/*
 * layerlabfourier.h — pbrt-v3's "fourier" material, reading .bsdf files
 * through liblayerlab (goes to src/materials/ of a pbrt-v3 checkout; see
 * README.md).
 *
 * Why: pbrt-v3's own FourierBSDFTable::Read trusts the file's counts and
 * offsets, so a damaged file crashes the renderer. ll_bsdf_open validates
 * every field first; a file it rejects is reported through Error() and the
 * material renders black. Each file is opened once and shared by every
 * material that names it (reference counted), as pbrt-v3's own loader
 * shares its tables. A textured file's parameters are material parameters
 * of the same names ("float coat.alpha" 0.1 or "texture coat.alpha"
 * "roughmap"), evaluated at each shading point and turned into the basis
 * weights of the BSDF there.
 */
#ifndef PBRT_MATERIALS_LAYERLABFOURIER_H
#define PBRT_MATERIALS_LAYERLABFOURIER_H

#include "pbrt.h"
#include "material.h"
#include "reflection.h"
#include "materials/layerlab_pbrt_adapter.h"

#include <vector>

namespace pbrt {

// The FourierBSDF of pbrt-v3 (Jakob et al. 2014), evaluated by liblayerlab.
class LayerlabFourierBSDF : public BxDF {
  public:
    // Glossy reflection and transmission, as pbrt-v3's FourierBSDF: a .bsdf
    // file may hold both, and BSDF::f picks by the sides of wo and wi.
    // coeffs: the basis weights of a textured file (in the arena of the
    // intersection), nullptr for an untextured one.
    LayerlabFourierBSDF(const ll_bsdf *table, TransportMode mode,
                        const float *coeffs = nullptr)
        : BxDF(BxDFType(BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY)),
          lobe(table,
               mode == TransportMode::Radiance ? ll_pbrt::Transport::Radiance
                                               : ll_pbrt::Transport::Importance,
               coeffs) {}
    Spectrum f(const Vector3f &wo, const Vector3f &wi) const;
    Spectrum Sample_f(const Vector3f &wo, Vector3f *wi, const Point2f &u,
                      Float *pdf, BxDFType *sampledType) const;
    Float Pdf(const Vector3f &wo, const Vector3f &wi) const;
    std::string ToString() const;

  private:
    ll_pbrt::Lobe lobe;
};

class LayerlabFourierMaterial : public Material {
  public:
    LayerlabFourierMaterial(const std::string &filename,
                            const std::shared_ptr<Texture<Float>> &bumpMap);
    // table: the file (possibly empty: black); parameters: one float
    // texture per textured parameter of the file, in its order.
    LayerlabFourierMaterial(
        const ll_pbrt::Table &table,
        const std::vector<std::shared_ptr<Texture<Float>>> &parameters,
        const std::shared_ptr<Texture<Float>> &bumpMap);
    void ComputeScatteringFunctions(SurfaceInteraction *si, MemoryArena &arena,
                                    TransportMode mode,
                                    bool allowMultipleLobes) const;

  private:
    ll_pbrt::Table table;  // empty when the file could not be used: black
    std::vector<std::shared_ptr<Texture<Float>>> parameters;  // textured files
    std::size_t nBases = 1;
    std::shared_ptr<Texture<Float>> bumpMap;
};

// Takes the parameters of pbrt-v3's "fourier" material: "string bsdffile"
// and the optional "float bumpmap" texture; for a textured file also one
// float parameter or float texture per textured parameter, named as the
// file names it (ll_bsdf_get_parameter_name). A parameter the material does
// not set is reported with Warning() and takes the middle of its range.
LayerlabFourierMaterial *CreateLayerlabFourierMaterial(const TextureParams &mp);

}  // namespace pbrt

#endif  // PBRT_MATERIALS_LAYERLABFOURIER_H
