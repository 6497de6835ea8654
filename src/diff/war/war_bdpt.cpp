#include "diff/war/war_bdpt.h"

#include "diff/film_sample.h"
#include "diff/path_measurement.h"
#include "render/bdpt_sample.h"
#include "scene/integrator_settings.h"

#include <algorithm>

namespace penumbra {

namespace {

// What the estimator of one scene shares across samples.
struct Context {
    const Scene& scene;
    const Parameters& params;
    MaterialForm form;
    BoundaryTest boundary;
    WarScene field;
    // No sensor connection: light tracing (t = 1) is neither sampled nor counted in the MIS weights.
    BDPTPass bdpt;

    Context(const Scene& s, const Parameters& p, const WarOptions& o)
        : scene(s), params(p), form(s, p, FirstVertex::Material),
          boundary(s), field{s, p, form, boundary, o.field}, bdpt(s, bdpt_settings(s, o.path), false) {}
};

// The subpath vertex v on the geometry, a surface vertex warped conditioned on its detector-side neighbour y
// (a vertex after a delta lobe is not warped: diff/path_measurement.h steered_vertex); `material` gets X(p,
// θ) without the warp.
MeasuredVertex<Var> warped_vertex(const Context& c, const PathVertex& v, const WarNeighbor& y,
                                  AuxiliaryRng& rng, uint64_t& rays, Vec3<Var>* material = nullptr) {
    const bool surface = v.type == VertexType::Surface || (v.type == VertexType::Light && v.emitter->shape());
    if (!surface) {
        const MeasuredVertex<Var> m = measured_vertex<Var>(v, c.form);
        if (material) *material = m.p;
        return m;
    }
    const WarVertex w = war_vertex(c.field, v.si, y, rng, rays);
    MeasuredVertex<Var> m;
    m.ref = &v;
    m.si = w.si;
    m.p = w.si.p;
    m.jacobian = w.jacobian;
    m.surface = true;
    if (material) *material = w.material;
    return m;
}

// The light subpath's factor up to its connection vertex e = y_{s−1} (warped on the camera side), from the
// prefix up to y_{s−2}: light_prefix's step (diff/path_measurement.h) with e in place of y_{s−1}.
Color3<Var> light_head(const Context& c, const BDPTRecord& record, const std::vector<MeasuredVertex<Var>>& y,
                       const std::vector<Color3<Var>>& prefix, const MeasuredVertex<Var>& e, size_t k) {
    Color3<Var> f = measured_flight(record.light[k], y[k - 1], e, c.form);
    if (k == 1) return f * measured_emission(y[0], e, c.form) * e.jacobian;
    f *= prefix[k - 1] * measured_scattering(y[k - 1], e.p, normalize(y[k - 2].p - y[k - 1].p));
    return y[k - 1].ref->delta ? f : f * measured_geometry(e, y[k - 1]) * e.jacobian;
}

// Next-event estimation's light point (s = 1) warped conditioned on z_{t−1}: f̂ of the strategy up to
// constants.
Color3<Var> area_light_connection(const Context& c, const StrategyRecord& st, const MeasuredVertex<Var>& zt,
                                  const Vec3<Var>& camera_side, const Color3<Var>& head,
                                  const WarNeighbor& here, AuxiliaryRng& rng, uint64_t& rays) {
    const DirectionSample3f& ds = st.light_sample;
    const Shape& shape = *ds.emitter->shape();
    const SurfaceInteraction3f light =
        surface_interaction<float>(shape, ds.prim, ds.bary, MeshVertices{shape.mesh});
    WarVertex y = war_vertex(c.field, light, here, rng, rays);
    const Vec3<Var> to_light = y.si.p - zt.p;
    const Var dist2 = squared_norm(to_light);
    const Vec3<Var> wo = to_light / sqrt(dist2);
    y.si.wi = y.si.to_local(-wo);
    const Var g = abs(dot(y.si.n, wo)) / dist2;
    return head * measured_scattering(zt, camera_side, wo) * ds.emitter->eval(y.si) * (g * y.jacobian) *
           chain_weight(st.connection, zt.p, y.si.p, false, false, false, c.form);
}

// A camera sample's film point: pixel, filter sample and ray.
struct Shot {
    int px, py;
    FilmSample fs;
    Ray ray;
};

// War's camera factor of the warped first vertex x1 (diff/war/war.h): P_j(s(x1(θ))) |ds/dA|(θ) J (1 + ∇·v) /
// (p_s |ds/dA|(θ0)); false when x1 leaves the film's projection.
bool camera_factor(const Context& c, const Shot& shot, const MeasuredVertex<Var>& x1, Var& factor) {
    const Sensor& sensor = *c.scene.sensor;
    const Vec3<Var> p_cam = c.form.to_reference_camera(x1.si.p, shot.ray.o);
    const Vec3<Var> n_cam = c.form.direction_to_reference_camera(x1.si.n);
    Vec2<Var> s;
    Var jacobian;
    if (!sensor.film_position(p_cam, n_cam, s, jacobian)) return false;
    factor = sensor.film->filter_weight(shot.px, shot.py, s) * relative_change(jacobian * x1.jacobian) /
             Var(shot.fs.pdf);
    return true;
}

// Σ_{s, t≥2} C_{s,t} f̂(p̄; θ) / f̂(p̄; θ0) times z_1's camera factor: one camera sample (Eq. 54).
Color3<Var> camera_sample(const Context& c, Sampler& sampler, AuxiliaryRng& rng, int px, int py,
                          RayCounter& rays) {
    thread_local BDPTSample sample;
    thread_local std::vector<MeasuredVertex<Var>> z, y, ys;
    thread_local std::vector<Vec3<Var>> z_material;
    thread_local std::vector<Color3<Var>> camera_factors, light_factors, heads;
    const Sensor& sensor = *c.scene.sensor;
    const Film& film = *sensor.film;
    const FilmSample fs = sample_film(*film.rfilter, sampler, false);
    const Vec2f center(px + 0.5f, py + 0.5f);
    // The ray's weight is 1 for the sensors war accepts (one center of projection): the camera factor
    // carries W/p.
    const Shot shot{px, py, fs, sensor.sample_ray(center + fs.offset, sampler.next_2d()).first};
    sample.trace_recorded(c.bdpt, sampler, rays, shot.ray);
    ++rays.rays;
    const std::vector<PathVertex>&camera_path = sample.camera, &light_path = sample.light;
    const BDPTRecord& record = sample.record;
    if (camera_path.size() < 2 || camera_path[1].infinite || record.count == 0) return Color3<Var>(Var(0.f));
    size_t s_max = 0;
    for (int k = 0; k < record.count; ++k)
        if (!is_black(record.strategies[size_t(k)].value))
            s_max = std::max(s_max, size_t(record.strategies[size_t(k)].s));

    // The camera subpath, each vertex warped given the previous one (z_1 given the camera).
    const Vec3<Var> o = c.form.camera_position(shot.ray.o);
    const WarNeighbor camera{Interaction3f{Infinity, shot.ray.o, Vec3f(0.f)}, o};
    z.assign(2, MeasuredVertex<Var>());
    z_material.assign(2, o);
    z[1] = warped_vertex(c, camera_path[1], camera, rng, rays.rays, &z_material[1]);
    Var factor;
    if (!camera_factor(c, shot, z[1], factor)) return Color3<Var>(Var(0.f));
    z[1].jacobian = Var(1.f); // in the camera factor
    for (size_t k = 2; k < camera_path.size(); ++k) {
        const PathVertex& v = camera_path[k];
        z_material.push_back(Vec3<Var>());
        if (camera_path[k - 1].delta) { // no warp after a delta lobe: its direction turns with the geometry
            z.push_back(steered_vertex(v, z[k - 1], k == 2 ? o : z[k - 2].p, c.form));
            z_material.back() = z.back().p;
            continue;
        }
        if (v.infinite) {
            z.push_back(escaped_vertex(v, z.back().p, v.d_env));
            continue;
        }
        const WarNeighbor previous{camera_path[k - 1].si, z_material[k - 1]};
        z.push_back(warped_vertex(c, v, previous, rng, rays.rays, &z_material[k]));
    }
    camera_prefix(z, o, record, c.form, camera_factors);

    // The light subpath's vertices y_0 … y_{s_max−2}, each warped given the next one and shared by every
    // connection beyond it.
    y.clear();
    for (size_t j = 0; j + 2 <= s_max; ++j) {
        const WarNeighbor toward{light_path[j + 1].si, c.form.vertex(light_path[j + 1].si).p};
        y.push_back(j >= 2 && light_path[j - 1].delta
                        ? steered_vertex(light_path[j], y[j - 1], y[j - 2].p, c.form)
                        : warped_vertex(c, light_path[j], toward, rng, rays.rays));
    }
    light_prefix(y, record, c.form, light_factors);

    const Color3<Var> L = reweighted_strategies(record, [&](const StrategyRecord& st) {
        const size_t t = size_t(st.t), s = size_t(st.s);
        const WarNeighbor here{camera_path[t - 1].si, z_material[t - 1]};
        if (s == 1 && st.light_sample.emitter->shape()) {
            const Vec3<Var> camera_side = t == 2 ? o : z[t - 2].p;
            return area_light_connection(c, st, z[t - 1], camera_side, camera_factors[t - 1], here, rng,
                                         rays.rays);
        }
        if (s < 2) return path_measurement(st, z, y, camera_factors, light_factors, o, c.scene, c.form);
        // y_{s−1} warped given z_{t−1} in place of its warp given y_s.
        ys.assign(y.begin(), y.begin() + std::ptrdiff_t(s - 1));
        ys.push_back(s >= 3 && light_path[s - 2].delta
                         ? steered_vertex(light_path[s - 1], y[s - 2], y[s - 3].p, c.form)
                         : warped_vertex(c, light_path[s - 1], here, rng, rays.rays));
        heads.assign(light_factors.begin(), light_factors.begin() + std::ptrdiff_t(s - 1));
        heads.push_back(light_head(c, record, ys, light_factors, ys.back(), s - 1));
        return path_measurement(st, z, ys, camera_factors, heads, o, c.scene, c.form);
    });
    return L * factor;
}

} // namespace

void require_war_bdpt_support(const Scene& scene, const Parameters& params) {
    require_war_support(scene, params);
    for (const auto& e : scene.emitters)
        if (e->is_infinite())
            throw Error(
                "method war-bdpt does not differentiate light subpaths of infinite lights (environment, sky, "
                "directional): use method war");
}

DerivativeImage war_bdpt_derivative(const Scene& scene, const Parameters& params, const WarOptions& options) {
    require_war_bdpt_support(scene, params);
    return pixel_derivative(war_loop<Context>(scene, params, options, "war-bdpt", camera_sample));
}

Gradient war_bdpt_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                           const WarOptions& options) {
    require_war_bdpt_support(scene, params);
    return pixel_gradient(war_loop<Context>(scene, params, options, "war-bdpt", camera_sample), adjoint);
}

} // namespace penumbra
