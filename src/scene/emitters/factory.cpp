// make_emitter: Mitsuba 3 emitter plugins by `type`. Each maker lives in the plugin's own file.
#include "scene/emitter.h"
#include "scene/factory.h"

namespace penumbra {

std::shared_ptr<Emitter> make_area_emitter(const Properties& props);
std::shared_ptr<Emitter> make_point_emitter(const Properties& props);
std::shared_ptr<Emitter> make_spot_emitter(const Properties& props);
std::shared_ptr<Emitter> make_directional_emitter(const Properties& props);
std::shared_ptr<Emitter> make_constant_emitter(const Properties& props);
std::shared_ptr<Emitter> make_envmap_emitter(const Properties& props, const LoadContext& ctx);

std::shared_ptr<Object> make_emitter(const Properties& props, const LoadContext& ctx) {
    const std::string& type = props.plugin();
    if (type == "area") return make_area_emitter(props);
    if (type == "point") return make_point_emitter(props);
    if (type == "spot") return make_spot_emitter(props);
    if (type == "directional") return make_directional_emitter(props);
    if (type == "constant") return make_constant_emitter(props);
    if (type == "envmap") return make_envmap_emitter(props, ctx);
    throw_unsupported_plugin(props, ObjectKind::Emitter);
}

} // namespace penumbra
