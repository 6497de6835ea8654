// The <integrator> factory: reads and checks every integrator's parameters at load time, so that a bad
// value is refused with its location before anything renders (the tables are in src/render/<plugin>.cpp).
#include "scene/integrator_settings.h"

#include "scene/factory.h"
#include "scene/scene.h"

#include <cmath>
#include <sstream>

namespace penumbra {

namespace {

PathSettings parse_path(const Properties& props) {
    PathSettings s;
    s.max_depth = int(props.get_int("max_depth", -1));
    s.rr_depth = int(props.get_int("rr_depth", 5));
    s.hide_emitters = props.get_bool("hide_emitters", false);
    if (s.max_depth < -1) props.raise("max_depth", "must be -1 (infinite) or non-negative");
    if (s.rr_depth <= 0) props.raise("rr_depth", "must be positive");
    return s;
}

BDPTSettings parse_bdpt(const Properties& props) {
    BDPTSettings s;
    s.max_depth = int(props.get_int("max_depth", -1));
    s.rr_depth = int(props.get_int("rr_depth", 5));
    s.hide_emitters = props.get_bool("hide_emitters", false);
    const std::string heuristic = props.get_string("heuristic", "power");
    if (heuristic == "power")
        s.heuristic = MISHeuristic::Power;
    else if (heuristic == "balance")
        s.heuristic = MISHeuristic::Balance;
    else
        props.raise("heuristic", "'heuristic' must be 'power' or 'balance', got '" + heuristic + "'");
    s.strategy_s = int(props.get_int("strategy_s", -1));
    s.strategy_t = int(props.get_int("strategy_t", -1));
    if ((s.strategy_s < 0) != (s.strategy_t < 0))
        props.raise(s.strategy_s < 0 ? "strategy_s" : "strategy_t",
                    "'strategy_s' and 'strategy_t' select one strategy together");
    if (s.strategy_t == 0 || (s.strategy_s == 0 && s.strategy_t == 1))
        props.raise("strategy_t", "'strategy_t' must be >= 1 (camera vertices), with s + t >= 2");
    if (s.max_depth < -1) props.raise("max_depth", "'max_depth' must be -1 (infinite) or non-negative");
    if (s.rr_depth <= 0) props.raise("rr_depth", "'rr_depth' must be positive");
    return s;
}

SPPMSettings parse_sppm(const Properties& props) {
    SPPMSettings s;
    s.photon_count = props.get_int("photon_count", 250000);
    s.initial_radius = props.get_float("initial_radius", 0.f);
    s.alpha = props.get_float("alpha", 0.7f);
    s.max_depth = int(props.get_int("max_depth", -1));
    s.rr_depth = int(props.get_int("rr_depth", 5));
    s.granularity = props.get_int("granularity", 0);
    s.max_passes = props.get_int("max_passes", -1);
    const std::string kernel = props.get_string("kernel", "constant");
    if (kernel == "constant")
        s.kernel = PhotonKernel::Constant;
    else if (kernel == "smooth")
        s.kernel = PhotonKernel::Smooth;
    else
        props.raise("kernel", "'kernel' must be 'constant' or 'smooth', got '" + kernel + "'");
    if (s.photon_count <= 0 || s.photon_count > (int64_t(1) << 31))
        props.raise("photon_count",
                    "'photon_count' must be positive (at most 2^31), got " + std::to_string(s.photon_count));
    if (!(s.initial_radius >= 0.f) || !std::isfinite(s.initial_radius))
        props.raise("initial_radius",
                    "'initial_radius' must be >= 0 (0: automatic), got " + std::to_string(s.initial_radius));
    if (!(s.alpha > 0.f && s.alpha <= 1.f))
        props.raise("alpha", "'alpha' must be in (0, 1], got " + std::to_string(s.alpha));
    if (s.max_depth < -1) props.raise("max_depth", "'max_depth' must be -1 (infinite) or non-negative");
    if (s.rr_depth <= 0) props.raise("rr_depth", "'rr_depth' must be positive");
    if (s.granularity < 0) props.raise("granularity", "'granularity' must be >= 0 (0: automatic)");
    if (s.max_passes == 0 || s.max_passes < -1)
        props.raise("max_passes", "'max_passes' must be positive or -1 (the sampler's sample count)");
    return s;
}

DirectSettings parse_direct(const Properties& props) {
    DirectSettings s;
    const int64_t shading = props.get_int("shading_samples", 1);
    s.emitter_samples = int(props.get_int("emitter_samples", shading));
    s.bsdf_samples = int(props.get_int("bsdf_samples", shading));
    s.hide_emitters = props.get_bool("hide_emitters", false);
    if (s.emitter_samples < 0 || s.bsdf_samples < 0 || s.emitter_samples + s.bsdf_samples == 0)
        props.raise("emitter_samples",
                    "emitter_samples and bsdf_samples must be non-negative and not both zero");
    return s;
}

AOVType parse_aov_type(const Properties& props, const std::string& type) {
    using T = AOVType;
    static const std::pair<const char*, T> table[] = {
        {"depth", T::Depth},          {"position", T::Position},     {"uv", T::UV},
        {"geo_normal", T::GeoNormal}, {"sh_normal", T::ShNormal},    {"albedo", T::Albedo},
        {"prim_index", T::PrimIndex}, {"shape_index", T::ShapeIndex}};
    for (const auto& [name, t] : table)
        if (type == name) return t;
    props.raise(
        "aovs",
        "unknown AOV type '" + type +
            "' (expected depth, position, uv, geo_normal, sh_normal, albedo, prim_index or shape_index)");
}

std::string trim(const std::string& s) {
    const size_t a = s.find_first_not_of(" \t\n"), b = s.find_last_not_of(" \t\n");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

// The nested object as a camera-driven integrator's settings, or null.
std::shared_ptr<const IntegratorSettings> camera_driven_settings(const std::shared_ptr<Object>& object) {
    auto settings = std::dynamic_pointer_cast<const IntegratorSettings>(object);
    return settings && camera_driven(settings->plugin) ? settings : nullptr;
}

void parse_aov(const Properties& props, IntegratorSettings& s) {
    std::stringstream list(props.get_string("aovs"));
    std::string item;
    while (std::getline(list, item, ',')) {
        item = trim(item);
        const size_t colon = item.find(':');
        if (colon == std::string::npos || colon == 0)
            props.raise("aovs", "entry '" + item + "' is not of the form name:type");
        s.aovs.push_back({trim(item.substr(0, colon)), parse_aov_type(props, trim(item.substr(colon + 1)))});
    }
    if (s.aovs.empty()) props.raise("aovs", "no AOV given");
    const auto nested = props.objects(ObjectKind::Integrator);
    if (nested.size() > 1) props.raise("aovs", "at most one nested integrator is supported");
    if (!nested.empty()) {
        auto inner = camera_driven_settings(nested[0]);
        if (!inner)
            throw LoadError(nested[0]->location,
                            "aov: the nested integrator must be camera-driven (path, direct)");
        s.nested.push_back({std::string(), std::move(inner)});
    }
}

void parse_moment(const Properties& props, IntegratorSettings& s) {
    props.objects(ObjectKind::Integrator); // marks them queried; names come from all_objects()
    for (const auto& [name, object] : props.all_objects()) {
        auto nested = camera_driven_settings(object);
        if (!nested)
            throw LoadError(object->location, "moment: nested integrator '" + object->plugin +
                                                  "' must be camera-driven (path, direct, aov, moment)");
        s.nested.push_back({name, std::move(nested)});
    }
    if (s.nested.empty())
        throw LoadError(props.location(), "moment: at least one nested integrator is required");
}

} // namespace

bool camera_driven(const std::string& plugin) {
    return plugin == "path" || plugin == "volpath" || plugin == "volpathmis" || plugin == "direct" ||
           plugin == "aov" || plugin == "moment";
}

std::shared_ptr<Object> make_integrator_settings(const Properties& props, const LoadContext&) {
    auto s = std::make_shared<IntegratorSettings>();
    const std::string& type = props.plugin();
    if (type == "path" || type == "volpath" || type == "volpathmis" || type == "ptracer")
        s->path = parse_path(props);
    else if (type == "bdpt")
        s->bdpt = parse_bdpt(props);
    else if (type == "sppm")
        s->sppm = parse_sppm(props);
    else if (type == "direct")
        s->direct = parse_direct(props);
    else if (type == "aov")
        parse_aov(props, *s);
    else if (type == "moment")
        parse_moment(props, *s);
    else
        throw_unsupported_plugin(props, ObjectKind::Integrator);
    return s;
}

namespace {
bool integrator_is(const Scene& scene, const char* plugin) {
    return scene.integrator && scene.integrator->plugin == plugin;
}
} // namespace

PathSettings path_settings(const Scene& scene) {
    if (integrator_is(scene, "path") || integrator_is(scene, "volpath") || integrator_is(scene, "volpathmis"))
        return scene.integrator->path;
    if (scene_integrator_is_bdpt(scene)) {
        const BDPTSettings& b = scene.integrator->bdpt;
        return PathSettings{b.max_depth, b.rr_depth, b.hide_emitters};
    }
    return PathSettings{};
}

BDPTSettings bdpt_settings(const Scene& scene, const PathSettings& path) {
    if (scene_integrator_is_bdpt(scene)) {
        BDPTSettings s = scene.integrator->bdpt;
        s.strategy_s = s.strategy_t = -1;
        return s;
    }
    BDPTSettings s;
    s.max_depth = path.max_depth;
    s.rr_depth = path.rr_depth;
    s.hide_emitters = path.hide_emitters;
    return s;
}

bool scene_integrator_is_bdpt(const Scene& scene) { return integrator_is(scene, "bdpt"); }

const SPPMSettings* sppm_settings(const Scene& scene) {
    return integrator_is(scene, "sppm") ? &scene.integrator->sppm : nullptr;
}

} // namespace penumbra
