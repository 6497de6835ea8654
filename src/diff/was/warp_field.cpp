#include "diff/was/warp_field.h"

#include <cmath>

namespace penumbra {

namespace {

// A tape value with value 0 and the same derivative: V_direct without its value (the estimate needs only ∂θ).
Var tangent_part(const Var& v) { return Var(0.f, v.id); }
Vec3<Var> tangent_part(const Vec3<Var>& v) {
    return {tangent_part(v.x), tangent_part(v.y), tangent_part(v.z)};
}

} // namespace

WarpCoefficients warp_coefficients(std::span<const double> w, std::span<const Vec3f> g,
                                   const WarpOptions& o) {
    const size_t n = w.size();
    WarpCoefficients out{std::vector<double>(n, 0.0), std::vector<Vec3f>(n, Vec3f(0.f))};
    if (n == 0) return out;
    // Prefix sums at the end of each batch: Z_k = Σ w_i, G_k = Σ ∂w_i (lines 10–11). The consistent estimator
    // is the single prefix of all samples with λ = 1.
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
    const double keep = 1.0 - double(o.rr_stop);
    for (size_t k = 0; k < batches; ++k) {
        const double inv_q = std::pow(keep, -double(k));
        lambda[k] = o.unbiased ? (k + 1 < batches ? inv_q * (1.0 - 1.0 / keep) : inv_q) : 1.0;
    }
    // Lines 12–13 per prefix, summed over the prefixes that contain sample i (suffix sums over k ≥ batch(i)):
    // field_i = w_i Σ λ_k / Z_k, divergence_i = ∂w_i Σ λ_k / Z_k − w_i Σ λ_k G_k / Z_k².
    double s = 0.0;
    Vec3f r(0.f);
    for (size_t k = batches; k-- > 0;) {
        if (z[k] > 0.0) {
            s += lambda[k] / z[k];
            r += gz[k] * float(lambda[k] / (z[k] * z[k]));
        }
        for (size_t i = k * batch; i < std::min(n, (k + 1) * batch); ++i) {
            out.field[i] = w[i] * s;
            out.divergence[i] = g[i] * float(s) - r * float(w[i]);
        }
    }
    return out;
}

WarpCoefficients jackknife_coefficients(std::span<const double> w, std::span<const Vec3f> g, size_t group) {
    const size_t n = w.size(), groups = n / std::max<size_t>(1, group);
    WarpCoefficients out{std::vector<double>(n, 0.0), std::vector<Vec3f>(n, Vec3f(0.f))};
    if (groups < 2 || groups * group != n) return out;
    double z = 0.0;
    Vec3f gz(0.f);
    for (size_t i = 0; i < n; ++i) {
        z += w[i];
        gz += g[i];
    }
    if (!(z > 0.0)) return out;
    // Per group k: Z_(−k), G_(−k); S = Σ_k 1/Z_(−k), T = Σ_k G_(−k)/Z_(−k)².
    std::vector<double> zk(groups);
    std::vector<Vec3f> gk(groups);
    double S = 0.0;
    Vec3f T(0.f);
    for (size_t k = 0; k < groups; ++k) {
        double wk = 0.0;
        Vec3f g_k(0.f);
        for (size_t i = k * group; i < (k + 1) * group; ++i) {
            wk += w[i];
            g_k += g[i];
        }
        zk[k] = z - wk;
        gk[k] = gz - g_k;
        if (zk[k] > 0.0) {
            S += 1.0 / zk[k];
            T += gk[k] * float(1.0 / (zk[k] * zk[k]));
        }
    }
    // Σ over the leave-one-out estimates that contain sample i (all but its own group's), then
    // J = G F_N − (G − 1)/G Σ_k F_(−k) per coefficient.
    const double G = double(groups), shrink = (G - 1.0) / G;
    for (size_t i = 0; i < n; ++i) {
        const size_t k = i / group;
        const double s_i = S - (zk[k] > 0.0 ? 1.0 / zk[k] : 0.0);
        const Vec3f t_i = T - (zk[k] > 0.0 ? gk[k] * float(1.0 / (zk[k] * zk[k])) : Vec3f(0.f));
        out.field[i] = G * w[i] / z - shrink * w[i] * s_i;
        out.divergence[i] = (g[i] * float(1.0 / z) - gz * float(w[i] / (z * z))) * float(G) -
                            (g[i] * float(s_i) - t_i * float(w[i])) * float(shrink);
    }
    return out;
}

namespace {

// The warp's coefficients: for the consistent estimator with `jackknife`, the delete-a-group jackknife of the
// ratio (antithetic pairs as groups); otherwise warp_coefficients (the plain ratio, or the unbiased
// telescoping sum).
WarpCoefficients ratio_coefficients(std::span<const double> w, std::span<const Vec3f> g, const WarpOptions& o,
                                    bool jackknife) {
    return o.unbiased || !jackknife ? warp_coefficients(w, g, o)
                                    : jackknife_coefficients(w, g, o.antithetic ? 2 : 1);
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
    const WarpCoefficients c = ratio_coefficients(w, g, o, o.sphere_jackknife);
    // ω + P(ω) V and 1 + Σ ⟨b_i, V_i⟩ − 2 ⟨ω, V⟩ (the surface divergence of the projected field).
    Vec3<Var> field(Var(0.f));
    Var divergence(0.f);
    for (size_t i = 0; i < n; ++i) {
        const Vec3<Var>& warp = aux[i].warp;
        if (warp.x.is_constant() && warp.y.is_constant() && warp.z.is_constant()) continue;
        const Vec3<Var> v = tangent_part(warp);
        field += v * Var(float(c.field[i]));
        divergence += dot(Vec3<Var>(c.divergence[i]), v);
    }
    const Var radial = dot(Vec3<Var>(omega), field);
    return {Vec3<Var>(omega) + field - Vec3<Var>(omega) * radial, Var(1.f) + divergence - Var(2.f) * radial};
}

PixelWarpEstimate estimate_pixel_warp(const Vec2f& x, std::span<const PixelAuxiliarySample> aux, float sigma,
                                      const WarpOptions& o) {
    const size_t n = aux.size();
    std::vector<double> w(n);
    std::vector<Vec3f> g(n);
    for (size_t i = 0; i < n; ++i) {
        const HarmonicWeight::Value h = o.weight.planar(aux[i].offset, sigma, aux[i].boundary);
        const double inv_pdf = aux[i].pdf > 0.f ? 1.0 / double(aux[i].pdf) : 0.0;
        w[i] = h.w * inv_pdf;
        g[i] = h.gradient * float(inv_pdf);
    }
    const WarpCoefficients c = ratio_coefficients(w, g, o, o.film_jackknife);
    Var vx(0.f), vy(0.f), divergence(0.f);
    for (size_t i = 0; i < n; ++i) {
        if (aux[i].warp.x.is_constant() && aux[i].warp.y.is_constant()) continue;
        const Var tx = tangent_part(aux[i].warp.x), ty = tangent_part(aux[i].warp.y);
        vx += tx * Var(float(c.field[i]));
        vy += ty * Var(float(c.field[i]));
        divergence += tx * Var(c.divergence[i].x) + ty * Var(c.divergence[i].y);
    }
    return {Vec2<Var>(Var(x.x) + vx, Var(x.y) + vy), Var(1.f) + divergence};
}

} // namespace penumbra
