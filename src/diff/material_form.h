// The material-form parameterization of paper 001 §4.1: a path is sampled in the reference configuration as
// material points (triangle, barycentrics) and re-evaluated on the spatial geometry x = X(p, θ), with the area
// Jacobian J(p) = dA(x)/dA(p) (Eq. 17). X is evaluated at θ0 (the identity) with its exact first derivative.
// The first vertex may instead be parameterized by its camera ray (diff/first_vertex.h).
//
// Contacts. Where two surfaces touch (a box resting on a floor) and move relative to each other, the
// material form's integrand has a singularity: for x on one surface and y on the other, d/dθ G(x, y) grows
// like |v_x − v_y| / |x − y| · G, whose integral over path space is not absolutely convergent (the interior
// estimate is Cauchy-tailed: its mean jumps from seed to seed). Any flow of the reference configuration is as
// good as the material one (the boundary terms take velocities relative to it), so a vertex y reached by a
// BSDF sample from x near it is instead carried along the fixed direction ω from x(θ) (its "attached" position,
// where the ray meets y's moving triangle; the solid-angle form of the segment, in which G J is constant), blended
// with its material point by χ(|x − y|) (1 within half the contact length, 0 beyond it, smooth between):
//     V_y = V_mat + χ (V_att − V_mat),  div V_y = div V_mat + χ (div V_att − div V_mat) + ∇χ · (V_att − V_mat).
// Emitter vertices stay material (next-event and BSDF samples of a light share one flow); static pairs have
// V_att = V_mat.
#pragma once
#include "diff/first_vertex.h"
#include "diff/parameters.h"
#include "diff/volume_motion.h"
#include "scene/shape_interaction.h"

#include <type_traits>

namespace penumbra {

// Vertex positions and normals of one shape under the enabled parameters: vertex_positions leaves and motions.
struct MovedVertices {
    const Shape& shape;
    const std::vector<Motion>& motions;

