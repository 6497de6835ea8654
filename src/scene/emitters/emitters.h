// The Mitsuba 3 emitter plugins, one per file of this directory; make_emitter (factory.cpp) dispatches on
// `type`.
#pragma once
#include "core/image.h"
#include "scene/emitter.h"
#include "scene/factory.h"

#include <memory>

namespace penumbra {

std::shared_ptr<Emitter> make_area_emitter(const Properties& props);
std::shared_ptr<Emitter> make_point_emitter(const Properties& props);
std::shared_ptr<Emitter> make_spot_emitter(const Properties& props);
std::shared_ptr<Emitter> make_projector_emitter(const Properties& props);
std::shared_ptr<Emitter> make_directional_emitter(const Properties& props);
std::shared_ptr<Emitter> make_constant_emitter(const Properties& props);
std::shared_ptr<Emitter> make_envmap_emitter(const Properties& props, const LoadContext& ctx);
// In-memory construction of an envmap (also used by tests). Throws Error for an image smaller than 2x3 pixels
// or with a negative or non-finite pixel.
std::shared_ptr<Emitter> make_envmap_emitter(Image image, float scale, const Transform& to_world,
                                             bool mis_compensation);

// Helpers shared by the plugins (defined in factory.cpp).
// LoadError at parameter `name` unless the emitted spectrum `value` is finite and non-negative.
void check_emission(const Properties& props, const std::string& name, const Color3f& value);
// The spectrum parameter `name` (default 1), checked by check_emission.
Color3f get_emission(const Properties& props, const std::string& name);
// The connection of `ref` to a light at `position` (point, spot): a delta position, so pdf is the discrete
// probability 1 and the caller's weight is I(-ds.d) / ds.dist^2.
DirectionSample3f delta_position_sample(const Emitter* emitter, const Vec3f& position,
                                        const Interaction3f& ref);

} // namespace penumbra
