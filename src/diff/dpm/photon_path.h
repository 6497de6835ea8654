// A photon-mapping path on an extended path space manifold (paper 003 §5): the eye subpath x_1 (the camera)
// ... x_s (the visible point, where the density is estimated) through specular vertices, the photon x*_s,
// and its light subpath back to the emitter, X = [x_1, ..., x_s, x*_s, x_{s+1}, ..., x_k] (Eq. 21). Its
// vertices follow the scene parameters under one of three EPSMs (Fig. 5), which share the light subpath's
// constraints — the light's position fixed, the emitted direction fixed in the light's frame, a half
// vector at each specular middle vertex and the outgoing direction fixed at each other one — and differ on the
// eye subpath:
//   FixedEyeRay   DPM-C (§5.2.1): the eye ray fixed in the camera's frame and half vectors along the chain, so
//                 x_s slides along its pixel's ray: contribution derivatives only, no screen-space motion;
//   FixedDensity  DPM-G's first EPSM (§5.2.2): x_s fixed on its surface, half vectors up to the camera;
//   VertexMerge   DPM-G's second EPSM: the photon fixed in x_s's local frame (Eq. 24), so x_s follows it.
// The contribution (Eq. 23) is evaluated on the moving vertices as its ratio to the reference value: the
// sampling densities stay at θ0 (they divide the value the estimator already has), every direction the light
// walk sampled keeps its local coordinates (the cosines there are constant), and each specular vertex
// contributes its smooth factor g only (BSDF decomposition, §4.2.2: D(h) is constant under its half-vector
// constraint).
#pragma once
#include "diff/dpm/epsm.h"
#include "render/path_vertex.h"
#include "render/photon_kernel.h"
#include "render/visible_point.h"

#include <vector>

namespace penumbra {

enum class PhotonPathEpsm { FixedEyeRay, FixedDensity, VertexMerge };

// The sampled path in the reference configuration.
struct PhotonPath {
    Vec3f camera;                                  // x_1, the camera's center of projection
    const std::vector<SpecularVertex>* eye_chain;  // x_2 ... x_{s-1}
    const SurfaceInteraction3f* visible;           // x_s
    const std::vector<PathVertex>* light;          // the light subpath y_0 (on the emitter) ... y_j = x*_s
    int photon = 0;                                // j
    float radius = 0.f;                            // the merging radius r (fixed)
    PhotonKernel kernel = PhotonKernel::Smooth;
};

struct PhotonPathValue {
    Color3<Var> ratio;  // I(X(θ), θ) / I(X0, θ0) (Eq. 23), 1 at θ0, on the tape
    Vec3<Var> first;    // x_2 (the eye ray's first hit), for screen-space positions
};

// Builds the EPSM, solves Eq. 2 on the current tape and evaluates the contribution ratio. False when the
// constraint Jacobian is singular or a factor of the contribution is zero at θ0 (the path is dropped).
bool photon_path_value(const Parameters& params, const PhotonPath& path, PhotonPathEpsm epsm,
                       PhotonPathValue& out);

} // namespace penumbra
