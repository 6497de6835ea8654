// Phase functions (Mitsuba 3's `isotropic` and `hg`). Directions are world-space unit vectors pointing away
// from the scattering point: `wi` toward the previous path vertex, `wo` toward the next, so that forward
// scattering is wo = -wi. eval() is templated on the scalar type (one physics code path); sampling is exact
// (the sampling weight eval/pdf is 1).
#pragma once
#include "core/frame.h"
#include "core/math.h"
#include "core/param.h"
#include "core/scalar.h"
#include "scene/object.h"

#include <utility>

namespace penumbra {

class PhaseFunction : public Object {
  public:
    ObjectKind kind() const override { return ObjectKind::Phase; }
    float g = 0.f;    // Henyey-Greenstein asymmetry (0 = isotropic), in (-1, 1)
    int g_index = -1; // parameter index of g when differentiated

    // p(wi, wo) = (1 - g²) / (4π (1 + g² + 2 g (wi·wo))^{3/2})  (Henyey & Greenstein 1941, Mitsuba's sign).
    template <typename T> T eval(const Vec3<T>& wi, const Vec3<T>& wo) const {
        using std::sqrt;
        const T gv = param_value<T>(g, g_index);
        const T denom = T(1) + gv * gv + T(2) * gv * dot(wi, wo);
        return T(Inv4Pi) * (T(1) - gv * gv) / (denom * sqrt(denom));
    }
    // Samples wo ~ p(wi, ·) exactly; returns wo and its solid-angle density.
    std::pair<Vec3f, float> sample(const Vec3f& wi, const Vec2f& u) const;
    float pdf(const Vec3f& wi, const Vec3f& wo) const { return eval<float>(wi, wo); }
    void traverse(ParamVisitor& v) override;
};

} // namespace penumbra
