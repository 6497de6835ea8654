// The eye pass of (stochastic progressive) photon mapping: an eye subpath from the camera through delta
// (specular, null) scattering, ending at its first surface with a non-delta BSDF, the visible point where
// photons are merged (Hachisuka & Jensen 2009). Emission the subpath reaches on the way (emitters and
// the environment seen directly or through specular chains) is returned apart.
#pragma once
#include "render/integrator.h"

namespace penumbra {

struct VisiblePoint {
    SurfaceInteraction3f si; // si.wi: toward the camera side (local); invalid: the subpath found no point
    Color3f beta;            // eye-subpath throughput up to si (the sensor's weight included)
    int depth = 0;           // segments from the camera to si
    bool valid() const { return si.is_valid(); }
};

struct EyeSubpathSettings {
    int max_depth = -1; // longest full path in segments (-1: unlimited)
    int rr_depth = 5;   // eye depth at which Russian roulette starts along specular chains
};

// Traces `ray` (whose sample weight is `beta`); adds the emission it reaches to `emission`. A BSDF with
// both delta and non-delta lobes (plastic, masks) is a visible point with probability 1/2 (weight 2, its
// non-delta lobes only), else continues along a sampled delta lobe (weight 2; a sampled non-delta lobe
// ends the subpath): an unbiased split of the two parts.
VisiblePoint trace_visible_point(const Scene& scene, Sampler& sampler, Ray ray, Color3f beta,
                                 const EyeSubpathSettings& settings, Color3f& emission, RayCounter& rays);

} // namespace penumbra
