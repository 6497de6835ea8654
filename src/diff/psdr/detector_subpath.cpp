#include "diff/psdr/detector_subpath.h"

#include "diff/media_walk.h"
#include "render/adjoint_shading.h"
#include "render/volume_visibility.h"

namespace penumbra {

namespace {

// A vertex of the detector subpath: on a surface (si valid) or in `medium` at p (si.p), wi toward the previous
// vertex (world).
struct DetectorVertex {
    SurfaceInteraction3f si;
    Vec3f wi;
    const Medium* medium = nullptr; // at a medium vertex: its medium; at a surface: the one arrived through
    bool in_medium() const { return !si.is_valid(); }
};

// The ray from p (a surface point with normal n, or a medium point: n = 0) to the camera.
Ray ray_to_camera(const Scene& scene, const Vec3f& p, const Vec3f& n) {
    const Sensor& sensor = *scene.sensor;
    Interaction3f at;
    at.p = p;
    at.n = n;
    return sensor.plugin == "orthographic" ? at.spawn_ray(sensor.to_sensor(p))
                                           : at.spawn_ray_to(sensor.to_world.apply_point(Vec3f(0.f)));
}

// Whether no opaque surface hides the point p (normal n) from the camera (media and null boundaries aside).
bool camera_sees(const Scene& scene, const Vec3f& p, const Vec3f& n, Sampler& sampler, RayCounter& rays) {
    return !is_black(segment_transmittance(scene, ray_to_camera(scene, p, n), nullptr, sampler, rays));
}

// The camera's importance at vertex v in film measure, times the adjoint BSDF (or the phase function) toward
// the camera and the connection's transmittance.
bool connect_to_camera(const Scene& scene, const DetectorVertex& v, CameraConnection& out, Sampler& sampler,
                       RayCounter& rays) {
    const Sensor& sensor = *scene.sensor;
    const Vec3f& p = v.si.p;
    const Vec3f to_cam = sensor.to_sensor(p);
    const Vec3f n = v.in_medium() ? to_cam : v.si.n;
    float jacobian;
    if (!sensor.film_position(p, n, out.s, jacobian)) return false;
    const float r = sensor.film->rfilter->radius(); // border pixels' filters reach r beyond the film
    if (!(out.s.x >= -r && out.s.y >= -r && out.s.x <= sensor.film->width + r && out.s.y <= sensor.film->height + r))
        return false;
    const float cos_cam = std::abs(dot(n, to_cam));
    if (!(cos_cam > 0.f)) return false;
    Color3f f;
    const Medium* medium = v.medium;
    if (v.in_medium()) {
        f = Color3f(v.medium->phase->eval<float>(v.wi, to_cam));
    } else {
        f = v.si.bsdf()->eval(BSDFContext{TransportMode::Importance}, v.si, v.si.to_local(to_cam)) *
            adjoint_shading_correction(v.si, to_cam);
        medium = target_medium(*v.si.shape, v.si.n, to_cam, medium);
    }
    if (is_black(f)) return false;
    const Color3f tr = segment_transmittance(scene, ray_to_camera(scene, p, v.in_medium() ? Vec3f(0.f) : v.si.n),
                                             medium, sampler, rays);
    out.weight = f * tr * (jacobian / cos_cam);
    return !is_black(out.weight);
}

// Whether path vertex k < t of a detector subpath is carried from its predecessor toward the camera (as the
// interior's path walk carries it) rather than being its material point: after a delta lobe there (along the
// lobe's direction), or by the contact flow (MaterialForm::flowed_vertex) off emitters within the contact
// length.
bool follows_flow(const MaterialForm& form, const std::vector<DetectorVertex>& chain,
                  const std::vector<BSDFSample>& lobes, int k) {
    if (lobes[size_t(k + 1)].sampled_type & BSDFDelta) return true;
    const SurfaceInteraction3f& si = chain[size_t(k)].si;
    return !si.shape->emitter && form.contact_weight(norm(si.p - chain[size_t(k + 1)].si.p)) > 0.f;
}

// The receiver x_D0 = chain[0] of a detector subpath (chain[t] seen by the camera; surfaces) under the
// interior's flow, built from the camera side as the interior's path walk builds it: the first path vertex on
// its camera ray (or its material point), each later one carried from its predecessor toward the camera
// (follows_flow) along the predecessor's delta lobe (the detector walk sampled it the other way: the lobe's
// reference directions swap and its relative index inverts) or by the contact flow, else its material point.
SurfaceInteraction<Var> flowed_receiver(const Scene& scene, const MaterialForm& form,
                                        const std::vector<DetectorVertex>& chain,
                                        const std::vector<BSDFSample>& lobes, int t) {
    const SurfaceInteraction3f& seen = chain[size_t(t)].si;
    const Vec3f to_camera = scene.sensor->to_sensor(seen.p);
    SurfaceInteraction<Var> x = form.image_space_first_vertex()
                                    ? form.ray_vertex(seen, Ray(seen.p + to_camera, to_camera * -1.f))
                                    : form.vertex(seen);
    Vec3<Var> beyond(seen.p + to_camera); // the vertex after x toward the camera
    for (int k = t - 1; k >= 0; --k) {
        const SurfaceInteraction3f& si = chain[size_t(k)].si;
        const BSDFSample& sampled = lobes[size_t(k + 1)];
        SurfaceInteraction<Var> y;
        if (!follows_flow(form, chain, lobes, k)) {
            y = form.vertex(si);
        } else if (!(sampled.sampled_type & BSDFDelta)) {
            Var jacobian;
            y = form.flowed_vertex(si, x.p, jacobian);
        } else {
            BSDFSample lobe = sampled;
            lobe.wo = chain[size_t(k + 1)].si.wi;
            lobe.eta = 1.f / sampled.eta;
            x.wi = x.to_local(normalize(beyond - x.p));
            y = form.ray_vertex(si, x.p, x.to_world(delta_direction(x.wi, sampled.wo, lobe)));
        }
        beyond = x.p;
        x = y;
    }
    return x;
}

} // namespace

void detector_connections(const Scene& scene, const MaterialForm& form, const BoundarySegment& segment, int t_min,
                          int t_max, const PathSettings& settings, Sampler& sampler, RayCounter& rays,
                          DetectorConnections& out) {
    const BSDFContext ctx{TransportMode::Importance};
    DetectorVertex v{segment.receiver, segment.direction * -1.f, segment.medium};
    Color3f throughput(1.f);
    // The subpath's vertices and the lobe each sampled (for the receiver's flow).
    thread_local std::vector<DetectorVertex> chain;
    thread_local std::vector<BSDFSample> lobes;
    chain.clear();
    lobes.clear();
    const auto velocity = [&](int t) {
        if (t == 0 || segment.in_medium || !follows_flow(form, chain, lobes, 0))
            return segment.velocity_at_depth(t);
        for (int k = 1; k <= t; ++k) // a medium vertex toward the camera: its material point (docs/design.md)
            if (chain[size_t(k)].in_medium()) return segment.velocity_at_depth(t);
        return segment.velocity_relative_to(form, flowed_receiver(scene, form, chain, lobes, t).p);
    };
    for (int t = 0; t_max < 0 || t <= t_max; ++t) {
        chain.push_back(v);
        lobes.push_back(BSDFSample{});
        const BSDF* bsdf = v.si.bsdf();
        if (!v.in_medium() && !bsdf) return;
        if (t >= t_min && (v.in_medium() || bsdf->has(BSDFSmooth))) {
            CameraConnection c;
            if (connect_to_camera(scene, v, c, sampler, rays) &&
                (t > 0 ||
                 (!segment.contact && camera_sees(scene, segment.dark_point,
                                                  v.in_medium() ? Vec3f(0.f) : v.si.n, sampler, rays)))) {
                c.weight *= throughput;
                c.t = t;
                c.velocity = velocity(t);
                out.items[out.count++] = c;
                if (out.count == DetectorConnections::Capacity) return;
            }
        }
        if (t == t_max) return;
        // The next direction: phase sampling (weight 1) or adjoint BSDF sampling.
        Vec3f d;
        Ray ray;
        const Medium* medium = v.medium;
        if (v.in_medium()) {
            const auto [wo, pdf] = v.medium->phase->sample(v.wi, sampler.next_2d());
            if (!(pdf > 0.f)) return;
            d = wo;
            ray = Ray(v.si.p, d);
        } else {
            const float u1 = sampler.next_1d();
            const auto [bs, weight] = bsdf->sample(ctx, v.si, u1, sampler.next_2d());
            if (is_black(weight)) return;
            d = v.si.to_world(bs.wo);
            lobes.back() = bs;
            throughput *= weight * adjoint_shading_correction(v.si, d);
            medium = target_medium(*v.si.shape, v.si.n, d, medium);
            ray = v.si.spawn_ray(d);
        }
        const FlightEnd end = sample_interaction(scene, ray, medium, true, sampler, rays);
        if (end.kind == FlightEnd::Kind::None || end.kind == FlightEnd::Kind::Escaped) return;
        throughput *= end.weight;
        if (t == 0 && end.kind == FlightEnd::Kind::Surface) {
            throughput *= segment.first_segment_geometry_ratio(end.si);
            if (is_black(throughput)) return;
        }
        v.si = end.kind == FlightEnd::Kind::Surface ? end.si : SurfaceInteraction3f{};
        if (end.kind == FlightEnd::Kind::Medium) v.si.p = end.p;
        else v.si.wi = v.si.to_local(d * -1.f);
        v.wi = d * -1.f;
        v.medium = end.medium;
        if (t + 1 >= settings.rr_depth) {
            const float q = std::min(max_component(throughput), 0.95f);
            if (sampler.next_1d() >= q) return;
            throughput /= q;
        }
    }
}

} // namespace penumbra
