#include "diff/psdr/bdpt_interior.h"

#include "diff/path_measurement.h"
#include "render/bdpt_sample.h"

namespace penumbra {

namespace {

// z_1 on the geometry with its camera factor (diff/psdr/interior_media.h's rule): image space, on the fixed camera
// ray (a medium vertex keeps its fraction of the ray's piece between the moving surfaces around it, with the
// Jacobian of that stretch); material form, X(p1, θ) with W/p = camera(x1, n, J).
MeasuredVertex<Var> first_vertex(const MaterialForm& form, const PathVertex& v, const LegChain& chain,
                                 const Ray& ray, const Vec3<Var>& o, const CameraFactor& camera,
                                 float escaped_weight, Var& factor) {
    const bool image = form.image_space_first_vertex();
    MeasuredVertex<Var> x;
    x.ref = &v;
    factor = Var(1.f);
    if (v.infinite) {
        if (!image) factor = Var(escaped_weight);
        return escaped_vertex(v, o, ray.d);
    }
    if (!image) {
        x = measured_vertex<Var>(v, form);
        factor = camera(x.p, x.surface ? x.si.n : normalize(o - x.p), x.jacobian);
        x.jacobian = Var(1.f);
        return x;
    }
    if (v.type == VertexType::Surface) {
        Ray camera_ray = ray;
        camera_ray.tmax = Infinity;
        x.si = form.ray_vertex(v.si, camera_ray);
        x.p = x.si.p;
        x.surface = true;
        return x;
    }
    const LegPiece& piece = chain.pieces[size_t(chain.count - 1)];
    const Vec3<Var> far = o + Vec3<Var>(ray.d);
    const Vec3<Var> start =
        chain.count > 1 ? crossing_point(form, chain.pieces[size_t(chain.count - 2)].bound, o, far) : o;
    const float distance = dot(v.p - ray.o, ray.d) / squared_norm(ray.d);
    if (piece.bound.is_valid()) {
        const float length0 = piece.bound.t, s = (distance - piece.start) / length0;
        const Vec3<Var> stop = crossing_point(form, piece.bound, o, far);
        x.p = start + (stop - start) * Var(s);
        factor = norm(stop - start) / Var(length0 * norm(ray.d));
    } else {
        x.p = start + Vec3<Var>(ray.d) * Var(distance - piece.start);
    }
    return x;
}

// Why the bidirectional estimator cannot differentiate the scene (empty: it can).
std::string unsupported(const Scene& scene) {
    for (const auto& e : scene.emitters)
        if (e->is_infinite()) return "light subpaths of infinite lights are not differentiated";
    return "";
}

} // namespace

InteriorEstimator parse_interior_estimator(const std::string& name) {
    if (name == "auto") return InteriorEstimator::Auto;
    if (name == "unidirectional") return InteriorEstimator::Unidirectional;
    if (name == "bidirectional") return InteriorEstimator::Bidirectional;
    throw Error("interior estimator must be unidirectional, bidirectional or auto, got '" + name + "'");
}

bool bidirectional_interior(const Scene& scene, InteriorEstimator estimator) {
    if (estimator == InteriorEstimator::Auto)
        return scene_integrator_is_bdpt(scene) &&
               unsupported(scene).empty();
    return estimator == InteriorEstimator::Bidirectional;
}

void require_bidirectional_support(const Scene& scene) {
    const std::string why = unsupported(scene);
    if (!why.empty())
        throw Error("the bidirectional interior estimator cannot differentiate this scene (" + why +
                    "): use --interior-estimator unidirectional");
}

BDPTPass bidirectional_pass(const Scene& scene, const PathSettings& path) {
    return BDPTPass(scene, bdpt_settings(scene, path), false);
}

// Σ_{s, t>=2} C_{s,t} f(x̄; θ) / f(x̄; θ0) times the camera factor (paper 001 §7 with §5.1's first vertex).
Color3<Var> bidirectional_camera_path(const BDPTPass& pass, const MaterialForm& form, Sampler& sampler,
                                      const Ray& ray, const Color3f& ray_weight, const CameraFactor& camera,
                                      float escaped_weight, HorizonRule* horizon, RayCounter& rays) {
    thread_local BDPTSample sample;
    thread_local std::vector<MeasuredVertex<Var>> z, y;
    thread_local std::vector<Color3<Var>> camera_factors, light_factors;
    sample.trace_recorded(pass, sampler, rays, ray);
    const std::vector<PathVertex>& camera_path = sample.camera;
    const BDPTRecord& record = sample.record;
    if (camera_path.size() < 2 || record.count == 0) return Color3<Var>(Var(0.f));

    // The camera subpath on the geometry.
    const bool image = form.image_space_first_vertex();
    const Vec3<Var> o = image ? Vec3<Var>(ray.o) : form.camera_position(ray.o);
    Var camera_factor;
    z.assign(1, MeasuredVertex<Var>());
    z.push_back(
        first_vertex(form, camera_path[1], record.camera[1], ray, o, camera, escaped_weight, camera_factor));
    for (size_t k = 2; k < camera_path.size(); ++k) {
        const PathVertex& v = camera_path[k];
        if (camera_path[k - 1].delta)
            z.push_back(steered_vertex(v, z[k - 1], k == 2 ? o : z[k - 2].p, form));
        else if (v.infinite)
            z.push_back(escaped_vertex(v, z.back().p, v.d_env));
        else
            z.push_back(measured_vertex<Var>(v, form));
    }
    camera_prefix(z, o, record, form, camera_factors);

    // The light subpath on the geometry.
    y.clear();
    for (size_t j = 0; j < sample.light.size(); ++j) {
        const PathVertex& v = sample.light[j];
        y.push_back(j >= 2 && sample.light[j - 1].delta ? steered_vertex(v, y[j - 1], y[j - 2].p, form)
                                                        : measured_vertex<Var>(v, form));
    }
    light_prefix(y, record, form, light_factors);

    Color3<Var> L = reweighted_strategies(record, [&](const StrategyRecord& st) {
        return path_measurement(st, z, y, camera_factors, light_factors, o, pass.scene, form);
    });
    // The shading horizons at the camera subpath's vertices, with the subpath's throughput (value 0).
    for (size_t k = 1; horizon && k < camera_path.size(); ++k) {
        const PathVertex& v = camera_path[k];
        const BSDF* bsdf = v.type == VertexType::Surface && z[k].surface ? v.si.bsdf() : nullptr;
        if (!bsdf || !bsdf->has(BSDFSmooth)) continue;
        if (const auto term = horizon->attached_boundary(*bsdf, v.si, z[k].si, unsigned(k - 1), rays))
            L += Color3<Var>(v.beta) * *term;
    }
    return L * Color3<Var>(ray_weight) * camera_factor;
}

} // namespace penumbra
