// Boundary segments away from the camera (paper 001 §5.2, Eqs. 29–31): a segment x_S0 → x_D0 that grazes a
// discontinuity edge at an interior point x_B. Seen from the source endpoint x_S0, the edge casts a
// visibility discontinuity curve onto the receiver surface of x_D0; the boundary term integrates, along that
// curve, the jump of the path contribution (its lit-side value, Eq. 21) times the curve's normal velocity
// relative to the receiver's material point (Eqs. 47–50).
//
// The estimators sample an edge point x_B by length and a source point (an emitter sample, or the first
// surface behind x_B along a sampled direction), extend x_S0 → x_B to the receiver, and convert the measure
// of the curve with dℓ(x_D0) = stretch · dℓ(x_B) (the ratio in Eq. 40).
//
// In participating media (Algorithm 1, sampleInteraction) the extension beyond x_B is a free flight: it ends
// at a medium vertex x_D0 or passes on to the receiver surface. A medium vertex lies on the shadow sheet swept
// by the lines from the source through the edge, whose area element is (Eqs. 39, 41)
//     dA(x_D0) = (r_D / r_B) |ω × ê| dr_D dℓ(x_B)
// (r_D, r_B the distances of x_D0 and x_B from the source, ω the segment's direction, ê the edge's tangent;
// |ω × ê| dr_D dℓ(x_B) from a source at infinity): `stretch` then holds dA(x_D0) / (dℓ(x_B) dr_D). Every
// segment carries its transmittance (with the free flight's weight).
#pragma once
#include "core/distribution.h"
#include "diff/edges.h"
#include "diff/material_form.h"
#include "diff/media_walk.h"
#include "render/integrator.h"

#include <optional>

namespace penumbra {

// A set of edges sampled by length.
struct EdgeSet {
    std::vector<uint32_t> indices; // into SceneEdges::edges
    DiscreteDistribution by_length;
    float total_length = 0.f;
    bool empty() const { return indices.empty(); }
};

// Every discontinuity edge of the scene, sampled by length, and for each emitter the edges that can cast its
// shadows.
struct SceneEdges {
    struct SceneEdge {
        const Shape* shape;
        Edge edge;
        bool closed;     // the edge's mesh has no boundary edges (a solid: concave edges never graze a line)
        bool inside_out; // a closed mesh wound inside out (negative signed volume): its face normals point in
    };
    std::vector<SceneEdge> edges;
    EdgeSet all;
    // Per emitter (in the order of Scene::emitters), the edges that can graze a segment leaving it: for a light
    // within a bounding sphere, an edge qualifies if one of its face planes meets the sphere, or else if it
    // grazes the line from the center (the faces' orientations are then the same from every point of the
    // sphere); for a directional light the exact test along its direction; for environments every edge that
    // can graze at all. A convex or flat emitter's own edges cannot shadow it and are left out. On a finely
    // tessellated occluder only a band of edges around the silhouette remains, instead of all of them.
    std::vector<EdgeSet> lit;

    bool media = false; // the scene has participating media (render/light_medium.h)

