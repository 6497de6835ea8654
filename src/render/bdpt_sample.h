// The set-up of bidirectional path tracing's samples (Veach 1997, §10.2), written once for the `bdpt`
// integrator (render/bdpt.cpp) and the differentiable bidirectional estimators (diff/psdr/bdpt_interior.h,
// diff/war/war_bdpt.h): what a pass shares, and per camera sample the camera and light subpaths and every
// (s, t) strategy connecting them with its MIS-weighted contribution C_{s,t}. The renderer sums the
// strategies and splats light tracing; a differentiable estimator asks for the record and re-evaluates each
// recorded strategy's path on the geometry.
#pragma once
#include "render/bdpt_record.h"
#include "render/bdpt_subpaths.h"

#include <vector>

namespace penumbra {

// What every camera sample of a pass shares.
struct BDPTPass {
    const Scene& scene;
    BDPTSettings settings;
    bool has_media;               // scene_has_media (render/light_medium.h)
    bool sensor_connects;         // light tracing (t = 1) is sampled and counted in the MIS weights
    BoundingSphere bounds;        // infinite lights emit from a disk of this radius
    size_t max_camera, max_light; // subpath vertices of max_depth's longest path (unbounded for -1)

    // `light_tracing`: connect scene points to the sensor, unless it is a radiance or irradiance meter.
    BDPTPass(const Scene& scene, const BDPTSettings& settings, bool light_tracing);
};

// One camera sample's subpaths z_0 z_1 ... and y_0 y_1 ..., and what a recorded sample drew; kept across
// samples for their storage.
struct BDPTSample {
    std::vector<PathVertex> camera, light;
    BDPTRecord record;

    // Traces the camera subpath along `ray` (lens sample u_aperture) and a light subpath and connects them:
    // returns Σ_{t>=2} C_{s,t} for the ray's pixel and adds light tracing's C_{s,1} to `splats`
    // (unnormalized).
    Color3f render(const BDPTPass& pass, Sampler& sampler, RayCounter& rays, const Ray& ray,
                   const Vec2f& u_aperture, Image& splats);
    // The same sample recorded for a differentiable estimator (the pass without light tracing, the lens
    // sample at the aperture's center): every strategy's C_{s,t} and the chains of every segment in `record`.
    void trace_recorded(const BDPTPass& pass, Sampler& sampler, RayCounter& rays, const Ray& ray);

  private:
    Color3f trace(const BDPTPass& pass, Sampler& sampler, RayCounter& rays, const Ray& ray,
                  const Vec2f& u_aperture, Image* splats, BDPTRecord* recorded);
};

} // namespace penumbra
