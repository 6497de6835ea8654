// The "large steps" parameterization of a mesh's vertex positions (Nicolet, Jacobson and Jakob 2021, "Large
// Steps in Inverse Rendering of Geometry"): the optimizer steps in u = (I + λL) x instead of x, where L is
// the uniform (combinatorial) Laplacian of the mesh, L_ii = deg(i), L_ij = −1 for every edge (i, j). Then
//   x = (I + λL)⁻¹ u                  (their Eq. 13: positions from the latent variables),
//   dL/du = (I + λL)⁻ᵀ dL/dx = (I + λL)⁻¹ dL/dx   (I + λL is symmetric),
// so a gradient step in u moves x by a smoothed (low-pass filtered) step, and the high frequencies of the
// noisy, silhouette-concentrated gradient no longer tear the mesh. I + λL is symmetric positive definite; it
// is factorized once per mesh (Eigen's sparse Cholesky, SimplicialLDLT) and every solve is two triangular
// solves. Values are n × 3, stored row-major per vertex (x0, y0, z0, x1, ...), the layout of
// vertex_positions.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace penumbra {

class LargeSteps {
  public:
    // `indices`: 3 per triangle into [0, vertex_count) (a vertex in no triangle keeps x = u). Throws Error on
    // an out-of-range index, λ ≤ 0 or a failed factorization.
    LargeSteps(std::span<const uint32_t> indices, int vertex_count, double lambda);
    ~LargeSteps();
    LargeSteps(const LargeSteps&) = delete;
    LargeSteps& operator=(const LargeSteps&) = delete;

    int vertex_count() const { return vertex_count_; }
    double lambda() const { return lambda_; }

    // u = (I + λL) x.
    std::vector<double> to_latent(std::span<const double> x) const;
    // x = (I + λL)⁻¹ u (Eq. 13 of Nicolet et al.).
    std::vector<double> from_latent(std::span<const double> u) const;
    // dL/du = (I + λL)⁻¹ dL/dx (the chain rule through from_latent; the operator is symmetric).
    std::vector<double> latent_gradient(std::span<const double> dx) const { return from_latent(dx); }

  private:
    struct Factorization;
    std::unique_ptr<Factorization> factorization_;
    int vertex_count_ = 0;
    double lambda_ = 0;
};

} // namespace penumbra
