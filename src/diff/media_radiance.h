// Radiance leaving a vertex of a boundary path through participating media: the source subpath of Algorithm 1
// (paper 001 §5.2, line 16) from a surface or medium vertex x_S0, the radiance seen beyond a silhouette's edge
// (the primary term) and through a pixel's edge (the pixel-boundary term): the volumetric path tracer of
// render/volpath_tracer.h on the reference geometry, started at the vertex.
#pragma once
#include "diff/media_walk.h"
#include "render/path_tracer.h"

namespace penumbra {

// A vertex: on a surface (si valid, si.wi toward the direction the radiance leaves in) or in `medium` at
// si.p.
struct RadianceVertex {
    SurfaceInteraction3f si;
    Vec3f to_viewer;                // world direction the radiance leaves in
    const Medium* medium = nullptr; // a surface vertex: the medium on the viewer's side
};

// The radiance leaving `v` toward v.to_viewer; at a medium vertex the in-scattered radiance ∫ f_p L_i dω (σ_s
// is the caller's, in the free flight's weight). `max_depth` counts scattering vertices as volpath does (a
// path with k of them, v included, is counted if k < max_depth; -1: unbounded); `emission`: include a surface
// vertex's own emission.
Color3f vertex_radiance(const Scene& scene, const RadianceVertex& v, int max_depth, bool emission,
                        const PathSettings& settings, Sampler& sampler, RayCounter& rays);

// The radiance arriving at ray.o along −ray.d from where a free flight along `ray` (starting in `medium`) ends: a
// medium vertex (its in-scattering), a surface (its emission unless settings hide it at the first vertex, and
// its reflection) or the environment, times the flight's weight; with that end, whose material point the
// boundary terms move.
struct ArrivingRadiance {
    Color3f radiance{0.f};
    FlightEnd end;
};
ArrivingRadiance arriving_radiance(const Scene& scene, const Ray& ray, const Medium* medium,
                                   const PathSettings& settings, Sampler& sampler, RayCounter& rays);

} // namespace penumbra
