// Differential vertex sampling (paper 002 §4.1, Algorithm 1): at an intermediate vertex x_i whose BSDF has a
// differential lobe (BSDF::has_differential_lobe), the vertex becomes the path's differential vertex with
// probability q_i, and the next direction is then drawn from the differential density p_∂f instead of the
// BSDF density p_f; once a path has its differential vertex, later vertices use p_f. q_i = q at vertices with
// a lobe and 0 elsewhere (a vertex without a lobe would have p_∂f = p_f: spending the path's one differential
// vertex there gains nothing). Since q_i depends only on the path prefix, the mixture density of Eq. (24)
// holds with q replaced by q_i.
#pragma once
#include "scene/bsdf.h"

namespace penumbra {

// p_∂f = (p_+ + p_−) / 2: the sign of the single-signed decomposition is chosen at random with probability
// 1/2 (as the paper does; not antithetically), then the signed lobe is sampled.
inline BSDFSample sample_differential_lobe(const BSDF& bsdf, const BSDFContext& ctx, const SurfaceInteraction3f& si,
                                           float u_sign, float u1, const Vec2f& u2) {
    const int sign = u_sign < 0.5f ? 1 : -1;
    BSDFSample bs = bsdf.sample_differential(ctx, si, sign, u1, u2);
    if (!(bs.pdf > 0.f)) return {};
    bs.pdf = 0.5f * (bsdf.pdf_differential(ctx, si, 1, bs.wo) + bsdf.pdf_differential(ctx, si, -1, bs.wo));
    return bs;
}

inline float pdf_differential_lobe(const BSDF& bsdf, const BSDFContext& ctx, const SurfaceInteraction3f& si, const Vec3f& wo) {
    return 0.5f * (bsdf.pdf_differential(ctx, si, 1, wo) + bsdf.pdf_differential(ctx, si, -1, wo));
}

// The bracket of Eq. (24), accumulated along the path (Algorithm 1, lines 14-15): after the intermediate
// vertices x_1 … x_k,
//   w1 = Σ_{i<=k} (p_∂f(x_i) / p_f(x_i)) q_i Π_{l<i} (1 − q_l)   (the differential vertex is one of them),
//   w2 = Π_{i<=k} (1 − q_i)                                     (none of them is),
// so that p_mix(x̄) = [Π p_f] (w1 + w2). The product Π p_f is in the throughput, as in the paper.
struct DifferentialMIS {
    double w1 = 0.0, w2 = 1.0;
    void advance(double q, double ratio) {
        w1 += w2 * q * ratio;
        w2 *= 1.0 - q;
    }
    double mixture() const { return w1 + w2; }
};

} // namespace penumbra
