#include "diff/volume_motion.h"

#include "diff/parameters.h"

namespace penumbra {

struct VolumeMotion::Impl {};

VolumeMotion::VolumeMotion(const Scene&, const Parameters&) {}
VolumeMotion::~VolumeMotion() = default;

bool VolumeMotion::identity() const { return true; }

Vec3<Var> VolumeMotion::position(const Vec3f& p, const Medium*, Var* jacobian) const {
    if (jacobian) *jacobian = Var(1.f);
    return Vec3<Var>(p);
}

} // namespace penumbra
