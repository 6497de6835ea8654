#include "scene/volume.h"

#include <utility>

namespace penumbra {

// Slab test (Kay & Kajiya 1986).
bool BoundingBox3f::intersect(const Vec3f& o, const Vec3f& d, float& t0, float& t1) const {
    t0 = -Infinity;
    t1 = Infinity;
    for (int a = 0; a < 3; ++a) {
        const float inv = 1.f / d[a];
        float near = (lo[a] - o[a]) * inv, far = (hi[a] - o[a]) * inv;
        if (std::isnan(near) || std::isnan(far)) { // d[a] = 0 with o[a] on a slab plane
            if (o[a] < lo[a] || o[a] > hi[a]) return false;
            continue;
        }
        if (near > far) std::swap(near, far);
        t0 = std::max(t0, near);
        t1 = std::min(t1, far);
        if (t0 > t1) return false;
    }
    return true;
}

} // namespace penumbra
