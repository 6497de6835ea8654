// The linear control variate of warped-area sampling (paper 004 §4.2, Appendix D) for the primary vertex,
// whose film position x (pixel units, relative to the pixel center) is sampled from the Gaussian pixel filter
// k = N(0, σ² I). The filter's share of the area term (Eq. 5), ∫ g ⟨∂x k, V⟩ dx, is estimated by
//   M(x) = g(x) ⟨∂x k(x) / k(x), V(x)⟩ = −g(x) ⟨x, V(x)⟩ / σ²,
// which is noisy even for a flat emitter (E[M] = 0 when g V is constant). With the linear model
// g V ≈ μ_g μ_V + A x, A = μ_g ∇V + μ_V ∇gᵀ (Appendix D), the control
//   C(x) = −⟨x, μ_g μ_V + A x⟩ / σ²  (Eq. 14 with the score of k)
// has the known mean E[C] = −tr(A) (E[x xᵀ] = σ² I; the paper's σ² tr(A) is the same with ∂x k unnormalized),
// so Q = M − C + E[C] is unbiased whatever A is, as long as A does not depend on x (estimate μ_g, ∇g, μ_V, ∇V
// from other samples, e.g. the previous pass or pixel).
#pragma once
#include "core/vector.h"

namespace penumbra {

struct LinearControlVariate {
    static float dot2(const Vec2f& a, const Vec2f& b) { return a.x * b.x + a.y * b.y; }

    float sigma = 0.5f; // the filter's standard deviation (pixels)
    float mu_g = 0.f;   // mean radiance over the pixel
    Vec2f grad_g;       // mean ∂x g
    Vec2f mu_v;         // mean warp V
    Vec2f jac_v[2];     // mean ∂x V: rows ∂x V_0, ∂x V_1

    // A = μ_g ∇V + μ_V ∇gᵀ, as rows.
    Vec2f row(int r) const { return jac_v[r] * mu_g + grad_g * (r == 0 ? mu_v.x : mu_v.y); }
    // C(x) (Eq. 14).
    float control(const Vec2f& x) const {
        const Vec2f ax(dot2(row(0), x), dot2(row(1), x));
        return -(dot2(x, mu_v * mu_g) + dot2(x, ax)) / (sigma * sigma);
    }
    // E[C] = −tr(A).
    float mean() const { return -(row(0).x + row(1).y); }
    // Q = M − C(x) + E[C].
    float controlled(float m, const Vec2f& x) const { return m - control(x) + mean(); }
};

} // namespace penumbra
