// Normal map: the nested BSDF sees the shading normal n = normalize(2 c - 1), c the texture's RGB value,
// given in the local shading frame ((0.5, 0.5, 1) leaves the surface unchanged); its tangent is the original
// tangent made orthogonal to n. Mitsuba orthogonalizes its world-space dp/du against this local n instead,
// which rotates the tangent about n by a different angle: the two agree for isotropic nested BSDFs.
//
// Mitsuba 3 parameters (src/bsdfs/normalmap.cpp):
//   normalmap       texture   (required)   RGB-encoded tangent-space normals (use a `raw` bitmap)
//   (nested bsdf)   bsdf      (one)        the BSDF whose shading frame is perturbed
// Differentiable (traverse): `normalmap` (e.g. `normalmap.data` of a bitmap), `nested_bsdf`.
#include "scene/bsdfs/perturbed_frame.h"

namespace penumbra {

class NormalMapBSDF final : public PerturbedFrameBSDF<NormalMapBSDF> {
  public:
    NormalMapBSDF(TexturePtr normalmap, BSDFPtr nested)
        : PerturbedFrameBSDF(std::move(nested)), normalmap_(std::move(normalmap)) {}

    // n = normalize(2 c - 1) in the local shading frame.
    template <typename T> Frame<T> frame(const SurfaceInteraction<T>& si) const {
        const Color3<T> c = normalmap_->eval(si);
        const Vec3<T> n(T(2) * c.x - T(1), T(2) * c.y - T(1), T(2) * c.z - T(1));
        const T length = norm(n);
        if (!(length > T(0))) return Frame<T>();
        return frame_about_normal(n / length);
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("nested_bsdf", nested().get());
        v.put_object("normalmap", normalmap_.get());
    }

  private:
    TexturePtr normalmap_;
};

BSDFPtr make_normalmap(TexturePtr normalmap, BSDFPtr nested) {
    return std::make_shared<NormalMapBSDF>(std::move(normalmap), std::move(nested));
}

BSDFPtr load_normalmap(const Properties& props) {
    TexturePtr normalmap = props.get_texture("normalmap");
    const auto children = nested_bsdfs(props);
    if (children.size() != 1)
        throw LoadError(props.location(), "normalmap: expected exactly one nested BSDF, got " +
                                              std::to_string(children.size()));
    return make_normalmap(std::move(normalmap), children[0]);
}

} // namespace penumbra