    Vec3<Var> position(uint32_t v) const {
        const Vec3f p0 = shape.mesh.positions[v];
        const int base = shape.vertex_index();
        const auto leaf = [&](float value, int k) { return Var::parameter(value, base + 3 * int(v) + k); };
        Vec3<Var> x(p0);
        if (base >= 0 && !shape.group_shape) x = Vec3<Var>(leaf(p0.x, 0), leaf(p0.y, 1), leaf(p0.z, 2));
        // A flattened instance copy: x = A g + b of its group shape's vertex g, so dx/dg = A (to_world's
        // linear part).
        if (base >= 0 && shape.group_shape)
            x += shape.instance_to_world.apply_vector(Vec3<Var>(leaf(0.f, 0), leaf(0.f, 1), leaf(0.f, 2)));
        for (const Motion& m : motions) x += Vec3<Var>(velocity(m, p0)) * Var::parameter(0.f, m.index);
        return x;
    }
    // dX/dθ at θ = 0 of a motion at p: translate d, rotate a × (p - c), scale (p - c), deform d φ(p).
    static Vec3f velocity(const Motion& m, const Vec3f& p) {
        switch (m.kind) {
        case Parameter::Kind::Translate: return m.vector;
        case Parameter::Kind::Rotate: return cross(m.vector, p - m.center);
        case Parameter::Kind::Deform: return m.vector * deform_weight(m, p);
        default: return p - m.center;
        }
    }
    // Vertex normals rotate with rotations; translations and uniform scaling leave them unchanged; a
    // deformation turns them by the inverse transpose of its gradient, n - θ ∇φ (d·n) to first order (the
    // surface normalizes them). Under vertex_positions they are recomputed from the positions (as Mitsuba 3's
    // Mesh::parameters_changed does): leaves of the tape whose derivatives are chained to the positions once
    // per pass (diff/vertex_normals.h).
    Vec3<Var> normal(uint32_t v) const {
        const Vec3f n0 = shape.mesh.normals[v];
        Vec3<Var> n = shape.vertex_normal_index() >= 0 ? recomputed_normal_leaf(v) : Vec3<Var>(n0);
        for (const Motion& m : motions)
            if (m.kind == Parameter::Kind::Rotate) n += Vec3<Var>(cross(m.vector, n0)) * Var::parameter(0.f, m.index);
            else if (m.kind == Parameter::Kind::Deform)
                n -= Vec3<Var>(deform_weight_gradient(m, shape.mesh.positions[v]) * dot(m.vector, n0)) *
                     Var::parameter(0.f, m.index);
        return n;
    }

private:
    // The value is the stored normal, the derivative the recomputed one's; a flattened instance copy's is its
    // group shape's transformed as TriangleMesh::apply_transform does.
    Vec3<Var> recomputed_normal_leaf(uint32_t v) const {
        const Vec3f n0 = shape.mesh.normals[v];
        const int base = shape.vertex_normal_index() + 3 * int(v);
        if (!shape.group_shape)
            return Vec3<Var>(Var::parameter(n0.x, base), Var::parameter(n0.y, base + 1), Var::parameter(n0.z, base + 2));
        const Vec3f g = shape.group_shape->mesh.normals[v];
        const Vec3<Var> n = normalize(shape.instance_to_world.apply_normal(
            Vec3<Var>(Var::parameter(g.x, base), Var::parameter(g.y, base + 1), Var::parameter(g.z, base + 2))));
        return Vec3<Var>(Var(n0.x, n.x.id), Var(n0.y, n.y.id), Var(n0.z, n.z.id));
    }
};

// X(·, θ) for every shape and the camera.
// Motions of the camera and of point-like lights, which depend on the enabled parameters only (MaterialForm and
// diff/dpm/epsm.h use them).
// The camera's center of projection as it moves.
inline Vec3<Var> camera_position(const Parameters& params, const Vec3f& camera) {
    Vec3<Var> y(camera);
    for (const Motion& m : params.sensor_motions())
        if (m.kind == Parameter::Kind::Translate) y += Vec3<Var>(m.vector) * Var::parameter(0.f, m.index);
    return y;
}
// A direction turned into the moving camera's reference frame (its rotations inverted, to first order).
inline Vec3<Var> direction_to_reference_camera(const Parameters& params, const Vec3<Var>& d) {
    Vec3<Var> y = d;
    for (const Motion& m : params.sensor_motions())
        if (m.kind == Parameter::Kind::Rotate)
            y -= Vec3<Var>(cross(m.vector, Vec3f(d.x.v, d.y.v, d.z.v))) * Var::parameter(0.f, m.index);
    return y;
}
// A world point as seen by the moving camera: the camera's motion applied inversely to the point (first order
// at θ = 0), so that the reference camera's projection can be used.
inline Vec3<Var> to_reference_camera(const Parameters& params, const Vec3<Var>& x, const Vec3f& camera_position) {
    Vec3<Var> y = x;
    for (const Motion& m : params.sensor_motions()) {
        const Var theta = Var::parameter(0.f, m.index);
        if (m.kind == Parameter::Kind::Translate) y -= Vec3<Var>(m.vector) * theta;
        else y -= Vec3<Var>(cross(m.vector, Vec3f(x.x.v, x.y.v, x.z.v) - camera_position)) * theta;
    }
    return y;
}
// A point-like light's position as it moves.
inline Vec3<Var> light_position(const Parameters& params, const Emitter& e, const Vec3f& x_e) {
    Vec3<Var> y(x_e);
    for (const Motion& m : params.emitter_motions(&e))
        if (m.kind == Parameter::Kind::Translate) y += Vec3<Var>(m.vector) * Var::parameter(0.f, m.index);
    return y;
}

// The inverse of a light's motion applied to a receiver point x (first order at θ = 0): the reference light's
// emission at the result is the moved light's at x, since the light is rigid.
inline Vec3<Var> to_reference_light(const Parameters& params, const Emitter& e, const Vec3<Var>& x) {
    Vec3<Var> y = x;
    for (const Motion& m : params.emitter_motions(&e)) {
        const Var theta = Var::parameter(0.f, m.index);
        if (m.kind == Parameter::Kind::Translate)
            y -= Vec3<Var>(m.vector) * theta;
        else
            y -= Vec3<Var>(cross(m.vector, Vec3f(x.x.v, x.y.v, x.z.v) - m.center)) * theta;
    }
    return y;
}

// The foot of x on the plane through p0 with normal n (of any length).
inline Vec3<Var> foot_on_plane(const Vec3<Var>& x, const Vec3<Var>& p0, const Vec3<Var>& n) {
    return x - n * (dot(x - p0, n) / dot(n, n));
}

// The contact length of a scene: vertices within it of their predecessor are carried by the blended flow
// (docs/design.md, "Contacts").
float contact_length(const Scene& scene);

class MaterialForm {
public:
    // contact: whether vertices near their predecessor follow the contact flow (above).
    MaterialForm(const Scene& scene, const Parameters& params, FirstVertex first_vertex, bool contact = true)
        : params_(params), image_space_first_vertex_(penumbra::image_space_first_vertex(scene, params, first_vertex)),
          contact_length_(contact ? contact_length(scene) : 0.f), volume_motion_(scene, params) {}

