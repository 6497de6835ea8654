// The camera's end of a volumetric path in the interior term (paper 001 §5.1 with media): the chain from the
// camera through the sensor's medium and null surfaces to the first vertex x1 — a surface vertex, or a
// medium vertex (a volume measure, Eqs. 22–23 with |ds/dω| / ℓ² in place of |ds/dA|) — then
// render/volpath_tracer.h for the rest of the path.
#pragma once
#include "diff/material_form.h"
#include "render/path_tracer.h"

#include <functional>

namespace penumbra {

// The camera factor W/p of a material-form first vertex at x1(θ) with normal n (toward the camera for a
// medium vertex) and Jacobian J (area or volume).
using CameraFactor = std::function<Var(const Vec3<Var>& x1, const Vec3<Var>& n, const Var& jacobian)>;

// W/p · (L_e(x1 → camera) + L(x1 → camera)) along one sampled path started by the camera ray `ray` (the
// film sample's weight included in `camera` or `ray_weight`). Image space (form.image_space_first_vertex()):
// the ray is fixed, x1 slides along it (a medium vertex keeps its fraction of the ray's piece between the
// moving surfaces around it, with the Jacobian of that stretch) and W/p = ray_weight. Material form: x1 =
// X(p1, θ) and W/p = camera(x1, n, J) · ray_weight (escaped rays: escaped_weight · ray_weight, a direction
// does not move on the film).
Color3<Var> volumetric_camera_path(const Scene& scene, const MaterialForm& form, Sampler& sampler,
                                   const Ray& ray, const Color3f& ray_weight, const CameraFactor& camera,
                                   float escaped_weight, const PathSettings& settings, RayCounter& rays);

// The image-space parameterization of a medium point x seen by the pinhole at `camera` (the first vertex of
// volumetric_camera_path): the point at x's fraction of its piece of the fixed camera ray, between the
// moving surfaces around it (or the camera), on the tape. Boundary terms take the velocity of a medium
// endpoint connected directly to the camera relative to it.
Vec3<Var> seen_medium_point(const Scene& scene, const MaterialForm& form, const Vec3f& camera, const Vec3f& x);

} // namespace penumbra
