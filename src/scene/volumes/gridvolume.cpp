#include "scene/media_loading.h"

namespace penumbra {

std::shared_ptr<Object> make_gridvolume(const Properties& props, const LoadContext&) {
    throw_unsupported_plugin(props, ObjectKind::Volume);
}

} // namespace penumbra
