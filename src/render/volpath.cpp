// `volpath` and `volpathmis`: unidirectional volumetric path tracers (Mitsuba 3's plugins of these names).
// The estimator is render/volpath_tracer.h.
//
// | parameter      | type    | default | meaning                                                    |
// |----------------|---------|---------|------------------------------------------------------------|
// | max_depth      | integer | -1      | longest path depth (-1 = infinite, 1 = visible emitters)    |
// | rr_depth       | integer | 5       | depth at which Russian roulette starts                     |
// | hide_emitters  | boolean | false   | do not show directly visible emitters                      |
//
// Chromatic media (per-channel sigma_t): `volpath` chooses the channel that drives each free-flight distance
// anew for every segment and weights the segment by the channel-averaged density (one-sample balance
// heuristic per segment: unbiased even where a channel has sigma_t = 0, unlike Mitsuba's volpath, which
// divides by the chosen channel's density alone). `volpathmis` chooses one hero channel per path and weights
// the whole path by the channel-averaged path density (pbrt-v4's r_u; Mitsuba's volpathmis does the same):
// lower variance for long paths in strongly chromatic media, where per-segment weights multiply up to 3 per
// segment.
#include "render/volpath.h"

namespace penumbra {

void VolPathIntegrator::sample(const Scene& scene, Sampler& sampler, const Ray& primary, Color3f* out,
                               RayCounter& rays) const {
    out[0] = trace_volpath(scene, sampler, primary, settings_, spectral_, rays);
}

} // namespace penumbra
