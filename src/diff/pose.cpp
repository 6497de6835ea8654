#include "diff/pose.h"

#include "scene/shape.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

Vec3d Mat3d::operator*(const Vec3d& v) const {
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

Mat3d Mat3d::operator*(const Mat3d& o) const {
    Mat3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j];
    return r;
}

Mat3d Mat3d::transpose() const {
    Mat3d r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r.m[i][j] = m[j][i];
    return r;
}

// R = I + sin θ [a]× + (1 − cos θ) [a]×², θ = |ω|, a = ω / θ.
Mat3d rotation_from_vector(const Vec3d& omega) {
    const double theta = norm(omega);
    Mat3d r;
    if (theta == 0.0) return r;
    const Vec3d a = omega / theta;
    const double s = std::sin(theta), c = 1.0 - std::cos(theta);
    const double k[3][3] = {{0, -a.z, a.y}, {a.z, 0, -a.x}, {-a.y, a.x, 0}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double k2 = 0;
            for (int l = 0; l < 3; ++l)
                k2 += k[i][l] * k[l][j];
            r.m[i][j] += s * k[i][j] + c * k2;
        }
    return r;
}

// J_l(φ) = I + (1 − cos θ)/θ² [φ]× + (θ − sin θ)/θ³ [φ]×², θ = |φ| (the SO(3) left Jacobian; Barfoot, State
// Estimation for Robotics, ch. 7).
Mat3d left_jacobian(const Vec3d& phi) {
    const double theta2 = dot(phi, phi), theta = std::sqrt(theta2);
    // Taylor series below 1e-3 rad (the closed forms cancel catastrophically there).
    const double a = theta < 1e-3 ? 0.5 - theta2 / 24.0 : (1.0 - std::cos(theta)) / theta2;
    const double b = theta < 1e-3 ? 1.0 / 6.0 - theta2 / 120.0 : (theta - std::sin(theta)) / (theta2 * theta);
    const double k[3][3] = {{0, -phi.z, phi.y}, {phi.z, 0, -phi.x}, {-phi.y, phi.x, 0}};
    Mat3d j;
    for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 3; ++c) {
            double k2 = 0;
            for (int l = 0; l < 3; ++l)
                k2 += k[i][l] * k[l][c];
            j.m[i][c] += a * k[i][c] + b * k2;
        }
    return j;
}

Vec3d rotation_vector(const Mat3d& r) {
    // The skew part is sin θ · a, the trace 1 + 2 cos θ.
    const Vec3d w = Vec3d(r.m[2][1] - r.m[1][2], r.m[0][2] - r.m[2][0], r.m[1][0] - r.m[0][1]) * 0.5;
    const double s = norm(w), c = (r.m[0][0] + r.m[1][1] + r.m[2][2] - 1.0) * 0.5;
    const double theta = std::atan2(s, c);
    if (s < 1e-12 && c > 0) return w;
    if (c > -0.99) return w * (theta / s);
    // Near θ = π the skew part vanishes: the axis is the dominant column of (R + I) / 2 = a aᵀ + O(sin θ).
    int i = 0;
    for (int k = 1; k < 3; ++k)
        if (r.m[k][k] > r.m[i][i]) i = k;
    Vec3d a(r.m[0][i] + r.m[i][0], r.m[1][i] + r.m[i][1], r.m[2][i] + r.m[i][2]);
    a[i] = r.m[i][i] + 1.0;
    a = normalize(a);
    if (dot(a, w) < 0) a = -a;
    return a * theta;
}

double rotation_angle(const Mat3d& a, const Mat3d& b) {
    const Mat3d d = a * b.transpose();
    const Vec3d w(d.m[2][1] - d.m[1][2], d.m[0][2] - d.m[2][0], d.m[1][0] - d.m[0][1]);
    return std::atan2(0.5 * norm(w), (d.m[0][0] + d.m[1][1] + d.m[2][2] - 1.0) * 0.5);
}

ShapePose::ShapePose(Shape& shape)
    : shape_(shape), positions_(shape.mesh.positions), normals_(shape.mesh.normals) {
    Vec3f lo(Infinity), hi(-Infinity);
    for (const Vec3f& p : positions_) {
        lo = min(lo, p);
        hi = max(hi, p);
    }
    c0_ = Vec3d((lo + hi) * 0.5f);
}

ShapePose::ShapePose(Shape& shape, const Vec3d& center)
    : shape_(shape), positions_(shape.mesh.positions), normals_(shape.mesh.normals), c0_(center) {}

void ShapePose::apply() const {
    for (size_t i = 0; i < positions_.size(); ++i)
        shape_.mesh.positions[i] = Vec3f(c0_ + t_ + r_ * (Vec3d(positions_[i]) - c0_) * (1.0 + s_));
    for (size_t i = 0; i < normals_.size(); ++i)
        shape_.mesh.normals[i] = Vec3f(normalize(r_ * Vec3d(normals_[i])));
    shape_.finalize();
}

} // namespace penumbra
