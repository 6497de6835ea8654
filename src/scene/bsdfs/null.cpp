// Index-matched boundary: light passes straight through (a pure Null lobe, wo = -wi, weight 1).
//
// Mitsuba 3 parameters (src/bsdfs/null.cpp): none.
#include "scene/bsdfs/bsdfs.h"

namespace penumbra {

class NullBSDF final : public BSDFBase<NullBSDF> {
public:
    NullBSDF() { flags_ = BSDFNull; }
    template <typename T> Color3<T> eval_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const {
        return Color3<T>(T(0));
    }
    template <typename T> T pdf_t(const BSDFContext&, const SurfaceInteraction<T>&, const Vec3<T>&) const { return T(0); }
    template <typename T>
    Color3<T> delta_weight_t(const BSDFContext&, const SurfaceInteraction<T>& si, const Vec3<T>& wo) const {
        return Color3<T>(si.wi.z * wo.z < T(0) ? T(1) : T(0));
    }
    std::pair<BSDFSample, Color3f> sample(const BSDFContext&, const SurfaceInteraction3f& si, float,
                                          const Vec2f&) const override {
        BSDFSample bs;
        bs.wo = -si.wi;
        bs.pdf = 1.f;
        bs.sampled_type = BSDFNull;
        return {bs, Color3f(1.f)};
    }
};

BSDFPtr make_null_bsdf() { return std::make_shared<NullBSDF>(); }
BSDFPtr load_null_bsdf(const Properties&) { return make_null_bsdf(); }

} // namespace penumbra
