// The shading horizon of a path vertex: a boundary of the direct-illumination integral that no edge carries.
// A surface shaded with interpolated vertex normals scatters light arriving from below the geometric tangent
// plane of its triangle (the BSDF sees the shading frame only), yet its own solid hides what lies there: the
// integrand f_s L_e G V of a vertex x jumps where a light point y crosses the plane s = n_g · (y − x) = 0.
// When the light or the surface moves, the jump moves over the light, and the material form's derivative has
// the boundary term (paper 001 Eq. 19, second term, with the plane as the discontinuity)
//     ∫_{C_x} f_s(x → ω_y) L_e(y → x) G(x, y) (V₊ − V₋) ṡ / |∇_A s| dℓ(y),
// C_x the curve where the plane meets the light's triangles, V± the visibility of y from just above and just
// below the plane (a closed solid blocks one side; an open sheet blocks neither: no jump), ṡ = ds/dθ with x,
// n_g and y at their material points, and |∇_A s| = |n_g − (n_g · n_y) n_y| the gradient of s along the
// light. For an environment C_x is the plane's great circle of directions, s = n_g · ω and |∇s| = 1.
// It is estimated at every vertex of the interior term's camera paths (and camera subpaths): one area
// light whose bounding sphere the plane cuts (chosen uniformly) and a point of C_x by length; every
// environment emitter at a uniform direction of the great circle. Light that other surfaces reflect across
// the plane (a moving smooth-shaded object's horizon sweeping over the rest of the scene, or a moving surface
// crossing a static one's) is the same jump in direction form: at a uniform direction ω of the great circle
// the grazing ray finds z, and the term is f_s(x → ω) L_r(z → x) ṡ / r (r = |z − x|, s = n_g · (z − x), L_r
// the radiance z reflects, its emission being the area-light technique's), with L_r estimated by a path
// traced from z; it is drawn only where x or z moves. The estimate enters the interior's tape as g (s −
// detach(s)): value 0, derivative g ṡ.
#pragma once
#include "diff/auxiliary_rng.h"
#include "diff/material_form.h"
#include "render/path_tracer.h"

#include <optional>
#include <vector>

namespace penumbra {

class ShadingHorizon {
  public:
    ShadingHorizon(const Scene& scene, const Parameters& params);
    // The term at the vertex `hit` (si: the same vertex on the tape, its wi set) of a path `depth` bounces
    // from the camera, per unit path throughput; none where nothing was drawn (flat shading, no light the
    // plane cuts), so that such vertices put nothing on the tape.
    std::optional<Color3<Var>> sample(const MaterialForm& form, const BSDF& bsdf,
                                      const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                                      unsigned depth, const PathSettings& settings, AuxiliaryRng& rng,
                                      RayCounter& rays) const;

  private:
    struct AreaLight {
        const Emitter* emitter;
        const Shape* shape;
        BoundingSphere bounds;
    };
    std::optional<Color3<Var>> area_light(const MaterialForm& form, const BSDF& bsdf,
                                          const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                                          const AreaLight& light, float weight, const Vec2f& u,
                                          RayCounter& rays) const;
    std::optional<Color3<Var>> environment(const BSDF& bsdf, const SurfaceInteraction3f& hit,
                                           const SurfaceInteraction<Var>& si, const Emitter& emitter, float u,
                                           RayCounter& rays) const;
    std::optional<Color3<Var>> surfaces(const MaterialForm& form, const BSDF& bsdf,
                                        const SurfaceInteraction3f& hit, const SurfaceInteraction<Var>& si,
                                        const PathSettings& reflected, AuxiliaryRng& rng,
                                        RayCounter& rays) const;

    const Scene& scene_;
    const Parameters& params_;
    bool moving_ = false; // some shape moves (surfaces' horizons can sweep)
    std::vector<AreaLight> area_;
    std::vector<const Emitter*> environments_;
};

// The interior term's vertex rule: the material form's, with the shading horizon attached at every vertex
// (none where `horizon` is null).
struct HorizonRule : GeometryRule<Var, MaterialForm> {
    const ShadingHorizon* horizon;
    PathSettings settings;
    AuxiliaryRng rng;
    std::optional<Color3<Var>> attached_boundary(const BSDF& bsdf, const SurfaceInteraction3f& hit,
                                                 const SurfaceInteraction<Var>& si, unsigned depth,
                                                 RayCounter& rays) {
        if (!horizon) return std::nullopt;
        return horizon->sample(geometry, bsdf, hit, si, depth, settings, rng, rays);
    }
};

} // namespace penumbra
