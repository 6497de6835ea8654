// Density estimation at a visible point: the photons of one pass within radius r, weighted by the kernel
// (the photon-mapping radiance estimate, with the kernel of render/photon_kernel.h).
#pragma once
#include "render/photon_kernel.h"
#include "render/photon_map.h"
#include "render/visible_point.h"
#include "scene/bsdf.h"
#include "scene/phase.h"

#include <cmath>

namespace penumbra {

struct PhotonGather {
    // M = Σ K(d_p / r): the kernel-weighted number of photons (their number with the constant kernel).
    float count = 0.f;
    // Φ = Σ K(d_p / r) β_eye f(x, ω_eye, ω_p) / |cos_g| Φ_p.
    Color3f flux{0.f};
};

// Photons are merged with the visible point when the full path fits in max_depth (eye + photon segments)
// and they lie on a surface facing the same way (normals within 60°: no flux from a wall's other side or
// the other face of a corner). Calls visit(photon, K(d / r), f / |cos_g|) for each: BSDF::eval() returns
// f |cos θ| in the shading frame, while the photons' density is per unit of geometric area (the
// shading-normal correction of adjoint transport).
template <typename Visit>
void for_each_merged_photon(const PhotonMap& map, const VisiblePoint& vp, float radius, PhotonKernel kernel,
                            int max_depth, Visit&& visit) {
    const BSDF* bsdf = vp.si.bsdf();
    const BSDFContext ctx{TransportMode::Radiance};
    const float inv_radius = 1.f / radius;
    map.for_each_within(vp.si.p, radius, [&](const Photon& ph, float d2) {
        if (max_depth >= 0 && vp.depth + int(ph.depth) > max_depth) return;
        if (dot(ph.n, vp.si.n) < 0.5f) return;
        const float cos_g = std::abs(dot(vp.si.n, ph.wi));
        if (!(cos_g > 0.f)) return;
        const float k = photon_kernel(kernel, std::sqrt(d2) * inv_radius);
        if (!(k > 0.f)) return;
        visit(ph, k, bsdf->eval(ctx, vp.si, vp.si.to_local(ph.wi)) / cos_g);
    });
}

inline PhotonGather gather_photons(const PhotonMap& map, const VisiblePoint& vp, float radius,
                                   PhotonKernel kernel, int max_depth) {
    PhotonGather g;
    for_each_merged_photon(map, vp, radius, kernel, max_depth, [&](const Photon& ph, float k, const Color3f& f) {
        g.count += k;
        g.flux += f * ph.flux * k;
    });
    g.flux *= vp.beta;
    return g;
}

// Density estimation at a visible point in a medium: the volume photons within radius r (normalized over the
// ball: Σ K Φ_p p(ω_eye, ω_p) / (4/3 π r³) estimates σ_s ∫ p L_i), with the medium's phase function.
inline PhotonGather gather_volume_photons(const PhotonMap& map, const VisiblePoint& vp, float radius,
                                          PhotonKernel kernel, int max_depth) {
    PhotonGather g;
    const PhaseFunction& phase = *vp.medium->phase;
    const float inv_radius = 1.f / radius;
    map.for_each_within(vp.p, radius, [&](const Photon& ph, float d2) {
        if (max_depth >= 0 && vp.depth + int(ph.depth) > max_depth) return;
        const float k = volume_photon_kernel(kernel, std::sqrt(d2) * inv_radius);
        if (!(k > 0.f)) return;
        g.count += k;
        g.flux += ph.flux * (k * phase.eval(vp.wi, ph.wi));
    });
    g.flux *= vp.beta;
    return g;
}

} // namespace penumbra
