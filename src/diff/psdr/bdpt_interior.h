// The bidirectional estimator of the interior term (paper 001 §5.1, §7): each camera sample traces the float
// bidirectional path tracer's camera and light subpaths (render/bdpt*.cpp: detached sampling, MIS weights and
// Russian roulette) and differentiates every strategy's contribution C_{s,t} = f(x̄) w_{s,t} / p_{s,t} as
//     C_{s,t} · f(x̄; θ) / f(x̄; θ0)
// with f the material-form measurement contribution of the same path (diff/path_measurement.h): sampling
// densities and MIS weights stay detached, so the estimator is the renderer's at θ0 and its derivative is
// unbiased for every strategy.
//
// Strategies: t >= 2 only (a camera subpath vertex z_1 on the camera ray), with MIS weights over those
// strategies (they still sum to 1 per path). Light tracing (t = 1) would parameterize z_1 by its material
// point and splat into other pixels; with the image-space first vertex, mixing it with the camera ray's
// parameterization under detached MIS weights would be biased.
//
// Media: free flights along subpaths (delta tracking in heterogeneous media) and ratio tracking along
// connections are re-evaluated on the moving segments from their records (render/flight_record.h).
//
// Limits: light subpaths of infinite lights are not differentiated (next-event estimation and emission found
// by camera subpaths are). Asked for explicitly, such scenes throw a clear error; `auto` falls back to the
// unidirectional estimator.
#pragma once
#include "diff/psdr/interior_media.h"
#include "diff/psdr/shading_horizon.h"
#include "render/bdpt_sample.h"
#include "render/bdpt_subpaths.h"
#include "scene/integrator_settings.h"

#include <string>

namespace penumbra {

enum class InteriorEstimator {
    Auto,           // bidirectional when the scene's integrator is `bdpt` (and the scene is supported)
    Unidirectional, // path tracing / volumetric path tracing (diff/psdr/interior_media.h)
    Bidirectional,
};

InteriorEstimator parse_interior_estimator(const std::string& name);
bool bidirectional_interior(const Scene& scene, InteriorEstimator estimator);
// Throws when the scene has what the bidirectional estimator does not differentiate (see above).
void require_bidirectional_support(const Scene& scene);

// The pass of the bidirectional estimator: the scene's bdpt settings (or `path`'s), without light tracing
// (t = 1 is neither sampled nor counted in the MIS weights).
BDPTPass bidirectional_pass(const Scene& scene, const PathSettings& path);
// W/p · L(x1 → camera) along one camera sample's bidirectional strategies, on the tape, with the shading
// horizons of the camera subpath's surface vertices (`horizon`, diff/psdr/shading_horizon.h; null: none);
// the other arguments are volumetric_camera_path's (diff/psdr/interior_media.h).
Color3<Var> bidirectional_camera_path(const BDPTPass& pass, const MaterialForm& form, Sampler& sampler,
                                      const Ray& ray, const Color3f& ray_weight, const CameraFactor& camera,
                                      float escaped_weight, HorizonRule* horizon, RayCounter& rays);

} // namespace penumbra
