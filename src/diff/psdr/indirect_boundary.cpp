#include "diff/psdr/indirect_boundary.h"

#include "core/warp.h"

#include "diff/media_radiance.h"
#include "diff/media_walk.h"
#include "diff/psdr/detector_subpath.h"
#include "diff/psdr/direct_boundary.h"
#include "render/light_medium.h"

namespace penumbra {

namespace {

constexpr uint64_t EmitterSalt = 0xD1B54A32D192ED03ULL, DirectionalSalt = 0x8CB92BA72F3D8DD7ULL,
                   CameraSalt = 0x94D049BB133111EBULL;

// Deepest detector vertex for a boundary segment whose source subpath has at least `source_segments` segments
// (-1: unbounded): the whole path camera → x_Dt … x_D0 → x_S0 → … has t + 2 + source_segments − 1 segments.
int max_detector_depth(const PathSettings& settings, int source_segments) {
    return settings.max_depth < 0 ? -1 : settings.max_depth - 1 - source_segments;
}

// Radiance x_S0 reflects toward x_D0 (its emission excluded), by path tracing from x_S0 with at most
// `max_depth` segments counting x_D0 → x_S0 (-1: unbounded).
Color3f reflected_radiance(const Scene& scene, const SurfaceInteraction3f& x_s0, const Vec3f& from, int max_depth,
                           const PathSettings& settings, Sampler& sampler, RayCounter& rays) {
    PathSettings source = settings;
    source.max_depth = max_depth;
    source.hide_emitters = true;
    const Ray arriving(from, normalize(x_s0.p - from));
    return trace_path<float>(scene, sampler, arriving, x_s0, x_s0, ReferenceGeometry{}, source, rays);
}

// Radiance the source vertex x_S0 sends toward x_D0 (its emission excluded) with at most `max_depth` segments
// counting x_D0 → x_S0 (-1: unbounded): path tracing in vacuum, volumetric path tracing in media
// (diff/media_radiance.h; at a medium vertex the in-scattered radiance, σ_s being in the flight's weight).
Color3f source_radiance(const Scene& scene, const FlightEnd& x_s0, const Vec3f& from, bool media, int max_depth,
                        const PathSettings& settings, Sampler& sampler, RayCounter& rays) {
    if (!media) return reflected_radiance(scene, x_s0.si, from, max_depth, settings, sampler, rays);
    RadianceVertex v{x_s0.kind == FlightEnd::Kind::Surface ? x_s0.si : SurfaceInteraction3f{},
                     normalize(from - x_s0.p), x_s0.medium};
    v.si.p = x_s0.p;
    return vertex_radiance(scene, v, max_depth, false, settings, sampler, rays);
}

// Splats the connections' contributions, the radiance arriving at x_D0 from the source side estimated once
// per path-length budget the connections need (all from the same random numbers; each is unbiased for its
// budget): `radiance(budget)` with at most `budget` segments counting x_D0 → x_S0 (-1: unbounded).
template <typename Radiance>
void splat_with_source_radiance(const DetectorConnections& connections, const Color3f& factor,
                                const PathSettings& settings, Sampler& sampler, Radiance&& radiance_within,
                                BoundarySample& out) {
    Color3f radiance(0.f);
    int budget_of_radiance = -2;
    const Sampler source_start = sampler;
    for (int k = 0; k < connections.count; ++k) {
        const CameraConnection& c = connections.items[k];
        const int budget = settings.max_depth < 0 ? -1 : settings.max_depth - (c.t + 1);
        if (budget != budget_of_radiance) {
            sampler = source_start;
            radiance = radiance_within(budget);
            budget_of_radiance = budget;
        }
        if (!is_black(radiance)) out.add_splat(c.s, radiance * c.weight * factor, c.velocity);
    }
}

// The light a contact's receiver takes from the face rising from the curve (diff/psdr/boundary_segment.h,
// Contact): just outside the curve, the face fills the quarter of the receiver's directions on its side, and
// no line through the edge reaches the receiver from there, so the grazing segments leave that light out. A
// direction ω toward the face (cosine-weighted about the receiver's normal; the others are the grazing
// segments'), the radiance arriving along it (emission included: no emitter sample covers it), and the
// detector subpath from the receiver; seen directly (t = 0) the contact is the primary term's (a silhouette
// resting on the surface). `weight`: the inverse probability of taking this strategy at the edge point.
BoundarySample sample_contact_face(const Scene& scene, const SceneEdges& edges, const SegmentContext& context,
                                   const PathSettings& settings, const EdgePoint& x_b, const Contact& contact,
                                   float weight, Sampler& sampler, RayCounter& rays) {
    BoundarySample out;
    const int t_max = max_detector_depth(settings, 1);
    if (settings.max_depth >= 0 && t_max < 1) return out;
    const SurfaceInteraction3f& recv = contact.surface;
    const Vec3f w = Frame<float>(contact.up).to_world(warp::square_to_cosine_hemisphere(sampler.next_2d()));
    if (!(dot(w, contact.rising_normal) < 0.f)) return out;
    const BoundarySegment seg = contact_segment(scene, context.form, x_b, contact, w);
    DetectorConnections connections;
    detector_connections(scene, context.form, seg, 1, t_max, settings, sampler, rays, connections);
    if (connections.count == 0) return out;
    // |cos| / p(ω) = π, over the edge point's density.
    const float factor = Pi * edges.all.total_length * weight;
    const Ray ray = recv.spawn_ray(w);
    ++rays.rays;
    const SurfaceInteraction3f source = scene.intersect(ray);
    splat_with_source_radiance(
        connections, Color3f(factor), settings, sampler,
        [&](int budget) {
            PathSettings arriving = settings;
            arriving.max_depth = budget;
            arriving.hide_emitters = false;
            return trace_path<float>(scene, sampler, ray, source, source, ReferenceGeometry{}, arriving,
                                     rays);
        },
        out);
    return out;
}

// The camera technique of the lit side (sample_from_camera): x_D0 where a camera ray through a film point
// uniform over the image and its filter's margin first meets the scene, the edge point x_B drawn by the edge
// tree as seen from x_D0 toward the camera; the line x_B → x_D0 is then traced as Algorithm 1 traces it. It
// samples the segments whose receiver the camera sees (t = 0) in proportion to the receiver's lobe toward the
// edges, where Algorithm 1's uniform directions rarely find the lobe of a glossy receiver (a hedge's edges in
// a glossy floor). The two are combined by the balance heuristic (equal sample counts) on those segments.
// Only in vacuum, with a camera that projects points and no null surfaces (where the first surface a camera
// ray meets is the receiver the camera connection sees).
struct CameraEdges {
    const SceneEdges& edges;
    const EdgeTree& tree;
    // The film rectangle the camera rays pass through, its filter's margin included (pixels²).
    float film_area;
    CameraEdges(const SceneEdges& e, const EdgeTree& t, const Film& film)
        : edges(e), tree(t), film_area(float(film.width + 2.f * film.rfilter->radius()) *
                                       float(film.height + 2.f * film.rfilter->radius())) {}
};

bool camera_technique_applies(const Scene& scene, const SceneEdges& edges) {
    if (edges.media || edges.empty() || scene.sensor->medium || !scene.sensor->projects_points())
        return false;
    for (const auto& shape : scene.shapes)
        if (shape->bsdf && shape->bsdf->has(BSDFNull)) return false;
    return true;
}

// The camera technique's density of the lit side's segment through x_B to the receiver seen from the camera,
// per unit length of x_B and solid angle of ω_B: the film point's density |ds/dA(x_D0)| / area, the edge
// tree's, and dA(x_D0) = r_D² / |cos φ_D| dσ(ω_B).
float camera_density(const Scene& scene, const CameraEdges& camera, const BoundarySegment& seg,
                     const EdgePoint& x_b) {
    const SurfaceInteraction3f& x = seg.receiver;
    Vec2f s;
    float jacobian;
    if (!(seg.cos_receiver > 0.f) || !scene.sensor->film_position(x.p, x.n, s, jacobian)) return 0.f;
    const EdgeViewer viewer(x, scene.sensor->to_sensor(x.p));
    const float p_edge = camera.tree.pdf(viewer, x_b);
    return jacobian / camera.film_area * p_edge * squared_norm(x.p - x_b.p) / seg.cos_receiver;
}

// The lit side of the line through x_B along ω_B (Algorithm 1 of paper 001, lines 4–): x_S0 by a free flight
// behind x_B, the segment on to x_D0, the radiance x_S0 sends along it. Returns the segment (invalid when the
// line has no source or no receiver).
// `camera`: the camera technique when it applies, whose density weighs the connection of x_D0 itself (the
// balance heuristic); `seen`: the receiver the camera technique drew this line for (then only x_D0's own
// connection is made, and only if the line reaches that receiver).
BoundarySegment add_lit_side(const Scene& scene, const SegmentContext& context, const PathSettings& settings,
                             const EdgePoint& x_b, const Vec3f& w_b, float edge_weight, float pdf_w,
                             const std::optional<Contact>& contact, const CameraEdges* camera,
                             const SurfaceInteraction3f* seen, Sampler& sampler, RayCounter& rays,
                             BoundarySample& out) {
    // x_S0 (line 4): a free flight behind x_B along −ω_B, ending at a medium vertex or the first surface.
    // The medium around x_B: a line grazing an edge passes outside the edge's shape (its exterior medium, if the
    // shape bounds media; otherwise the medium found by the walk from the sensor).
    const Shape& edge_shape = *x_b.edge->shape;
    const Medium* edge_medium = !context.media                              ? nullptr
                                : edge_shape.interior || edge_shape.exterior ? edge_shape.exterior.get()
                                                                             : medium_at(scene, x_b.p, rays);
    const FlightEnd x_s0 =
        flight_from_edge(scene, x_b, w_b * -1.f, edge_medium, context.volume_endpoints, sampler, rays);
    SegmentSource source{.p = x_s0.p, .n = Vec3f(0.f), .medium = x_s0.medium, .in_medium = true, .from_edge = true,
                         .edge_medium = edge_medium};
    if (x_s0.kind == FlightEnd::Kind::Surface) {
        const SurfaceInteraction3f& si = x_s0.si;
        if (!si.bsdf() || !si.bsdf()->has(BSDFSmooth)) return {};
        source.n = si.n;
        source.shape = si.shape;
        source.prim = si.prim_index;
        source.bary = si.bary;
        source.in_medium = false;
    } else if (x_s0.kind != FlightEnd::Kind::Medium) {
        return {};
    }
    const BoundarySegment seg = trace_boundary_segment(scene, context, source, x_b, sampler, rays, contact);
    if (!seg.valid) return seg;
    if (seen && (seg.receiver.shape != seen->shape || seg.receiver.prim_index != seen->prim_index))
        return seg;

    DetectorConnections connections;
    detector_connections(scene, context.form, seg, 0, seen ? 0 : max_detector_depth(settings, 2), settings,
                         sampler, rays, connections);
    if (connections.count == 0) return seg;
    // The balance heuristic on x_D0's own connection: 1 / p_directional becomes 1 / (p_directional +
    // p_camera).
    if (camera && connections.items[0].t == 0) {
        const float p_directional = pdf_w / edge_weight;
        const float p_camera = camera_density(scene, *camera, seg, x_b);
        connections.items[0].weight *= p_directional / (p_directional + p_camera);
    }

    // G(x_S0, x_D0) times the Jacobian of Eqs. 40–43 over the density of (x_B, ω_B): for two surface vertices
    //   |cos φ_S| |cos φ_D| / r² · r_S² / |cos φ_S| · stretch = |cos φ_D| r_S² stretch / r²,
    // and the same expression for medium vertices (no cosine there, stretch = dA(x_D0)/(dℓ(x_B) dr_D)); the
    // densities of r_S and r_D are in the flights' weights.
    const float r_s2 = squared_norm(x_b.p - x_s0.p), r2 = squared_norm(seg.receiver.p - x_s0.p);
    const Color3f factor =
        x_s0.weight * seg.transmittance * (seg.cos_receiver * r_s2 * seg.stretch / r2 * edge_weight / pdf_w);

    // The source subpath.
    splat_with_source_radiance(
        connections, factor, settings, sampler,
        [&](int budget) {
            return source_radiance(scene, x_s0, seg.receiver.p, context.media, budget, settings, sampler,
                                   rays);
        },
        out);
    return seg;
}

// The point of the edge's shape next to x_B that the line of a segment meets from `from` (a point of the
// receiver's plane just beside x_D0), traced back along the segment: the face a vertex attached to x_D0 lies
// on, on that side (invalid if the line meets something else or a face without a smooth BSDF).
SurfaceInteraction3f attached_face_point(const Scene& scene, const BoundarySegment& seg, const EdgePoint& x_b,
                                         const Vec3f& from, RayCounter& rays) {
    Interaction3f start;
    start.p = from;
    start.n = seg.receiver.n;
    ++rays.rays;
    const SurfaceInteraction3f y = scene.intersect(start.spawn_ray(seg.direction * -1.f));
    const bool usable = y.is_valid() && y.shape == x_b.edge->shape && y.bsdf() && y.bsdf()->has(BSDFSmooth);
    return usable ? y : SurfaceInteraction3f{};
}

// The dark side of the same line under the contact flow (docs/design.md, "Contacts"). A vertex y that follows
// x_D0 by a fixed direction (within the contact length ℓ) sits on the occluder's face just across the line,
// and that face ends at the edge, which moves relative to the fixed direction: the integrand's jump there,
// f(x_D0 → x_S0) − f(x_D0 → y), has a dark part the lit side leaves out. With the blended flow
// V = V_mat + χ (V_att − V_mat) and the edge moving materially, it is
//   −χ(|x_D0 − x_B|) · L(y → x_D0) · u,
// u the normal velocity, relative to x_D0's flow, of the fixed-direction line through x_B(θ) on the
// receiver's plane (the segment from a source at infinity along ω_B). Emitters and media keep the material
// flow (χ = 0). `lit`: the lit side's segment when it was traced (its receiver rejects most lines cheaply).
void add_attached_dark_side(const Scene& scene, const SegmentContext& context, const PathSettings& settings,
                            const EdgePoint& x_b, const Vec3f& w_b, float weight, const BoundarySegment& lit,
                            Sampler& sampler, RayCounter& rays, BoundarySample& out) {
    const Shape& occluder = *x_b.edge->shape;
    if (!context.form.has_contact_flow() || occluder.emitter) return;
    if (lit.valid &&
        (lit.contact || lit.in_medium || !(context.form.contact_weight(norm(lit.receiver.p - x_b.p)) > 0.f)))
        return;
    const SegmentSource along{.p = x_b.p, .n = Vec3f(0.f), .infinite = true, .d = w_b, .from_edge = true};
    const BoundarySegment seg = trace_boundary_segment(scene, context, along, x_b, sampler, rays);
    if (!seg.valid || seg.contact || seg.in_medium) return;
    const float chi = context.form.contact_weight(norm(seg.receiver.p - x_b.p));
    if (!(chi > 0.f)) return;
    // y: where the line from the receiver's dark side back along ω_B meets the occluder, next to x_B.
    const SurfaceInteraction3f y = attached_face_point(scene, seg, x_b, seg.dark_point, rays);
    if (!y.is_valid()) return;

    DetectorConnections connections;
    detector_connections(scene, context.form, seg, 0, max_detector_depth(settings, 2), settings, sampler,
                         rays, connections);
    if (connections.count == 0) return;
    const Color3f factor = seg.transmittance * (-chi * seg.cos_receiver * seg.stretch * weight);
    splat_with_source_radiance(
        connections, factor, settings, sampler,
        [&](int budget) {
            return reflected_radiance(scene, y, seg.receiver.p, budget, settings, sampler, rays);
        },
        out);
}

// A crease under the contact flow (docs/design.md, "Contacts"). From x_D0 in front of both faces of a convex
// edge, a vertex attached to x_D0 by a fixed direction passes from one face to the other where the direction
// meets the edge, and the edge moves relative to the fixed direction; with material vertices the crease is
// each face's fixed border and adds nothing. The jump is χ(|x_D0 − x_B|) (L(y₁ → x_D0) − L(y₀ → x_D0)), y_k
// the attached points on the faces on either side, moving at u (as for the dark side): a line through x_B
// along a direction d that leaves the solid there (sample_crease_direction), the segment from a source at
// infinity behind it. `weight`: the inverse density of x_B.
void add_attached_crease(const Scene& scene, const SegmentContext& context, const PathSettings& settings,
                         const EdgePoint& x_b, float weight, Sampler& sampler, RayCounter& rays,
                         BoundarySample& out) {
    if (!context.form.has_contact_flow() || x_b.edge->shape->emitter) return;
    Vec3f d;
    float pdf_d;
    if (!sample_crease_direction(*x_b.edge, sampler.next_2d(), d, pdf_d)) return;
    const SegmentSource along{
        .p = x_b.p, .n = Vec3f(0.f), .infinite = true, .d = d, .from_edge = true, .crease = true};
    const BoundarySegment seg = trace_boundary_segment(scene, context, along, x_b, sampler, rays);
    if (!seg.valid || seg.contact || seg.in_medium) return;
    const float chi = context.form.contact_weight(norm(seg.receiver.p - x_b.p));
    if (!(chi > 0.f)) return;
    const Vec3f beside = seg.dark_point - seg.receiver.p;
    const SurfaceInteraction3f y_dark = attached_face_point(scene, seg, x_b, seg.receiver.p + beside, rays),
                               y_lit = attached_face_point(scene, seg, x_b, seg.receiver.p - beside, rays);
    if (!y_dark.is_valid() || !y_lit.is_valid()) return;

    DetectorConnections connections;
    detector_connections(scene, context.form, seg, 0, max_detector_depth(settings, 2), settings, sampler,
                         rays, connections);
    if (connections.count == 0) return;
    const Color3f factor = Color3f(chi * seg.cos_receiver * seg.stretch * weight / pdf_d);
    splat_with_source_radiance(
        connections, factor, settings, sampler,
        [&](int budget) {
            const Color3f lit =
                reflected_radiance(scene, y_lit, seg.receiver.p, budget, settings, sampler, rays);
            return lit - reflected_radiance(scene, y_dark, seg.receiver.p, budget, settings, sampler, rays);
        },
        out);
}

// Algorithm 1 of paper 001: one multi-directional boundary sample, its endpoints drawn by sampleInteraction
// (surface or medium vertices); under the contact flow also the line's attached dark side, and a crease line
// through the same edge point.
BoundarySample sample_directional(const Scene& scene, const SceneEdges& edges, const SegmentContext& context,
                                  const CameraEdges* camera, const PathSettings& settings,
                                  const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
    BoundarySample out;
    const int t_max = max_detector_depth(settings, 2);
    if (settings.max_depth >= 0 && t_max < 0) return out;
    const EdgePoint x_b = sample_edge_point(edges, edges.all, index.stratified(sampler));
    // At a contact, half of the samples take the light from the rising face instead (each strategy counts
    // twice).
    float strategy_weight = 1.f;
    std::optional<Contact> contact;
    if (!context.media) {
        contact = resting_contact(scene, *x_b.edge, x_b.p, rays);
        if (contact->valid()) {
            strategy_weight = 2.f;
            if (sampler.next_1d() < 0.5f)
                return sample_contact_face(scene, edges, context, settings, x_b, *contact, strategy_weight,
                                           sampler, rays);
        }
    }
    Vec3f w_b;
    float pdf_w;
    if (!sample_grazing_direction(*x_b.edge, sampler.next_2d(), w_b, pdf_w)) return out;
    // Over the density of x_B (and that of ω_B).
    const float edge_weight = edges.all.total_length * strategy_weight;
    const BoundarySegment lit = add_lit_side(scene, context, settings, x_b, w_b, edge_weight, pdf_w, contact,
                                             camera, nullptr, sampler, rays, out);
    if (!(contact && contact->valid())) {
        add_attached_dark_side(scene, context, settings, x_b, w_b, edge_weight / pdf_w, lit, sampler, rays, out);
        add_attached_crease(scene, context, settings, x_b, edge_weight, sampler, rays, out);
    }
    return out;
}

// The camera technique (CameraEdges): a film point stratified over the samples, the receiver x_D0 the camera
// ray meets, an edge point drawn by the edge tree from x_D0, and the lit side of the line x_B → x_D0 with
// x_D0's own camera connection.
BoundarySample sample_from_camera(const Scene& scene, const SceneEdges& edges, const SegmentContext& context,
                                  const CameraEdges& camera, const PathSettings& settings,
                                  const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
    BoundarySample out;
    if (settings.max_depth >= 0 && max_detector_depth(settings, 2) < 0) return out;
    const Sensor& sensor = *scene.sensor;
    const Film& film = *sensor.film;
    const float margin = film.rfilter->radius();
    const uint64_t pixels = uint64_t(film.width) * uint64_t(film.height);
    const uint64_t cell = std::min(uint64_t(double(index.stratified(sampler)) * double(pixels)), pixels - 1);
    const Vec2f jitter = sampler.next_2d();
    const Vec2f s(-margin + (float(cell % uint64_t(film.width)) + jitter.x) * (film.width + 2.f * margin) /
                                float(film.width),
                  -margin + (float(cell / uint64_t(film.width)) + jitter.y) * (film.height + 2.f * margin) /
                                float(film.height));
    const Ray ray = sensor.sample_ray(s, Vec2f(0.5f)).first;
    ++rays.rays;
    const SurfaceInteraction3f seen = scene.intersect(ray);
    if (!seen.is_valid() || !seen.bsdf() || !seen.bsdf()->has(BSDFSmooth)) return out;
    float pdf_edge;
    const EdgeViewer viewer(seen, ray.d * -1.f);
    const float u_edge = sampler.next_1d();
    const EdgePoint x_b = camera.tree.sample(viewer, u_edge, sampler.next_1d(), pdf_edge);
    if (!(pdf_edge > 0.f)) return out;
    const Vec3f w_b = normalize(seen.p - x_b.p);
    const float pdf_w = grazing_direction_pdf(*x_b.edge, w_b);
    if (!(pdf_w > 0.f)) return out;
    std::optional<Contact> contact = resting_contact(scene, *x_b.edge, x_b.p, rays);
    const float edge_weight = edges.all.total_length * (contact->valid() ? 2.f : 1.f);
    add_lit_side(scene, context, settings, x_b, w_b, edge_weight, pdf_w, contact, &camera, &seen, sampler,
                 rays, out);
    return out;
}

// Runs `term(salt, sample)` for each technique: emitter sources, Algorithm 1 and, with `tree`, the camera
// technique.
template <typename Term>
void for_each_technique(const Scene& scene, const SceneEdges& edges, const EdgeTree* tree,
                        const Parameters& params, const BoundaryOptions& options, const Term& term) {
    const MaterialForm form(scene, params, options.first_vertex);
    const SegmentContext context{form, options.volume_endpoints, edges.media};
    const int t_max = max_detector_depth(options.path, 1);
    if (!scene.emitters.empty() && (t_max < 0 || t_max >= 1)) {
        term(EmitterSalt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
            return sample_emitter_boundary(scene, edges, context, 1, t_max, options.path, index, sampler,
                                           rays);
        });
    }
    const std::optional<CameraEdges> camera =
        tree ? std::optional<CameraEdges>(std::in_place, edges, *tree, *scene.sensor->film) : std::nullopt;
    const CameraEdges* cam = camera ? &*camera : nullptr;
    term(DirectionalSalt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_directional(scene, edges, context, cam, options.path, index, sampler, rays);
    });
    if (cam) {
        term(CameraSalt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
            return sample_from_camera(scene, edges, context, *cam, options.path, index, sampler, rays);
        });
    }
}

} // namespace

IndirectBoundary::IndirectBoundary(const Scene& scene, const SceneEdges& edges)
    : scene_(scene), edges_(edges) {
    if (camera_technique_applies(scene, edges)) camera_edges_.emplace(edges);
}

Image IndirectBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    const Film& film = *scene_.sensor->film;
    Image result(film.width, film.height);
    if (edges_.empty()) return result;
    for_each_technique(scene_, edges_, camera_edges_ ? &*camera_edges_ : nullptr, params, options,
                       [&](uint64_t salt, const auto& sample) {
                           const Image part = boundary_derivative(scene_, params, options, salt, sample);
                           for (size_t i = 0; i < result.pixels.size(); ++i)
                               result.pixels[i] += part.pixels[i];
                       });
    return result;
}

void IndirectBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                                std::vector<double>& gradient) const {
    if (edges_.empty()) return;
    for_each_technique(scene_, edges_, camera_edges_ ? &*camera_edges_ : nullptr, params, options,
                       [&](uint64_t salt, const auto& sample) {
                           boundary_gradient(scene_, params, adjoint, options, salt, sample, gradient);
                       });
}

} // namespace penumbra
