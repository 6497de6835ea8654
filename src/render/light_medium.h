// The medium a light path starts in: one rule for light tracing (ptracer) and bidirectional estimators
// (bdpt).
//
// Rule: an emitter that nests a medium (Mitsuba's `medium` child of emitters) sits in it. Otherwise an area
// emitter on a shape that declares media emits into the medium on its emitting side, the side its normal
// points to: the shape's exterior (target_medium, Mitsuba's rule). Any other emitter (point, spot, projector,
// an area light on a shape without media, the rays of infinite emitters, which start outside the scene) sits
// in the medium found by walking the straight segment from the sensor's position to the ray origin, starting
// in the sensor's medium and applying target_medium at every surface crossed whatever its BSDF. The walk
// agrees with the media the camera sees as long as the shapes' interior/exterior declarations are consistent.
#pragma once
#include "render/integrator.h"
#include "scene/scene.h"

namespace penumbra {

// Whether the sensor, a shape or an emitter declares a medium (otherwise every path travels in vacuum).
bool scene_has_media(const Scene& scene);

// The medium at world point x by the walk from the sensor described above. Counts its rays.
const Medium* medium_at(const Scene& scene, const Vec3f& x, RayCounter& rays);

// The medium a ray emitted by `emitter` from `origin` (Emitter::sample_ray's ray origin) starts in.
const Medium* emitter_medium(const Scene& scene, const Emitter& emitter, const Vec3f& origin,
                             RayCounter& rays);

} // namespace penumbra
