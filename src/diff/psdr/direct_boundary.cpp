#include "diff/psdr/direct_boundary.h"

#include "diff/psdr/detector_subpath.h"
#include "render/light_medium.h"
#include "scene/shape_interaction.h"

namespace penumbra {

namespace {

// Incident term at x from the light point, without visibility: point lights I/d², area lights L_e cos_y / d²,
// directional lights their irradiance, environments their radiance from the sampled direction.
Color3f incident(const Emitter& emitter, const SegmentSource& light, const Vec3f& x) {
    if (light.infinite) return emitter.is_delta() ? emitter.eval_delta(x) : emitter.eval_environment(light.d * -1.f);
    const Vec3f d = light.p - x;
    const float dist2 = squared_norm(d);
    if (!light.shape) return emitter.eval_delta(x);
    SurfaceInteraction3f y = surface_interaction<float>(*light.shape, light.prim, light.bary, MeshVertices{light.shape->mesh});
    y.wi = y.to_local(normalize(x - light.p));
    return emitter.eval(y) * (std::abs(dot(y.n, d)) / (dist2 * std::sqrt(dist2)));
}

// The boundary terms sample shadow edges, not jumps of the emitted light itself: refuses motions of a mesh
// that such a jump crosses (a projector's frustum border, nearest-filtered projected texels).
void check_emission_jumps(const Scene& scene, const Parameters& params) {
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
        const Shape* shape = scene.shapes[i].get();
        if (!params.moves(*shape)) continue;
        for (const auto& emitter : scene.emitters)
            if (emitter->emission_jumps_on(shape->mesh))
                throw Error(
                    "derivatives w.r.t. the motion of shape '" +
                    (shape->id.empty() ? "shape_" + std::to_string(i) : shape->id) +
                    "' are not supported: the light of the " + emitter->plugin + " emitter" +
                    (emitter->id.empty() ? "" : " '" + emitter->id + "'") +
                    " jumps across it (the border of its frustum or cone, or nearest-filtered texels), a "
                    "boundary penumbra does not sample");
    }
    // A moving light moves such jumps of its own light across every surface they fall on.
    for (size_t k = 0; k < scene.emitters.size(); ++k) {
        const Emitter& e = *scene.emitters[k];
        if (params.emitter_motions(&e).empty()) continue;
        for (const auto& shape : scene.shapes)
            if (e.emission_jumps_on(shape->mesh))
                throw Error(
                    "derivatives w.r.t. the motion of the " + e.plugin + " emitter '" +
                    (e.id.empty() ? "emitter_" + std::to_string(k) : e.id) +
                    "' are not supported: its light jumps across the scene (the border of its frustum or "
                    "cone, or nearest-filtered texels), a boundary penumbra does not sample");
    }
}

} // namespace

BoundarySample sample_emitter_boundary(const Scene& scene, const SceneEdges& edges, const SegmentContext& context,
                                       int t_min, int t_max, const PathSettings& settings,
                                       const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
    BoundarySample out;
    // An emitter, a point on one of the edges that can cast its shadows (the stratified number, rescaled by the
    // emitter selection, stratifies the edge points), and a light point: point lights at their position, area
    // lights by area; directional and environment emitters give a direction (from infinity), the latter by
    // their solid-angle density.
    if (scene.emitters.empty()) return out;
    float u_edge = index.stratified(sampler), select_pdf = 0.f;
    const size_t emitter_index = scene.sample_emitter_index(u_edge, select_pdf);
    const Emitter* emitter = scene.emitters[emitter_index].get();
    const Vec2f u2 = sampler.next_2d();
    const EdgeSet& shadow_edges = edges.lit[emitter_index];
    if (shadow_edges.empty()) return out;
    const EdgePoint x_b = sample_edge_point(edges, shadow_edges, u_edge);
    SegmentSource light;
    float light_pdf = select_pdf; // area or solid-angle density (1 for delta lights) times the selection probability
    if (const Shape* shape = emitter->shape()) {
        const PositionSample3f ps = shape->sample_position(u2);
        light = {.p = ps.p, .n = ps.n, .shape = shape, .prim = ps.prim, .bary = ps.bary};
        light_pdf *= ps.pdf;
    } else {
        Interaction3f ref;
        ref.p = x_b.p;
        const DirectionSample3f ds = emitter->sample_direction(ref, u2).first;
        if (!(ds.pdf > 0.f)) return out;
        light.p = ds.p;
        light.n = Vec3f(0.f);
        light.emitter = emitter;
        if (emitter->is_infinite()) {
            light.infinite = true;
            light.d = ds.d * -1.f;
            if (!emitter->is_delta()) light_pdf *= ds.pdf;
        }
    }

    if (context.media) {
        const Vec3f origin = light.infinite ? scene.bounding_sphere().center - light.d * (4.f * scene.bounding_sphere().radius + 1.f)
                                            : light.p;
        light.medium = emitter_medium(scene, *emitter, origin, rays);
    }

    const BoundarySegment seg = trace_boundary_segment(scene, context, light, x_b, sampler, rays);
    if (!seg.valid) return out;
    DetectorConnections connections;
    detector_connections(scene, context.form, seg, t_min, t_max, settings, sampler, rays, connections);
    // The segment's factor: incident term × |cos| at x_D0 × dℓ(x_D0)/dℓ(x_B) (at a medium vertex: × 1 ×
    // dA(x_D0)/(dℓ(x_B) dr_D)) × its transmittance (and free-flight weight), over the edge and light densities.
    const Color3f factor = incident(*emitter, light, seg.receiver.p) * seg.transmittance *
                           (seg.cos_receiver * seg.stretch * shadow_edges.total_length / light_pdf);
    for (int k = 0; k < connections.count; ++k) {
        const CameraConnection& c = connections.items[k];
        out.add_splat(c.s, factor * c.weight, c.velocity);
    }
    return out;
}

namespace {

constexpr uint64_t Salt = 0x94D049BB133111EBULL;

// Direct illumination needs paths of two segments (camera → x_D0 → light): max_depth 1 renders emitters seen
// directly only, and the term is zero.
bool direct_paths(const PathSettings& path) { return path.max_depth < 0 || path.max_depth >= 2; }

} // namespace

Image DirectBoundary::derivative(const Parameters& params, const BoundaryOptions& options) const {
    check_emission_jumps(scene_, params);
    if (edges_.empty() || scene_.emitters.empty() || !direct_paths(options.path))
        return Image(scene_.sensor->film->width, scene_.sensor->film->height);
    const MaterialForm form(scene_, params, options.first_vertex);
    const SegmentContext context{form, options.volume_endpoints, edges_.media};
    return boundary_derivative(scene_, params, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_emitter_boundary(scene_, edges_, context, 0, 0, options.path, index, sampler, rays);
    });
}

void DirectBoundary::gradient(const Parameters& params, const Image& adjoint, const BoundaryOptions& options,
                              std::vector<double>& gradient) const {
    check_emission_jumps(scene_, params);
    if (edges_.empty() || scene_.emitters.empty() || !direct_paths(options.path)) return;
    const MaterialForm form(scene_, params, options.first_vertex);
    const SegmentContext context{form, options.volume_endpoints, edges_.media};
    boundary_gradient(scene_, params, adjoint, options, Salt, [&](const BoundarySampleIndex& index, Sampler& sampler, RayCounter& rays) {
        return sample_emitter_boundary(scene_, edges_, context, 0, 0, options.path, index, sampler, rays);
    }, gradient);
}

} // namespace penumbra
