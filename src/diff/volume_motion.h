// The motion X(p, θ) of points inside participating media (paper 001 §6.1–6.2): a medium vertex is sampled
// at p in the reference configuration and re-evaluated at x = X(p, θ) with the volume Jacobian
// J = dV(x)/dV(p) (Eq. 46). X must carry every moving surface that bounds a medium (so that the media's
// boundaries are fixed in material space, assumption A.4) and be the identity elsewhere.
//
// For each shape the enabled parameters move (scene/tet_mesh.h builds the tet meshes once, here):
//  - its interior medium moves with it: affine motions (translate, rotate, scale) in closed form (J = 1 + 3θ
//    for scaling); otherwise (deform, vertex_positions) on a TetGen mesh of its interior whose vertices move
//    as the surface does (the deformation field at the Steiner points, or for vertex_positions a few sweeps
//    of neighbor averages), x interpolated linearly in each tet (Eq. (53)) and J the ratio of tet volumes
//    (Eq. (46));
//  - the medium around it (its exterior, or the medium it sits in when it declares none) moves in a shell:
//    a TetGen mesh between the shape and a box around it (up to twice its bounding box, each face stopping
//    short of other shapes' triangles), the shape's motion on its surface, zero on the box, harmonic in
//    between (Gauss-Seidel sweeps of the graph Laplacian); the identity outside the box. Open meshes (thin
//    sheets) work too. A shape touching another has no such box: Error.
// Moving a medium's container with other shapes inside it is refused (Error).
#pragma once
#include "core/var.h"
#include "core/vector.h"

#include <memory>
#include <string>
#include <vector>

namespace penumbra {

class Scene;
class Parameters;
class Medium;

class VolumeMotion {
  public:
    VolumeMotion(const Scene& scene, const Parameters& params);
    ~VolumeMotion();
    VolumeMotion(const VolumeMotion&) = delete;
    VolumeMotion& operator=(const VolumeMotion&) = delete;

    // Whether X is the identity in every medium.
    bool identity() const;
    // Why X does not follow some shapes moved only by their vertex_positions (reverse mode enables them all):
    // the errors that a selected motion of those shapes would throw. Their media's derivatives are missing.
    const std::vector<std::string>& omitted() const;
    // x = X(p, θ) on the thread's tape (first order at θ0) for a point p of `medium` in the reference
    // configuration; *jacobian (if not null) receives J = dV(x)/dV(p).
    Vec3<Var> position(const Vec3f& p, const Medium* medium, Var* jacobian) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace penumbra
