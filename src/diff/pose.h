// Rigid poses of shapes as optimized quantities. A pose (t, R) moves the shape's reference mesh (the scene's
// vertices, never the previous iterate) about its reference bounding-box center c0:
//   x = c0 + t + (1 + s) R (x0 − c0),   n = R n0   (s: uniform scale, 0 unless set; diff/parameter_table.h).
// Rotations are updated on the left by the exponential map, R ← exp([ω]×) R with ω a world-space rotation
// vector about the current center c0 + t: the increments are the same world-frame motions that the gradient
// is taken with respect to (diff/parameters.h), so Adam's moments live in one fixed tangent frame.
#pragma once
#include "core/vector.h"

#include <string>
#include <vector>

namespace penumbra {

class Shape;

struct Mat3d {
    double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    Vec3d operator*(const Vec3d& v) const;
    Mat3d operator*(const Mat3d& o) const;
    Mat3d transpose() const;
};

// exp([ω]×): rotation by |ω| radians about ω / |ω| (Rodrigues).
Mat3d rotation_from_vector(const Vec3d& omega);
// The left Jacobian J_l(φ) of SO(3): exp(φ + δ) ≈ exp([J_l(φ) δ]×) exp([φ]×), i.e. a change δ of a rotation
// vector is the world-frame rotation J_l(φ) δ applied on the left.
Mat3d left_jacobian(const Vec3d& phi);
// The inverse (log map): the rotation vector of R, angle in [0, π] radians.
Vec3d rotation_vector(const Mat3d& r);
// Geodesic distance: the angle of a bᵀ, radians (atan2 form, accurate near 0).
double rotation_angle(const Mat3d& a, const Mat3d& b);

class ShapePose {
  public:
    // Remembers the shape's current mesh as the reference (pose t = 0, R = I).
    explicit ShapePose(Shape& shape);
    // The same about a given center (the common center of an instance's shapes).
    ShapePose(Shape& shape, const Vec3d& center);

    Shape& shape() const { return shape_; }
    const Vec3d& translation() const { return t_; }
    const Mat3d& rotation() const { return r_; }
    // Current rotation center c0 + t (world).
    Vec3d center() const { return c0_ + t_; }

    double scale() const { return s_; }
    void set(const Vec3d& translation, const Mat3d& rotation, double scale = 0.0) {
        t_ = translation, r_ = rotation, s_ = scale;
    }
    // Writes the posed reference mesh into the shape and finalizes it (the caller rebuilds the BVH).
    void apply() const;

  private:
    Shape& shape_;
    std::vector<Vec3f> positions_, normals_;
    Vec3d c0_;
    Vec3d t_{0, 0, 0};
    Mat3d r_;
    double s_ = 0.0;
};

} // namespace penumbra
