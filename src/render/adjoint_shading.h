// Shading-normal correction of the adjoint BSDF (Veach 1997, Eq. 5.17) for importance transport.
#pragma once
#include "scene/interaction.h"

#include <cmath>

namespace penumbra {

// |w_prev·n_s||w_next·n_g| / (|w_prev·n_g||w_next·n_s|), applied on top of eval()'s |w_next·n_s| factor;
// w_prev (si.wi) points toward the light, w_next toward the camera side. Templated on the scalar type (the
// differentiable photon-mapping paths evaluate it on the tape).
template <typename T>
T adjoint_shading_correction(const SurfaceInteraction<T>& si, const Vec3<T>& w_next_world) {
    using std::abs;
    const Vec3<T> w_prev = si.to_world(si.wi);
    const T denom = abs(dot(w_prev, si.n)) * abs(dot(w_next_world, si.sh_frame.n));
    if (denom == T(0)) return T(0);
    return abs(dot(w_prev, si.sh_frame.n)) * abs(dot(w_next_world, si.n)) / denom;
}

} // namespace penumbra
