// Bump map: the height field h(u, v) (the texture's eval_1) displaces the surface along the shading normal
// n_s; the nested BSDF sees the normal of the displaced surface, ignoring the variation of n_s itself:
//   dp/du' = dp/du + n_s (scale dh/du - n_s . dp/du),  dp/dv' = dp/dv + n_s (scale dh/dv - n_s . dp/dv),
//   n' = normalize(dp/du' x dp/dv'), flipped to the side of the geometric normal.
// Constant offsets of h change nothing. The tangent is the original one made orthogonal to n' (see
// normalmap.cpp for how this differs from Mitsuba for anisotropic nested BSDFs).
//
// Mitsuba 3 parameters (src/bsdfs/bumpmap.cpp):
//   (nested texture)   texture   (one)   the height field, any name (use a `raw` bitmap)
//   scale              float     1.0     multiplier of the height gradient
//   (nested bsdf)      bsdf      (one)   the BSDF whose shading frame is perturbed
// Differentiable (traverse): `nested_texture` (e.g. `nested_texture.data` of a bitmap), `scale`,
// `nested_bsdf`.
#include "core/param.h"
#include "scene/bsdfs/perturbed_frame.h"
#include "scene/shape.h"

namespace penumbra {

namespace {

// Mitsuba's mesh partials: [p1 - p0, p2 - p0] = [dp/du, dp/dv] [uv1 - uv0, uv2 - uv0] (world space); without
// uvs or when that system is singular, coordinate_system(n) of the geometric normal (the uvs are then
// barycentrics).
void position_partials(const SurfaceInteraction3f& si, Vec3f& dp_du, Vec3f& dp_dv) {
    coordinate_system(si.n, dp_du, dp_dv);
    const TriangleMesh& mesh = si.shape->mesh;
    if (mesh.uvs.empty()) return;
    const uint32_t* i = &mesh.indices[3 * size_t(si.prim_index)];
    const Vec3f dp0 = mesh.positions[i[1]] - mesh.positions[i[0]],
                dp1 = mesh.positions[i[2]] - mesh.positions[i[0]];
    const Vec2f duv0 = mesh.uvs[i[1]] - mesh.uvs[i[0]], duv1 = mesh.uvs[i[2]] - mesh.uvs[i[0]];
    const float det = duv0.x * duv1.y - duv0.y * duv1.x;
    if (det == 0.f) return;
    dp_du = (dp0 * duv1.y - dp1 * duv0.y) / det;
    dp_dv = (dp1 * duv0.x - dp0 * duv1.x) / det;
}

} // namespace

class BumpMapBSDF final : public PerturbedFrameBSDF<BumpMapBSDF> {
  public:
    BumpMapBSDF(TexturePtr height, float scale, BSDFPtr nested)
        : PerturbedFrameBSDF(std::move(nested)), height_(std::move(height)), scale_(scale) {}

    template <typename T> Frame<T> frame(const SurfaceInteraction<T>& si) const {
        if (!si.shape) return Frame<T>();
        const Vec2<T> grad = height_->eval_1_grad(si) * param_value<T>(scale_, scale_index_);
        SurfaceInteraction3f sf;
        sf.n = Vec3f(detach(si.n.x), detach(si.n.y), detach(si.n.z));
        sf.shape = si.shape;
        sf.prim_index = si.prim_index;
        Vec3f dp_du_f, dp_dv_f;
        position_partials(sf, dp_du_f, dp_dv_f);
        const Vec3<T> ns = si.sh_frame.n, dp_du(dp_du_f), dp_dv(dp_dv_f);
        const Vec3<T> du = dp_du + ns * (grad.x - dot(ns, dp_du));
        const Vec3<T> dv = dp_dv + ns * (grad.y - dot(ns, dp_dv));
        Vec3<T> n = cross(du, dv);
        const T length = norm(n);
        if (!(length > T(0))) return Frame<T>();
        n = n / length;
        if (dot(si.n, n) < T(0)) n = -n;
        return frame_about_normal(si.to_local(n));
    }

    void traverse(ParamVisitor& v) override {
        v.put_object("nested_bsdf", nested().get());
        v.put_object("nested_texture", height_.get());
        v.put("scale", &scale_, 1, &scale_index_);
    }

  private:
    TexturePtr height_;
    float scale_;
    int scale_index_ = -1;
};

BSDFPtr make_bumpmap(TexturePtr height, float scale, BSDFPtr nested) {
    return std::make_shared<BumpMapBSDF>(std::move(height), scale, std::move(nested));
}

BSDFPtr load_bumpmap(const Properties& props) {
    const float scale = props.get_float("scale", 1.f);
    const auto textures = props.objects(ObjectKind::Texture);
    if (textures.size() != 1)
        throw LoadError(props.location(), "bumpmap: expected exactly one nested height-map texture, got " +
                                              std::to_string(textures.size()));
    const auto children = nested_bsdfs(props);
    if (children.size() != 1)
        throw LoadError(props.location(),
                        "bumpmap: expected exactly one nested BSDF, got " + std::to_string(children.size()));
    return make_bumpmap(std::static_pointer_cast<Texture>(textures[0]), scale, children[0]);
}

} // namespace penumbra
