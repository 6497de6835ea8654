// Cage-free non-rigid deformations of shapes as optimized quantities: the <shape>.deform motion of
// diff/parameters.h made finite. Handles k, each with a center c_k and a displacement θ_k ∈ R³ (world units),
// move the shape's reference mesh (the scene's vertices, never the previous iterate):
//   x = x0 + Σ_k θ_k φ_k(x0),   φ_k(x) = exp(−‖x − c_k‖² / 2r²),
// r a quarter of the reference bounding box's diagonal (the motion's radius), and normals by the inverse
// transpose of the deformation gradient F = I + Σ_k θ_k ∇φ_k(x0)ᵀ. The gradient with respect to θ_k is taken
// with the motions <shape>.deform@c_k along x, y and z at the current mesh (first order in θ: exact at θ =
// 0).
#pragma once
#include "core/vector.h"

#include <vector>

namespace penumbra {

class Shape;

class ShapeDeformation {
  public:
    // Remembers the shape's current mesh as the reference (every θ_k = 0).
    explicit ShapeDeformation(Shape& shape);

    Shape& shape() const { return shape_; }
    // The center of the reference bounding box (a handle's default center).
    Vec3f center() const { return center_; }
    // Adds a handle at `center` and returns its index.
    int add_handle(const Vec3f& center);
    const Vec3f& handle_center(int handle) const { return centers_[size_t(handle)]; }
    const Vec3d& displacement(int handle) const { return thetas_[size_t(handle)]; }
    void set(int handle, const Vec3d& theta) { thetas_[size_t(handle)] = theta; }
    // Writes the deformed reference mesh into the shape and finalizes it (the caller rebuilds the BVH).
    void apply() const;

  private:
    Shape& shape_;
    std::vector<Vec3f> positions_, normals_;
    Vec3f center_;
    double radius_ = 0;
    std::vector<Vec3f> centers_;
    std::vector<Vec3d> thetas_;
};

} // namespace penumbra
