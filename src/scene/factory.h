// Factories from parsed properties to scene objects, one per object kind. Each factory queries the
// parameters it understands (with Mitsuba 3 defaults) and throws a LoadError naming the plugin and the
// location for an unsupported `type`. The loader then rejects any parameter left unqueried.
#pragma once
#include "scene/properties.h"

#include <memory>
#include <string>

namespace penumbra {

// Context a factory may need: the directory list used to resolve relative file names.
struct LoadContext {
    std::vector<std::string> search_paths; // the scene file's directory first, then <path> entries
    // Resolves a file name against the search paths; throws LoadError at `loc` if not found.
    std::string resolve(const std::string& filename, const SourceLocation& loc) const;
};

std::shared_ptr<Object> make_bsdf(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_texture(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_emitter(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_shape(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_sensor(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_film(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_rfilter(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_sampler(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_medium(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_phase(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Object> make_volume(const Properties& props, const LoadContext& ctx);
// The <integrator>'s settings record (scene/integrator_settings.h).
std::shared_ptr<Object> make_integrator_settings(const Properties& props, const LoadContext& ctx);

// "file:line: unsupported <kind> plugin '<type>'" (one clear line).
[[noreturn]] void throw_unsupported_plugin(const Properties& props, ObjectKind kind);

} // namespace penumbra