    explicit SceneEdges(const Scene& scene);
    bool empty() const { return edges.empty(); }
};

// A point on an edge of `set`, drawn with density 1 / set.total_length (per unit length).
struct EdgePoint {
    const SceneEdges::SceneEdge* edge;
    float tau;      // position along the edge, in [0, 1]
    Vec3f a, b, p;  // the edge's endpoints and the point
};
EdgePoint sample_edge_point(const SceneEdges& edges, const EdgeSet& set, float u);

// Whether the line through the edge with direction d grazes the mesh there (it is a discontinuity of the
// visibility of that line): a boundary edge, or a convex edge with one face turned toward d and one away;
// edges of open meshes are tested with the faces' directions away from the edge instead (a fold of a sheet).
bool grazes(const SceneEdges::SceneEdge& edge, const Vec3f& d);

// A direction d, uniform over those that graze the edge (the line through the edge misses its faces' wedge),
// with its solid-angle density: for a two-face edge with wedge angle φ (< π) the grazing set is the band of
// azimuths around the edge outside the wedge and its mirror image, of measure 4(π − φ); boundary edges graze
// along any direction (density 1/4π). False when no direction grazes (a concave edge of a solid).
bool sample_grazing_direction(const SceneEdges::SceneEdge& edge, const Vec2f& u, Vec3f& d, float& pdf);
// The solid-angle density with which sample_grazing_direction draws d (0 where d does not graze the edge).
float grazing_direction_pdf(const SceneEdges::SceneEdge& edge, const Vec3f& d);

// A direction d, uniform over the lines through a convex edge of a solid that leave it there (in front of
// both faces: from a point on such a line the edge is a crease, not a silhouette), with its solid-angle
// density: the mirror image of the wedge, of measure 2φ. False for other edges.
bool sample_crease_direction(const SceneEdges::SceneEdge& edge, const Vec2f& u, Vec3f& d, float& pdf);

// Where an emitter's light comes from, for choosing the edges its light can reach: every direction (an
// environment), one direction of travel (a directional light), or the bounds of its positions (a mesh
// light's bounding sphere; a point, spot or projector light's position, radius 0).
struct EmitterReach {
    bool environment = false;
    bool directional = false;
    Vec3f travel{0.f}; // directional: the direction of the light's rays
    BoundingSphere bounds{Vec3f(0.f), 0.f};
};
EmitterReach emitter_reach(const Emitter& emitter, const BoundingSphere& scene_bounds);

// The free flight (sample_interaction) from the edge point x_B along a direction `dir` that grazes the edge,
// past hits on the edge's own faces: a grazing line meets them on the edge only, and a hit a hair's breadth
// beyond x_B is the ray's rounding (a receiver or source at a grazing angle, with a huge weight). None
// (Kind::None) if they persist.
FlightEnd flight_from_edge(const Scene& scene, const EdgePoint& x_b, const Vec3f& dir, const Medium* medium,
                           bool volume_vertices, Sampler& sampler, RayCounter& rays);

// The source endpoint x_S0: a point with its surface normal (zero for point lights) and, when it lies on a
// shape, its material point (which moves with the shape); or, for directional and environment emitters, a
// point at infinity: the segment's direction `d` (of travel, away from the emitter).
struct SegmentSource {
    Vec3f p;
    Vec3f n;
    const Shape* shape = nullptr;
    uint32_t prim = 0;
    Vec2f bary = Vec2f(0.f);
    bool infinite = false;
    Vec3f d = Vec3f(0.f);
    const Emitter* emitter = nullptr; // a point or directional light, whose motions move the source
    const Medium* medium = nullptr;   // the medium the segment leaves the source in
    bool in_medium = false;           // a medium vertex (moving by the volume motion)
    // x_S0 was found by a free flight back from x_B (Algorithm 1, line 4): the segment x_S0 → x_B is clear, its
    // transmittance is in the caller's weight, and x_B lies in `edge_medium`.
    bool from_edge = false;
    const Medium* edge_medium = nullptr;
    // The line enters the edge's solid behind x_B (sample_crease_direction): a crease seen from the receiver,
    // not a grazing line.
    bool crease = false;
};

struct BoundarySegment {
    bool valid = false;
    SurfaceInteraction3f receiver; // x_D0, with wi pointing toward the source (a medium vertex: only p is set)
    bool in_medium = false;        // x_D0 is a medium vertex (on the shadow sheet)
    const Medium* medium = nullptr; // the medium of x_D0 (in_medium), or the one the segment reaches it through
    Vec3f direction;               // ω, from the source toward x_D0
    Color3f transmittance{1.f};    // Tr(x_S0 → x_B) times the free flight's weight (Tr σ_s / p at a medium vertex)
    float stretch = 0.f;           // dℓ(x_D0) / dℓ(x_B); a medium vertex: dA(x_D0) / (dℓ(x_B) dr_D)
    float cos_receiver = 0.f;      // |n(x_D0) · ω| for the segment's direction ω (1 at a medium vertex)
    Vec3f dark_point;              // a point of the receiver just across the curve, on the occluded side
    Vec3f curve_point;             // a contact's point on the curve itself (x_D0 lies a probe outside it)
    Var velocity;                  // (x_D0(θ) − receiver material point(θ)) · n_dark: its derivative is the
                                   // curve's (or sheet's) normal velocity, n_dark pointing into the occluded side
    Var velocity_seen;             // the same relative to the point the fixed camera ray through x_D0 meets on
                                   // the moving receiver: the receiver as an image-space first vertex