    // Whether the first path vertex is parameterized by its (fixed) camera ray instead of its material point.
    bool image_space_first_vertex() const { return image_space_first_vertex_; }

    // The spatial interaction x = X(p, θ) at the material point of `hit` (wi and t are left unset).
    SurfaceInteraction<Var> vertex(const SurfaceInteraction3f& hit) const {
        return surface_interaction<Var>(*hit.shape, hit.prim_index, Vec2<Var>(hit.bary), vertices(*hit.shape));
    }
    // The point where the fixed ray meets the moving triangle of `hit` (the image-space first vertex), so
    // that x(θ) slides along the ray with the surface.
    SurfaceInteraction<Var> ray_vertex(const SurfaceInteraction3f& hit, const Ray& ray) const {
        return ray_vertex(hit, Vec3<Var>(ray.o), Vec3<Var>(ray.d));
    }
    // The point where the ray o(θ) + t d(θ) meets the moving triangle of `hit` (the vertex after a delta
    // lobe: o the lobe's vertex, d its direction): its barycentrics b(θ) solve o + t d = X(p0) + b1 (X(p1) −
    // X(p0)) + b2 (X(p2) − X(p0)) on the tape (Möller–Trumbore); values from the reference hit.
    SurfaceInteraction<Var> ray_vertex(const SurfaceInteraction3f& hit, const Vec3<Var>& o,
                                       const Vec3<Var>& d) const;
    // The vertex `hit`, reached by a BSDF sample from the vertex at `prev` (its position on the tape), under the
    // contact flow, with its relative area Jacobian (value 1): the material vertex and J(p) unless `hit` lies
    // within the contact length of `prev` on a shape that emits nothing.
    SurfaceInteraction<Var> flowed_vertex(const SurfaceInteraction3f& hit, const Vec3<Var>& prev, Var& jacobian) const;
    // The blend weight χ(r) of the contact flow at distance r from the predecessor, and dχ/dr.
    float contact_weight(float r, float* derivative = nullptr) const;
    // Whether any vertex can follow the contact flow (a contact length: not in media).
    bool has_contact_flow() const { return contact_length_ > 0.f; }
    // A vertex of a shape at X(p, θ).
    Vec3<Var> position(const Shape& shape, uint32_t v) const { return vertices(shape).position(v); }
    // A point of a contact curve: the moving point x(θ) of an edge that lies on the triangle `prim` of
    // `surface` (an object resting on it), projected onto the triangle's moving plane. Across the curve the
    // surface is hidden on one side (under the object); the curve moves over the surface with the edge's
    // tangential motion only (docs/design.md, "Contacts").
    Vec3<Var> contact_point(const Shape& surface, uint32_t prim, const Vec3<Var>& x) const {
        const uint32_t* i = &surface.mesh.indices[3 * size_t(prim)];
        const Vec3<Var> p0 = position(surface, i[0]);
        return foot_on_plane(x, p0, cross(position(surface, i[1]) - p0, position(surface, i[2]) - p0));
    }
    // A medium vertex x = X(p, θ) of `medium` with its volume Jacobian dV(x)/dV(p) (Eq. 46).
    Vec3<Var> medium_vertex(const Vec3f& p, const Medium* medium, Var& jacobian) const {
        return volume_motion_.position(p, medium, &jacobian);
    }
    const VolumeMotion& volume_motion() const { return volume_motion_; }
    // The camera's center of projection as it moves.
    Vec3<Var> camera_position(const Vec3f& camera) const { return penumbra::camera_position(params_, camera); }
    // J(p) = |(x1 - x0) × (x2 - x0)| / |(p1 - p0) × (p2 - p0)| for the triangle of `hit` (exact: X is affine on it).
    Var jacobian(const SurfaceInteraction3f& hit) const {
        const MovedVertices moved = vertices(*hit.shape);
        const uint32_t* i = &hit.shape->mesh.indices[3 * size_t(hit.prim_index)];
        const Vec3<Var> x0 = moved.position(i[0]);
        const Var area = norm(cross(moved.position(i[1]) - x0, moved.position(i[2]) - x0));
        return area / Var(area.v);
    }
    // A world point as seen by the moving camera (the reference camera's projection can then be used).
    Vec3<Var> to_reference_camera(const Vec3<Var>& x, const Vec3f& camera_position) const {
        return penumbra::to_reference_camera(params_, x, camera_position);
    }
    // Directions rotate with the camera too (normals used by the film Jacobian).
    Vec3<Var> direction_to_reference_camera(const Vec3<Var>& d) const {
        return penumbra::direction_to_reference_camera(params_, d);
    }

