// `aov`: arbitrary output variables at the first intersection (Mitsuba 3's `aov`).
//
// | parameter | type       | default | meaning                                                              |
// |-----------|------------|---------|----------------------------------------------------------------------|
// | aovs      | string     | —       | comma-separated `name:type` list; types: depth, position, uv,          |
// |           |            |         | geo_normal, sh_normal, albedo, prim_index, shape_index                 |
// | (nested)  | integrator | none    | optional integrator whose image becomes the first layer               |
#include "render/aov.h"

#include <sstream>

namespace penumbra {

namespace {
AOVIntegrator::Type parse_type(const Properties& props, const std::string& type) {
    using T = AOVIntegrator::Type;
    static const std::pair<const char*, T> table[] = {
        {"depth", T::Depth},         {"position", T::Position},       {"uv", T::UV},
        {"geo_normal", T::GeoNormal}, {"sh_normal", T::ShNormal},     {"albedo", T::Albedo},
        {"prim_index", T::PrimIndex}, {"shape_index", T::ShapeIndex}};
    for (const auto& [name, t] : table)
        if (type == name) return t;
    props.raise("aovs", "unknown AOV type '" + type +
                            "' (expected depth, position, uv, geo_normal, sh_normal, albedo, prim_index or shape_index)");
}

std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t\n"), b = s.find_last_not_of(" \t\n");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}
} // namespace

AOVIntegrator::AOVIntegrator(const Properties& props) {
    std::stringstream list(props.get_string("aovs"));
    std::string item;
    while (std::getline(list, item, ',')) {
        item = trim(item);
        const size_t colon = item.find(':');
        if (colon == std::string::npos || colon == 0)
            props.raise("aovs", "entry '" + item + "' is not of the form name:type");
        aovs_.push_back({trim(item.substr(0, colon)), parse_type(props, trim(item.substr(colon + 1)))});
    }
    if (aovs_.empty()) props.raise("aovs", "no AOV given");
    const auto nested = props.objects(ObjectKind::Integrator);
    if (nested.size() > 1) props.raise("aovs", "at most one nested integrator is supported");
    if (!nested.empty()) {
        inner_ = std::dynamic_pointer_cast<SamplingIntegrator>(nested[0]);
        if (!inner_) throw LoadError(nested[0]->location, "aov: the nested integrator must be camera-driven (path, direct)");
    }
}

std::vector<std::string> AOVIntegrator::layer_names() const {
    std::vector<std::string> names;
    if (inner_) names.push_back("");
    for (const auto& a : aovs_) names.push_back(a.name);
    return names;
}

namespace {
// Mitsuba's channel letters per AOV type (the values are the first components of each layer's colors).
const char* channel_letters(AOVIntegrator::Type type) {
    using T = AOVIntegrator::Type;
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
    for (const auto& a : aovs_) {
        Color3f v(0.f);
        if (si.is_valid()) switch (a.type) {
            case Type::Depth: v = Color3f(si.t); break;
            case Type::Position: v = si.p; break;
            case Type::UV: v = Color3f(si.uv.x, si.uv.y, 0.f); break;
            case Type::GeoNormal: v = si.n; break;
            case Type::ShNormal: v = si.sh_frame.n; break;
            case Type::Albedo: v = si.bsdf() ? si.bsdf()->eval_diffuse_reflectance(si) : Color3f(0.f); break;
            case Type::PrimIndex: v = Color3f(float(si.prim_index)); break;
            case Type::ShapeIndex: {
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
