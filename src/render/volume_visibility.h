// Visibility through participating media and index-matched boundaries: the transmittance of a straight
// segment, shared by every estimator that connects two path vertices (next-event estimation in volpath,
// camera connections in ptracer, connections in bdpt). Surfaces with a pure `null` BSDF are crossed (the
// medium changes by target_medium); any other surface blocks the segment.
#pragma once
#include "render/flight_record.h"
#include "render/integrator.h"
#include "scene/scene.h"

namespace penumbra {

// Transmittance along `ray` (unit direction) over [0, ray.tmax) for a ray starting in `medium` (null:
// vacuum). Zero if an opaque surface lies on the segment. Transmittance inside heterogeneous media is an
// unbiased estimate (ratio tracking). Counts the rays it traces. `end_medium` (optional) receives the medium
// at the segment's end; `pieces` (optional) the segment's pieces between crossings with their ratio-tracking
// records, for re-evaluation on a moving segment (render/flight_record.h chain_weight).
Color3f segment_transmittance(const Scene& scene, Ray ray, const Medium* medium, Sampler& sampler,
                              RayCounter& rays, const Medium** end_medium = nullptr,
                              LegChain* pieces = nullptr);

// The medium a sensor's rays start in.
inline const Medium* sensor_medium(const Scene& scene) { return scene.sensor->medium.get(); }

} // namespace penumbra