    // The inverse: a direction in the reference camera's frame back to the world (the camera's rotation applied).
    Vec3<Var> direction_from_reference_camera(const Vec3<Var>& d) const {
        Vec3<Var> y = d;
        for (const Motion& m : params_.sensor_motions())
            if (m.kind == Parameter::Kind::Rotate)
                y += Vec3<Var>(cross(m.vector, Vec3f(d.x.v, d.y.v, d.z.v))) * Var::parameter(0.f, m.index);
        return y;
    }

    // A moving light (first order at θ = 0): its position x_e + θ d (rotations are about x_e), and a
    // direction it emits along or arrives from, R(a, θ) d.
    Vec3<Var> light_position(const Emitter& e, const Vec3f& x_e) const {
        return penumbra::light_position(params_, e, x_e);
    }
    Vec3<Var> light_direction(const Emitter& e, const Vec3f& d) const {
        Vec3<Var> y(d);
        for (const Motion& m : params_.emitter_motions(&e))
            if (m.kind == Parameter::Kind::Rotate)
                y += Vec3<Var>(cross(m.vector, d)) * Var::parameter(0.f, m.index);
        return y;
    }
    // The inverse motion applied to a receiver point x (or a direction d): the reference light's emission at
    // the result is the moved light's at x, since the light is rigid.
    Vec3<Var> to_reference_light(const Emitter& e, const Vec3<Var>& x) const {
        return penumbra::to_reference_light(params_, e, x);
    }
    Vec3<Var> direction_to_reference_light(const Emitter& e, const Vec3f& d) const {
        Vec3<Var> y(d);
        for (const Motion& m : params_.emitter_motions(&e))
            if (m.kind == Parameter::Kind::Rotate)
                y -= Vec3<Var>(cross(m.vector, d)) * Var::parameter(0.f, m.index);
        return y;
    }
    // Radiance of the infinite emitters along the escaped world direction d.
    Color3<Var> environment(const Scene& scene, const Vec3f& d) const {
        Color3<Var> L(Var(0.f));
        for (const auto& e : scene.emitters)
            if (e->is_infinite() && !e->is_delta())
                L += e->eval_environment(direction_to_reference_light(*e, d));
        return L;
    }
    // The same along d warped on the sphere to `warped` (value d, tangent V: warped-area sampling and
    // reparameterization).
    Color3<Var> environment(const Scene& scene, const Vec3f& d, const Vec3<Var>& warped) const {
        Color3<Var> L(Var(0.f));
        for (const auto& e : scene.emitters)
            if (e->is_infinite() && !e->is_delta())
                L += e->eval_environment(direction_to_reference_light(*e, d) + (warped - Vec3<Var>(d)));
        return L;
    }

private:
    MovedVertices vertices(const Shape& shape) const { return {shape, params_.motions(&shape)}; }
    const Parameters& params_;
    bool image_space_first_vertex_;
    float contact_length_;
    VolumeMotion volume_motion_;
};

} // namespace penumbra
