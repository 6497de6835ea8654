// The motion X(p, θ) of points inside participating media (paper 001 §6.1–6.2): a medium vertex is sampled
// at p in the reference configuration and re-evaluated at x = X(p, θ) with the volume Jacobian
// J = dV(x)/dV(p) (Eq. 46). X must carry every moving surface that bounds a medium (so that the media's
// boundaries are fixed in material space, assumption A.4) and be the identity elsewhere.
#pragma once
#include "core/var.h"
#include "core/vector.h"

#include <memory>

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
    // x = X(p, θ) on the thread's tape (first order at θ0) for a point p of `medium` in the reference
    // configuration; *jacobian (if not null) receives J = dV(x)/dV(p).
    Vec3<Var> position(const Vec3f& p, const Medium* medium, Var* jacobian) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace penumbra
