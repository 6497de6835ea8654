// The film position of a material-form or warped camera sample: a defensive mixture of the normalized
// reconstruction filter and the uniform density on its support square (diff/psdr/interior.cpp,
// diff/was/warped_area.cpp).
#pragma once
#include "scene/film.h"
#include "scene/sampler.h"

namespace penumbra {

struct FilmSample {
    Vec2f offset; // from the pixel center, in pixels
    float pdf;    // density of `offset`
};

// A defensive mixture of the normalized filter and the uniform density on its support square: the density is
// bounded below, so P(s(θ))/p and its derivative stay bounded for any continuous filter (a tent's derivative
// would have unbounded variance under pure filter sampling). The antithetic partner mirrors the offset about
// the pixel center (paper 001 §5.1); the mixture is point-symmetric, so both have the same density.
inline FilmSample sample_film(const ReconstructionFilter& filter, Sampler& sampler, bool mirror) {
    const float r = filter.radius();
    const float choose = sampler.next_1d();
    const Vec2f u = sampler.next_2d();
    Vec2f offset = choose < 0.5f ? filter.sample(u) : Vec2f((2.f * u.x - 1.f) * r, (2.f * u.y - 1.f) * r);
    if (mirror) offset = offset * -1.f;
    const float pdf = 0.5f * filter.eval_normalized(offset) + 0.5f / (4.f * r * r);
    return {offset, pdf};
}

} // namespace penumbra
