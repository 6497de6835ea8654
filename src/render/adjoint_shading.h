// Shading-normal correction of the adjoint BSDF (Veach 1997, Eq. 5.17) for importance transport.
#pragma once
#include "scene/interaction.h"

#include <cmath>

namespace penumbra {

// |w_prev·n_s||w_next·n_g| / (|w_prev·n_g||w_next·n_s|), applied on top of eval()'s |w_next·n_s| factor;
// w_prev (si.wi) points toward the light, w_next toward the camera side.
inline float adjoint_shading_correction(const SurfaceInteraction3f& si, const Vec3f& w_next_world) {
    const Vec3f w_prev = si.to_world(si.wi);
    const float denom = std::abs(dot(w_prev, si.n)) * std::abs(dot(w_next_world, si.sh_frame.n));
    if (denom == 0.f) return 0.f;
    return std::abs(dot(w_prev, si.sh_frame.n)) * std::abs(dot(w_next_world, si.n)) / denom;
}

} // namespace penumbra
