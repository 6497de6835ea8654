#include "optim/deformation.h"

#include "core/error.h"
#include "scene/shape.h"

#include <cmath>

namespace penumbra {

ShapeDeformation::ShapeDeformation(Shape& shape)
    : shape_(shape), positions_(shape.mesh.positions), normals_(shape.mesh.normals) {
    Vec3f lo(Infinity), hi(-Infinity);
    for (const Vec3f& p : positions_) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    center_ = (lo + hi) * 0.5f;
    radius_ = 0.25 * double(norm(hi - lo));
    if (!(radius_ > 0)) throw Error("shape '" + shape.id + "': a deformation needs a non-empty bounding box");
}

int ShapeDeformation::add_handle(const Vec3f& center) {
    centers_.push_back(center);
    thetas_.emplace_back(0.0);
    return int(centers_.size()) - 1;
}

void ShapeDeformation::apply() const {
    for (size_t v = 0; v < positions_.size(); ++v) {
        const Vec3d x0(positions_[v]);
        Vec3d x = x0;
        double f[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}; // F = I + Σ θ_k ∇φ_kᵀ
        for (size_t k = 0; k < centers_.size(); ++k) {
            const Vec3d r = x0 - Vec3d(centers_[k]);
            const double phi = std::exp(-dot(r, r) / (2.0 * radius_ * radius_));
            const Vec3d grad = r * (-phi / (radius_ * radius_));
            x += thetas_[k] * phi;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    f[i][j] += thetas_[k][i] * grad[j];
        }
        shape_.mesh.positions[v] = Vec3f(x);
        if (v >= normals_.size()) continue;
        // n' ∝ F⁻ᵀ n = cof(F) n / det F (rows c0, c1, c2 of the cofactor matrix; det F > 0 for small θ).
        const Vec3d c0(f[1][1] * f[2][2] - f[1][2] * f[2][1], f[1][2] * f[2][0] - f[1][0] * f[2][2],
                       f[1][0] * f[2][1] - f[1][1] * f[2][0]);
        const Vec3d c1(f[0][2] * f[2][1] - f[0][1] * f[2][2], f[0][0] * f[2][2] - f[0][2] * f[2][0],
                       f[0][1] * f[2][0] - f[0][0] * f[2][1]);
        const Vec3d c2(f[0][1] * f[1][2] - f[0][2] * f[1][1], f[0][2] * f[1][0] - f[0][0] * f[1][2],
                       f[0][0] * f[1][1] - f[0][1] * f[1][0]);
        const Vec3d n(normals_[v]);
        shape_.mesh.normals[v] = Vec3f(normalize(Vec3d(dot(c0, n), dot(c1, n), dot(c2, n))));
    }
    shape_.finalize();
}

} // namespace penumbra
