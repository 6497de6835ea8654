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
//
// penumbra samples film positions from a defensive mixture p (diff/film_sample.h) and uses the sample's own
// ∇P_j / p in place of the Gaussian score: C = ⟨∇P_j / p, μ_g μ_V + A x⟩ with E[C] = −tr(A) for any filter
// that falls continuously to zero at its support's edge (integration by parts). Where the film's edge cuts the
// support (hdrfilm without sample_border: P_j ends there), E[C] gains the flux Σ_cuts ∮ P_j (μ_g μ_V + A x)·n.
#pragma once
#include "core/vector.h"
#include "scene/film.h"

#include <vector>

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

// ∇P_j(x) / p(x) at the film offset x from pixel (px, py)'s center (central differences of the uncut filter,
// 0 off the film).
Vec2f filter_gradient_ratio(const Film& film, int px, int py, const Vec2f& offset, float pdf);

// Where the film's edge cuts pixel j's filter support: the outward normal of the cut and the moments
// ∫ P_j dℓ and ∫ P_j x dℓ along it (x the offset from the pixel center; midpoint rule).
struct FilmCut {
    Vec2f normal;
    float m0 = 0.f;
    Vec2f m1;
};
std::vector<FilmCut> film_cuts(const Film& film, int px, int py);

// Q − M = −(C(x) − E[C]) for the control variate `cv` at film offset x with score ∇P_j / p, E[C] = −tr(A) +
// the cuts' flux.
float control_correction(const LinearControlVariate& cv, const std::vector<FilmCut>& cuts, const Vec2f& x,
                         const Vec2f& score);

} // namespace penumbra
