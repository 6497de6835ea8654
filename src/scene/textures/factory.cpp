// Texture factory: dispatches on the plugin name.
#include "scene/factory.h"
#include "scene/texture.h"

#include <array>

namespace penumbra {

// Defined in the plugin files of this directory.
std::shared_ptr<Texture> make_bitmap_texture(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Texture> make_checkerboard_texture(const Properties& props);
std::shared_ptr<Texture> make_srgb_texture(const Properties& props);
std::shared_ptr<Texture> make_uniform_texture(const Properties& props);

// Mitsuba's `to_uv`: a 4x4 transform reduced to a 2D affine map (upper-left 2x2 block and the translation
// column), as Transform4f::extract() does. Row-major [a00 a01 t0 a10 a11 t1]: uv' = A uv + t.
std::array<float, 6> uv_affine(const Transform& to_uv) {
    const auto& m = to_uv.matrix.m;
    return {m[0][0], m[0][1], m[0][3], m[1][0], m[1][1], m[1][3]};
}

std::shared_ptr<Object> make_texture(const Properties& props, const LoadContext& ctx) {
    const std::string& type = props.plugin();
    if (type == "bitmap") return make_bitmap_texture(props, ctx);
    if (type == "checkerboard") return make_checkerboard_texture(props);
    if (type == "srgb") return make_srgb_texture(props);
    if (type == "uniform") return make_uniform_texture(props);
    throw_unsupported_plugin(props, ObjectKind::Texture);
}

} // namespace penumbra
