// The eye pass of (stochastic progressive) photon mapping: an eye subpath from the camera through delta
// (specular, null) scattering, ending at its first surface with a non-delta BSDF, the visible point where
// photons are merged (Hachisuka & Jensen 2009). Emission the subpath reaches on the way (emitters and
// the environment seen directly or through specular chains) is returned apart.
#pragma once
#include "render/integrator.h"
#include "scene/medium.h"

namespace penumbra {

struct VisiblePoint {
    SurfaceInteraction3f si; // si.wi: toward the camera side (local); invalid: none on a surface
    Color3f beta;            // eye-subpath throughput up to the point (the sensor's weight included)
    int depth = 0;           // segments from the camera to the point
    // A point in a participating medium (si invalid): where the eye subpath scattered, the world direction
    // toward the camera side, and the medium; beta excludes σ_s there (the volume photons' flux carries it).
    const Medium* medium = nullptr;
    Vec3f p, wi;
    bool valid() const { return si.is_valid() || medium != nullptr; }
    bool in_medium() const { return medium != nullptr; }
};

// A specular vertex of the eye subpath: where it was scattered, and the relative index η_out / η_in of the
// sampled delta lobe (1: reflection), for the half-vector constraints of differentiable photon mapping.
struct SpecularVertex {
    SurfaceInteraction3f si;
    float eta = 1.f;
};

struct EyeSubpathSettings {
    int max_depth = -1; // longest full path in segments (-1: unlimited)
    int rr_depth = 5;   // eye depth at which Russian roulette starts along specular chains
};

// Traces `ray` (whose sample weight is `beta`); adds the emission it reaches to `emission`. A BSDF with
// both delta and non-delta lobes (plastic, masks) is a visible point with probability 1/2 (weight 2, its
// non-delta lobes only), else continues along a sampled delta lobe (weight 2; a sampled non-delta lobe
// ends the subpath): an unbiased split of the two parts. `chain` (optional) receives the specular vertices
// between the camera and the visible point (null crossings are not vertices).
VisiblePoint trace_visible_point(const Scene& scene, Sampler& sampler, Ray ray, Color3f beta,
                                 const EyeSubpathSettings& settings, Color3f& emission, RayCounter& rays,
                                 std::vector<SpecularVertex>* chain = nullptr);

// The eye subpath of pass `pass` in pixel (x, y): the sampler started at (seed, pixel, pass) gives the film
// position and the lens sample, then trace_visible_point. The one sequence of random numbers sppm traces and
// the differentiable photon-mapping estimators (diff/dpm/dpm.h) re-trace.
struct PixelVisiblePoint {
    VisiblePoint vp;
    Ray ray;          // the primary ray
    Vec2f film;       // its film position (pixels)
    Color3f emission; // the emission the subpath reached
};
PixelVisiblePoint trace_pixel_visible_point(const Scene& scene, Sampler& sampler, int x, int y, uint64_t seed,
                                            uint64_t pass, const EyeSubpathSettings& settings, RayCounter& rays,
                                            std::vector<SpecularVertex>* chain = nullptr);

} // namespace penumbra
