// layerlab system-libs (shims/pbrt-v3/system-libs.sh): this file replaces
// pbrt-v3's src/textures/ptex.cpp when pbrt-v3 is built against a system
// that packages no Ptex library (Debian 12). The declarations in ptex.h stay
// as they are; a "ptex" texture is reported once, when the scene creates it,
// and then evaluates to 0 -- what pbrt-v3 itself does with a Ptex file it
// cannot open -- so a scene that uses one still renders, visibly without it.

#include "textures/ptex.h"

#include "error.h"
#include "paramset.h"

namespace pbrt {

template <typename T>
PtexTexture<T>::PtexTexture(const std::string &filename, Float gamma)
    : valid(false), filename(filename), gamma(gamma) {
    Error("ptex texture \"%s\": this pbrt-v3 was built without Ptex "
          "(layerlab's system-libs.sh); the texture evaluates to 0",
          filename.c_str());
}

template <typename T>
PtexTexture<T>::~PtexTexture() {}

template <typename T>
T PtexTexture<T>::Evaluate(const SurfaceInteraction &) const {
    return T(0.f);
}

PtexTexture<Float> *CreatePtexFloatTexture(const Transform &,
                                           const TextureParams &tp) {
    return new PtexTexture<Float>(tp.FindFilename("filename"),
                                  tp.FindFloat("gamma", 2.2));
}

PtexTexture<Spectrum> *CreatePtexSpectrumTexture(const Transform &,
                                                 const TextureParams &tp) {
    return new PtexTexture<Spectrum>(tp.FindFilename("filename"),
                                     tp.FindFloat("gamma", 2.2));
}

}  // namespace pbrt
