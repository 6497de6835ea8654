// The Mitsuba 3 texture plugins, one per file of this directory; make_texture (factory.cpp) dispatches on
// `type`.
#pragma once
#include "scene/factory.h"
#include "scene/texture.h"

#include <array>
#include <memory>

namespace penumbra {

std::shared_ptr<Texture> make_bitmap_texture(const Properties& props, const LoadContext& ctx);
std::shared_ptr<Texture> make_checkerboard_texture(const Properties& props);
std::shared_ptr<Texture> make_mesh_attribute_texture(const Properties& props);
std::shared_ptr<Texture> make_rawconstant_texture(const Properties& props);
std::shared_ptr<Texture> make_srgb_texture(const Properties& props);
std::shared_ptr<Texture> make_uniform_texture(const Properties& props);

// Mitsuba's `to_uv`: a 4x4 transform reduced to a 2D affine map (upper-left 2x2 block and the translation
// column), as Transform4f::extract() does. Row-major [a00 a01 t0 a10 a11 t1]: uv' = A uv + t.
std::array<float, 6> uv_affine(const Transform& to_uv);

} // namespace penumbra
