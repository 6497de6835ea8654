// A motion field on a tetrahedral mesh (paper 001 §6.1–6.2), one region of the motion X of a medium
// (diff/volume_motion.h): velocities dX_k/dθ_k at the mesh's vertices, interpolated linearly in each tet
// (Eq. (53)), with the volume Jacobian of Eq. (46); or, without a mesh, a shape's affine motions in closed
// form.
#pragma once
#include "core/var.h"
#include "diff/parameters.h"
#include "scene/tet_mesh.h"

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace penumbra {

// One region where X is not the identity: the interior of a moving shape (its interior medium), or the shell
// between a moving shape and a box around it (the medium around the shape).
struct VolumeRegion {
    const Shape* shape = nullptr;
    const std::vector<Motion>* motions = nullptr;
    bool vertex_positions = false;
    Vec3f lo, hi; // points outside are not moved by this region
    // Tets (none: the interior of a shape under affine motions only, X given in closed form).
    TetMesh mesh;
    std::unique_ptr<TetLocator> locator;
    std::vector<Vec3f> velocity;   // dX_k/dθ_k at tet vertex i: [i * K + k]
    std::vector<float> divergence; // div dX_k in tet t (the derivative of Eq. (46) at θ0): [t * K + k]
    // vertex_positions: tet vertex i moves by Σ w δx_s over the shape's vertices s ([start[i], start[i+1])).
    std::vector<uint32_t> weight_start;
    std::vector<std::pair<uint32_t, float>> weights;

    size_t K() const { return motions->size(); }

    // Fills velocity (a field evaluated at every vertex, or harmonic away from the fixed ones), the
    // divergences and the vertex_positions weights. The first `fixed_inputs` input vertices are fixed: the
    // shape's (their motion) and the box's corners (zero); the Steiner points on the surface too (the
    // surface's motion there); `shape_vertex[i]`: the shape's vertex at tet vertex i, or -1.
    void interpolate(const std::vector<int64_t>& shape_vertex, size_t fixed_inputs, bool harmonic);
    // Adds this region's displacement X(p, θ) - p and J - 1 at p (nothing when p lies outside it).
    void add(const Vec3f& p, Vec3<Var>& x, Var* jacobian) const;

  private:
    // The vertex_positions weights: 1 at the shape's vertices, 0 at the box, and a few Jacobi-style sweeps
    // (the 4 largest weights kept: a few tape nodes per point) at the Steiner points; in the interior they
    // sum to 1 (translating every vertex translates the medium).
    void interpolate_weights(const std::vector<int64_t>& shape_vertex, const std::vector<bool>& fixed,
                             const std::vector<uint32_t>& start, const std::vector<uint32_t>& nb,
                             bool normalize);
};

} // namespace penumbra
