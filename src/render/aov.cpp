// `aov`: arbitrary output variables at the first intersection (Mitsuba 3's `aov`).
//
// | parameter | type       | default | meaning                                                              |
// |-----------|------------|---------|----------------------------------------------------------------------|
// | aovs      | string     | —       | comma-separated `name:type` list; types: depth, position, uv,          |
// |           |            |         | geo_normal, sh_normal, albedo, prim_index, shape_index                 |
// | (nested)  | integrator | none    | optional integrator whose image becomes the first layer               |
#include "render/aov.h"

namespace penumbra {

AOVIntegrator::AOVIntegrator(const IntegratorSettings& settings) : aovs_(settings.aovs) {
    if (!settings.nested.empty()) inner_ = make_sampling_integrator(*settings.nested[0].settings);
}

std::vector<std::string> AOVIntegrator::layer_names() const {
    std::vector<std::string> names;
    if (inner_) names.push_back("");
    for (const auto& a : aovs_) names.push_back(a.name);
    return names;
}

namespace {
// Mitsuba's channel letters per AOV type (the values are the first components of each layer's colors).
const char* channel_letters(AOVType type) {
    using T = AOVType;
    switch (type) {
    case T::Depth:
        return "T";
    case T::UV:
        return "UV";
    case T::Albedo:
        return "RGB";
    case T::PrimIndex:
    case T::ShapeIndex:
        return "I";
    default:
        return "XYZ"; // position, geo_normal, sh_normal
    }
}
} // namespace

std::vector<std::string> AOVIntegrator::layer_channels() const {
    std::vector<std::string> channels;
    if (inner_) channels.push_back("RGB");
    for (const auto& a : aovs_)
        channels.push_back(channel_letters(a.type));
    return channels;
}

void AOVIntegrator::sample(const Scene& scene, Sampler& sampler, const Ray& ray, Color3f* out, RayCounter& rays) const {
    if (inner_) inner_->sample(scene, sampler, ray, out++, rays);
    const SurfaceInteraction3f si = scene.intersect(ray);
    using T = AOVType;
    for (const auto& a : aovs_) {
        Color3f v(0.f);
        if (si.is_valid()) switch (a.type) {
            case T::Depth: v = Color3f(si.t); break;
            case T::Position: v = si.p; break;
            case T::UV: v = Color3f(si.uv.x, si.uv.y, 0.f); break;
            case T::GeoNormal: v = si.n; break;
            case T::ShNormal: v = si.sh_frame.n; break;
            case T::Albedo: v = si.bsdf() ? si.bsdf()->eval_diffuse_reflectance(si) : Color3f(0.f); break;
            case T::PrimIndex: v = Color3f(float(si.prim_index)); break;
            case T::ShapeIndex: {
                float index = 0.f;
                for (size_t i = 0; i < scene.shapes.size(); ++i)
                    if (scene.shapes[i].get() == si.shape) index = float(i);
                v = Color3f(index);
                break;
            }
            }
        *out++ = v;
    }
}

} // namespace penumbra
