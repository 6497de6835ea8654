// Texture factory: dispatches on the plugin name; uv_affine, shared by the uv-mapped plugins.
#include "scene/textures/textures.h"

namespace penumbra {

std::array<float, 6> uv_affine(const Transform& to_uv) {
    const auto& m = to_uv.matrix.m;
    return {m[0][0], m[0][1], m[0][3], m[1][0], m[1][1], m[1][3]};
}

std::shared_ptr<Object> make_texture(const Properties& props, const LoadContext& ctx) {
    const std::string& type = props.plugin();
    if (type == "bitmap") return make_bitmap_texture(props, ctx);
    if (type == "checkerboard") return make_checkerboard_texture(props);
    if (type == "mesh_attribute") return make_mesh_attribute_texture(props);
    if (type == "rawconstant") return make_rawconstant_texture(props);
    if (type == "srgb") return make_srgb_texture(props);
    if (type == "uniform") return make_uniform_texture(props);
    throw_unsupported_plugin(props, ObjectKind::Texture);
}

} // namespace penumbra
