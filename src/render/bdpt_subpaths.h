// The two random walks of bidirectional path tracing (Veach 1997, §10.2) and the vertex densities its MIS
// weights need: camera subpaths start on the sensor, light subpaths on an emitter chosen as
// Scene::sample_emitter does; both sample BSDFs or phase functions and free-flight distances in media,
// crossing null surfaces without creating vertices.
#pragma once
#include "render/integrator.h"
#include "render/path_vertex.h"

#include <vector>

namespace penumbra {

struct BDPTRecord; // render/bdpt_record.h

// What one sample's walks and connections share.
struct BDPTContext {
    const Scene& scene;
    const BDPTSettings& settings;
    Sampler& sampler;
    RayCounter& rays;
    bool has_media;        // the sensor, a shape or an emitter declares a medium (scene_has_media)
    bool sensor_connects;  // scene points can be connected to the sensor (not a radiance/irradiance meter)
    BoundingSphere bounds; // the disk infinite lights emit from has this radius
    BDPTRecord* record = nullptr; // the differentiable estimator's record of the sample (null: rendering)
};

// Camera subpath z_0 (on the lens), z_1, ... along the primary `ray` (lens sample `u_aperture`).
void camera_subpath(BDPTContext& ctx, const Ray& ray, const Vec2f& u_aperture, std::vector<PathVertex>& path,
                    size_t max_vertices);
// Light subpath y_0 (on the emitter), y_1, ...
void light_subpath(BDPTContext& ctx, std::vector<PathVertex>& path, size_t max_vertices);

// The free-flight factors of a straight connection from a to b (starting in `medium`): {ff of b from a, ff
// of a from b}; 1 without media.
std::pair<float, float> connection_free_flight(BDPTContext& ctx, const PathVertex& a, const PathVertex& b,
                                               const Medium* medium);

// World direction from `from` toward `to` (the light's direction for an infinite `to`).
Vec3f direction_to(const PathVertex& from, const PathVertex& to);

// Solid-angle density pdf_dir at `from` toward `to`, converted to `to`'s measure times the free-flight factor
// ff (p_A = p_σ |cos θ'| / d²); kept in solid angle for an infinite `to`. From an infinite light, pdf_dir is
// the density on the emission disk (parallel rays: only |cos| at `to`).
float to_area_density(const PathVertex& from, const PathVertex& to, float pdf_dir, float ff);

// Density with which the subpath through prev → v would sample `next` (v a surface or medium vertex).
float scattering_density(const PathVertex& v, const Vec3f& w_prev, const PathVertex& next, float ff,
                         TransportMode mode);

// v as a light endpoint of `emitter`: the density of sampling v itself (position, or the direction of an
// infinite light as seen from `next`), and of emitting toward `next`.
float light_origin_density(const Scene& scene, const Emitter* emitter, const PathVertex& v,
                           const PathVertex& next);
float light_emission_density(const BDPTContext& ctx, const Emitter* emitter, const PathVertex& v,
                             const PathVertex& next, float ff);

// The medium a ray leaving a surface vertex (or a medium vertex) in direction d travels in.
const Medium* medium_toward(const PathVertex& v, const Vec3f& d);
// The ray from v to the (finite) point target, offset off v's surface.
Ray ray_between(const PathVertex& v, const Vec3f& target);

} // namespace penumbra