    // On a surface receiver, what the velocity relative to any flow of the receiver is computed from: the moving
    // edge point x_B(θ), the receiver triangle's plane (a point and normal on the tape), the source (a surface
    // source within the contact length of x_D0 follows the receiver's flow: MaterialForm's contact flow).
    Vec3<Var> edge_point, plane_point, plane_normal;
    Vec3f n_dark;
    SegmentSource source;
    bool source_follows_receiver = false;
    // The edge lies on the receiver (an object resting on it): x_D0 is on the contact curve, which moves with
    // the edge's tangential motion over the receiver (MaterialForm::contact_point), whatever the source.
    bool contact = false;

    // The velocity in the parameterization of the detector vertex at depth t (t = 0: x_D0 itself, connected to
    // the camera; it is the first path vertex), when the receiver's flow is its material point (t > 0) or the
    // camera ray (t = 0).
    const Var& velocity_at_depth(int t) const { return t == 0 ? velocity_seen : velocity; }
    // (x_D0(θ) − receiver(θ)) · n_dark for a surface receiver carried by another flow to `receiver` (the contact
    // flow of its detector subpath).
    Var velocity_relative_to(const MaterialForm& form, const Vec3<Var>& receiver) const;
    // The geometry term of the detector subpath's first segment x_D1 → x_D0 taken at the contact curve rather
    // than at the probed receiver, G(x_D1, curve) / G(x_D1, x_D0) (1 for other segments): the boundary
    // integral is over the curve, which the face rising from it sees edge-on (G = 0); at the probe's offset
    // that face would take a finite share of the curve's light, concentrated on the pixels of the contact
    // line.
    float first_segment_geometry_ratio(const SurfaceInteraction3f& x_d1) const;
};

// A solid's edge resting on another surface at a point x (one of the edge's faces lies on it, facing it: a
// box on a floor): the surface under the object is hidden from everywhere, so the surface's integrand jumps
// along the contact curve, which moves with the object (docs/design.md, "Contacts"). `surface`: the receiving
// surface hit a few ray offsets outside the curve (its lit side); `rising_normal`: the outward normal of the
// edge's other face, which rises from the curve.
// How close to a surface an edge counts as resting on it, and how far outside the contact curve its receiver
// is probed: a few ray offsets.
inline float contact_probe(const Vec3f& x) { return 4.f * ray_offset_scale(x); }

struct Contact {
    SurfaceInteraction3f surface;
    Vec3f rising_normal;
    Vec3f up; // the receiver's normal on the object's side
    bool valid() const { return surface.is_valid(); }
};
Contact resting_contact(const Scene& scene, const SceneEdges::SceneEdge& edge, const Vec3f& x,
                        RayCounter& rays);

// The boundary segment at the contact curve through the edge point x_B, its receiver x_D0 on the contact's
// lit side with light arriving from direction w (toward its source): stretch 1, velocities of the curve
// relative to the receiver's flows (MaterialForm::contact_point); the caller sets its source and
// transmittance.
BoundarySegment contact_segment(const Scene& scene, const MaterialForm& form, const EdgePoint& x_b,
                                const Contact& contact, const Vec3f& w);

// What boundary segments are traced with: the motions of surface and medium vertices (the material form and
// its volume motion), and whether a segment may end in a medium (false: the surface-only boundary segments of a
// DTRT-like baseline); `media`: whether the scene has any (otherwise no medium look-ups).
struct SegmentContext {
    const MaterialForm& form;
    bool volume_endpoints;
    bool media;
};

// Extends source → x_B beyond the edge to the receiver x_D0 (with volume endpoints, a free flight that may
// end in a medium). Invalid when the edge does not graze the line, the segment source → x_B is blocked,
// nothing (or no BSDF) lies beyond, the flight is absorbed, or the curve degenerates. The lit side is lit
// (source → x_B → x_D0 is clear); the occluded side is the one the edge's faces lie on. Records the
// velocities on the thread's tape; a medium vertex moves by the volume motion. `contact`: the edge point's
// resting contact if the caller has already probed for it (resting_contact), else probed here.
BoundarySegment trace_boundary_segment(const Scene& scene, const SegmentContext& context,
                                       const SegmentSource& source, const EdgePoint& x_b, Sampler& sampler,
                                       RayCounter& rays,
                                       const std::optional<Contact>& contact = std::nullopt);

} // namespace penumbra
