#include "diff/dpm/photon_path.h"

#include "diff/material_form.h"
#include "render/adjoint_shading.h"
#include "scene/bsdf.h"
#include "scene/shape.h"

namespace penumbra {

namespace {

// Multiplies `ratio` by f(θ) / f(θ0) channel by channel (a channel that is 0 at θ0 carries no value to scale).
// False when f is black at θ0.
bool scale_by(Color3<Var>& ratio, const Color3<Var>& f) {
    bool any = false;
    for (int c = 0; c < 3; ++c) {
        const float f0 = f[c].v;
        if (!(f0 != 0.f) || !std::isfinite(f0)) continue;
        ratio[c] = ratio[c] * (f[c] * Var(1.f / f0));
        any = true;
    }
    return any;
}

bool scale_by(Color3<Var>& ratio, const Var& f) { return scale_by(ratio, Color3<Var>(f, f, f)); }

} // namespace

bool photon_path_value(const Parameters& params, const PhotonPath& path, PhotonPathEpsm epsm,
                       PhotonPathValue& out) {
    const std::vector<SpecularVertex>& chain = *path.eye_chain;
    const std::vector<PathVertex>& light = *path.light;
    const int j = path.photon;
    // Indices: 0 the camera, 1 ... e - 1 the specular chain, e = s the visible point, e + 1 the photon, then
    // the light subpath backwards to the emitter at L.
    const int e = int(chain.size()) + 1, L = e + 1 + j;
    const auto light_index = [&](int m) { return e + 1 + (j - m); }; // light subpath vertex y_m

    std::vector<EpsmVertex> vertices;
    vertices.reserve(size_t(L + 1));
    vertices.push_back(EpsmVertex::camera(path.camera));
    for (const SpecularVertex& v : chain)
        vertices.push_back(EpsmVertex::surface(v.si));
    vertices.push_back(EpsmVertex::surface(*path.visible));
    for (int m = j; m >= 1; --m)
        vertices.push_back(EpsmVertex::surface(light[size_t(m)].si));
    const PathVertex& y0 = light[0];
    const bool area_light = y0.emitter->shape() != nullptr;
    if (area_light)
        vertices.push_back(EpsmVertex::surface(y0.si));
    else
        vertices.push_back(EpsmVertex::point(y0.p, y0.infinite ? nullptr : y0.emitter));

    // Eye subpath (Fig. 5): what fixes x_s, then a half vector at each specular vertex x_2 ... x_{s-1}.
    std::vector<EpsmConstraint> constraints;
    switch (epsm) {
    case PhotonPathEpsm::FixedEyeRay: constraints.push_back(EpsmConstraint::fixed_direction(0, 1)); break;
    case PhotonPathEpsm::FixedDensity: constraints.push_back(EpsmConstraint::fixed_position(e)); break;
    case PhotonPathEpsm::VertexMerge: constraints.push_back(EpsmConstraint::vertex_merge(e, e + 1)); break;
    }
    for (int i = 1; i < e; ++i)
        constraints.push_back(EpsmConstraint::half_vector(i, i - 1, i + 1, chain[size_t(i - 1)].eta));
    // Light subpath: the emitter's position and emitted direction, then each middle vertex's outgoing ray.
    if (area_light) constraints.push_back(EpsmConstraint::fixed_position(L));
    constraints.push_back(EpsmConstraint::fixed_direction(L, L - 1));
    for (int m = 1; m < j; ++m) {
        const int i = light_index(m);
        constraints.push_back(light[size_t(m)].delta
                                  ? EpsmConstraint::half_vector(i, i + 1, i - 1, light[size_t(m)].eta)
                                  : EpsmConstraint::fixed_direction(i, i - 1));
    }

    EpsmPath x;
    if (!solve_epsm(params, vertices, constraints, x)) return false;
    const auto dir = [&](int from, int to) { return normalize(x.x[size_t(to)] - x.x[size_t(from)]); };
    Color3<Var> ratio(Var(1.f));

    // Eye subpath: the smooth factor g of each specular vertex (Eq. 16–18).
    const BSDFContext radiance{TransportMode::Radiance}, importance{TransportMode::Importance};
    for (int i = 1; i < e; ++i) {
        SurfaceInteraction<Var>& si = x.si[size_t(i)];
        si.wi = si.to_local(dir(i, i - 1));
        if (!scale_by(ratio, si.bsdf()->delta_weight(radiance, si, si.to_local(dir(i, i + 1))))) return false;
    }
    // Vertex merging (Eq. 23): ρ_s between the eye and the photon's incident direction, f / |cos_g| as the
    // density estimate has it, and the kernel K_r(|x_s − x*_s|).
    {
        SurfaceInteraction<Var>& si = x.si[size_t(e)];
        si.wi = si.to_local(dir(e, e - 1));
        const Vec3<Var> wp = dir(e + 1, e + 2);
        if (!scale_by(ratio, si.bsdf()->eval(radiance, si, si.to_local(wp)) / abs(dot(si.n, wp)))) return false;
        const Var t = norm(x.x[size_t(e)] - x.x[size_t(e + 1)]) * Var(1.f / path.radius);
        if (!scale_by(ratio, photon_kernel(path.kernel, t))) return false;
    }
    // Light subpath: the middle vertices' BSDFs with adjoint transport's shading-normal correction, and the
    // emission.
    for (int m = 1; m < j; ++m) {
        const int i = light_index(m);
        SurfaceInteraction<Var>& si = x.si[size_t(i)];
        si.wi = si.to_local(dir(i, i + 1));
        const Vec3<Var> next = dir(i, i - 1), wo = si.to_local(next);
        const BSDF* bsdf = si.bsdf();
        if (!scale_by(ratio, light[size_t(m)].delta ? bsdf->delta_weight(importance, si, wo)
                                                    : bsdf->eval(importance, si, wo)))
            return false;
        if (!scale_by(ratio, adjoint_shading_correction(si, next))) return false;
    }
    const Emitter& emitter = *y0.emitter;
    Color3<Var> emitted;
    if (area_light) {
        SurfaceInteraction<Var>& si = x.si[size_t(L)];
        si.wi = si.to_local(dir(L, L - 1));
        emitted = emitter.eval(si);
    } else if (y0.infinite) {
        emitted = emitter.is_delta() ? emitter.eval_delta(Vec3<Var>(light[1].p))
                                     : emitter.eval_environment(Vec3<Var>(y0.d_env));
    } else {
        // A point-like light emits along a direction fixed in the world (its translations keep it); its
        // rotations turn that direction in its own frame, where its intensity is defined.
        emitted = emitter.eval_delta(to_reference_light(params, emitter, x.x[size_t(L)] + Vec3<Var>(light[1].p - y0.p)));
    }
    if (!scale_by(ratio, emitted)) return false;
    out.ratio = ratio;
    out.first = x.x[1];
    return true;
}

} // namespace penumbra
