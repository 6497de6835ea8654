// Straight walks of the boundary terms through participating media and index-matched (`null`) boundaries
// (paper 001 §5.2, Algorithm 1): sampleInteraction — the free flight that ends a boundary segment at a medium
// vertex or at the first surface that scatters (segments' transmittance: render/volume_visibility.h).
// Surfaces whose BSDF is a pure `null` are crossed (the medium changes by target_medium); any other surface
// blocks a transmittance walk and ends a free flight. Weights are detached floats.
#pragma once
#include "render/integrator.h"
#include "scene/scene.h"

namespace penumbra {

// The end of a free flight along `ray` (unbounded) starting in `medium`: a medium vertex (scattered), a
// surface (passed), the ray escaping the scene (passed), or nothing (absorbed). With `volume_vertices` false,
// flights always pass, with the transmittance as weight (the surface-only boundary segments).
struct FlightEnd {
    enum class Kind { None, Medium, Surface, Escaped };
    Kind kind = Kind::None;
    Vec3f p;                        // the medium vertex or surface point
    SurfaceInteraction3f si;        // the surface (Surface)
    const Medium* medium = nullptr; // the medium the flight ends in (Medium) or arrives through (Surface)
    Color3f weight{0.f}; // Medium: Tr σ_s / p(t); Surface, Escaped: Tr / P(pass) (with volume_vertices)
};
FlightEnd sample_interaction(const Scene& scene, Ray ray, const Medium* medium, bool volume_vertices,
                             Sampler& sampler, RayCounter& rays);

// The first surface along `ray` that is not a pure null one, with its distance from ray.o in .t (invalid if
// none).
SurfaceInteraction3f first_opaque_hit(const Scene& scene, Ray ray, RayCounter& rays);

} // namespace penumbra
