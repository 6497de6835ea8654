// Visibility through participating media and index-matched boundaries: the transmittance of a straight
// segment, shared by every estimator that connects two path vertices (next-event estimation in volpath,
// camera connections in ptracer, connections in bdpt). Surfaces with a pure `null` BSDF are crossed (the
// medium changes by target_medium); any other surface blocks the segment.
#pragma once
#include "render/integrator.h"
#include "scene/scene.h"

namespace penumbra {

// Transmittance along `ray` (unit direction) over [0, ray.tmax) for a ray starting in `medium` (null:
// vacuum). Zero if an opaque surface lies on the segment. Transmittance inside heterogeneous media is an
// unbiased estimate (ratio tracking). Counts the rays it traces.
Color3f segment_transmittance(const Scene& scene, Ray ray, const Medium* medium, Sampler& sampler,
                              RayCounter& rays);

// The rest of `ray` beyond its surface hit `si`: offset off the surface, tmax shortened by the distance
// covered (not positive when nothing is left).
Ray ray_beyond(const Ray& ray, const SurfaceInteraction3f& si);

// The medium a sensor's rays start in.
inline const Medium* sensor_medium(const Scene& scene) { return scene.sensor->medium.get(); }

} // namespace penumbra
