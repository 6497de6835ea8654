#include "scene/factory.h"

#include <filesystem>

namespace penumbra {

const char* kind_name(ObjectKind kind) {
    switch (kind) {
    case ObjectKind::Shape: return "shape";
    case ObjectKind::BSDF: return "bsdf";
    case ObjectKind::Texture: return "texture";
    case ObjectKind::Emitter: return "emitter";
    case ObjectKind::Sensor: return "sensor";
    case ObjectKind::Film: return "film";
    case ObjectKind::RFilter: return "rfilter";
    case ObjectKind::Sampler: return "sampler";
    case ObjectKind::Integrator: return "integrator";
    case ObjectKind::Medium: return "medium";
    case ObjectKind::Phase: return "phase";
    case ObjectKind::Volume: return "volume";
    }
    return "object";
}

void throw_unsupported_plugin(const Properties& props, ObjectKind kind) {
    throw LoadError(props.location(), std::string("unsupported ") + kind_name(kind) + " plugin '" + props.plugin() + "'");
}

std::string LoadContext::resolve(const std::string& filename, const SourceLocation& loc) const {
    namespace fs = std::filesystem;
    const fs::path p(filename);
    if (p.is_absolute()) {
        if (fs::exists(p)) return p.string();
    } else {
        for (const std::string& dir : search_paths) {
            const fs::path candidate = fs::path(dir) / p;
            if (fs::exists(candidate)) return candidate.lexically_normal().string();
        }
    }
    std::string where;
    for (const std::string& dir : search_paths) where += (where.empty() ? "" : ", ") + dir;
    throw LoadError(loc, "file '" + filename + "' not found" + (where.empty() ? "" : " (searched: " + where + ")"));
}

} // namespace penumbra
