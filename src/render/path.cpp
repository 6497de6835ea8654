// `path`: unidirectional path tracer with next-event estimation and MIS (Mitsuba 3's `path`). The estimator
// itself is render/path_tracer.h, shared with the differentiable estimators.
//
// | parameter      | type    | default | meaning                                                    |
// |----------------|---------|---------|------------------------------------------------------------|
// | max_depth      | integer | -1      | longest path depth (-1 = infinite, 1 = visible emitters)    |
// | rr_depth       | integer | 5       | depth at which Russian roulette starts                     |
// | hide_emitters  | boolean | false   | do not show directly visible emitters                      |
#include "render/path.h"

#include "render/path_tracer.h"

namespace penumbra {

void PathIntegrator::sample(const Scene& scene, Sampler& sampler, const Ray& primary, Color3f* out,
                            RayCounter& rays) const {
    const SurfaceInteraction3f first = scene.intersect(primary);
    out[0] = trace_path<float>(scene, sampler, primary, first, first, ReferenceGeometry{}, settings_, rays);
}

} // namespace penumbra
