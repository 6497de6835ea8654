#include "diff/warp_field.h"

#include <cmath>

namespace penumbra {

namespace {

// The tangent of a tape value with value 0: V_direct without its value ω' (the estimate needs only ∂θ ω').
Vec3<Var> tangent_part(const Vec3<Var>& v) {
    return Vec3<Var>(Var(0.f, v.x.id), Var(0.f, v.y.id), Var(0.f, v.z.id));
}

// ω + P(ω) Σ c_i V_i and 1 + Σ ⟨b_i, V_i⟩ − 2 ⟨ω, Σ c_i V_i⟩: the field and its surface divergence from the
// per-sample coefficients of an estimator (only derivatives of V_i enter).
WarpEstimate assemble(const Vec3f& omega, std::span<const AuxiliarySample> aux, const std::vector<double>& c,
                      const std::vector<Vec3f>& b) {
    Vec3<Var> field(Var(0.f));
    Var divergence(0.f);
    for (size_t i = 0; i < aux.size(); ++i) {
        if (aux[i].warp.x.is_constant() && aux[i].warp.y.is_constant() && aux[i].warp.z.is_constant())
            continue;
        const Vec3<Var> v = tangent_part(aux[i].warp);
        field += v * Var(float(c[i]));
        divergence += dot(Vec3<Var>(b[i]), v);
    }
    const Var radial = dot(Vec3<Var>(omega), field);
    return {Vec3<Var>(omega) + field - Vec3<Var>(omega) * radial, Var(1.f) + divergence - Var(2.f) * radial};
}

} // namespace

WarpEstimate estimate_warp(const Vec3f& omega, std::span<const AuxiliarySample> aux, const WarpOptions& o) {
    const size_t n = aux.size();
    // Algorithm 2 lines 6–7: w_i and ∂ω w_i, each divided by the vMF density of ω'_i.
    std::vector<double> w(n);
    std::vector<Vec3f> g(n);
    for (size_t i = 0; i < n; ++i) {
        const HarmonicWeight::Value h =
            o.weight(omega, aux[i].vmf.direction, aux[i].vmf.one_minus_cos, aux[i].boundary);
        const double inv_pdf = aux[i].vmf.pdf > 0.f ? 1.0 / double(aux[i].vmf.pdf) : 0.0;
        w[i] = h.w * inv_pdf;
        g[i] = h.gradient * float(inv_pdf);
    }
    std::vector<double> c(n, 0.0);
    std::vector<Vec3f> b(n, Vec3f(0.f));
    if (n == 0) return assemble(omega, aux, c, b);
    // Prefix estimates F_k over batches: Z_k = Σ_{i ≤ end_k} w_i, G_k = Σ ∂ω w_i (lines 10–11). The
    // consistent estimator is the single prefix of all samples with λ = 1.
    const size_t batch = o.unbiased ? size_t(std::max(1, o.rr_batch)) : n;
    const size_t batches = (n + batch - 1) / batch;
    std::vector<double> z(batches), lambda(batches);
    std::vector<Vec3f> gz(batches);
    double zsum = 0.0;
    Vec3f gsum(0.f);
    for (size_t i = 0; i < n; ++i) {
        zsum += w[i];
        gsum += g[i];
        if ((i + 1) % batch == 0 || i + 1 == n) {
            z[i / batch] = zsum;
            gz[i / batch] = gsum;
        }
    }
    // λ_k = 1/q_k − 1/q_{k+1}, λ_N = 1/q_N with q_k = P(N ≥ k) = (1 − p)^{k−1} (Eq. 11 as a weighted sum).
    for (size_t k = 0; k < batches; ++k) {
        const double inv_q = std::pow(1.0 - double(o.rr_stop), -double(k));
        lambda[k] =
            o.unbiased ? (k + 1 < batches ? inv_q * (1.0 - 1.0 / (1.0 - double(o.rr_stop))) : inv_q) : 1.0;
    }
    // Lines 12–13 per prefix, summed over the prefixes that contain sample i (suffix sums over k ≥ batch(i)):
    // c_i = w_i Σ λ_k / Z_k, b_i = ∂ω w_i Σ λ_k / Z_k − w_i Σ λ_k G_k / Z_k².
    double s = 0.0;
    Vec3f r(0.f);
    for (size_t k = batches; k-- > 0;) {
        if (z[k] > 0.0) {
            s += lambda[k] / z[k];
            r += gz[k] * float(lambda[k] / (z[k] * z[k]));
        }
        for (size_t i = k * batch; i < std::min(n, (k + 1) * batch); ++i) {
            c[i] = w[i] * s;
            b[i] = g[i] * float(s) - r * float(w[i]);
        }
    }
    return assemble(omega, aux, c, b);
}

} // namespace penumbra
