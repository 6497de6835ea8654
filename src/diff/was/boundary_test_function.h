// The boundary test B(ω') of warped-area sampling for triangle meshes (paper 004 Appendix A): a soft
// indicator that vanishes at the visibility boundaries seen from a point x, so that the harmonic weights (Eq.
// 8) pull the warp field to the boundary's velocity there. Per hit triangle, each corner v gets
//   B_v = 0                                        if an edge at v is a silhouette from x (its two faces are
//                                                  turned differently toward x) or open (one face),
//   B_v = c² / (1 − (1 − β)(1 − c²)), c = ⟨ω', n_v⟩ otherwise (the paper's (1 − (1 − c²)) / (...)),
// with n_v the average normal of the faces around v and β the spread (0.01 in the paper), and B(ω') is the
// barycentric interpolation of the three B_v at the hit. Rays that escape get B = 1: no boundary is known
// there (an escaped ray next to a mesh still sees the mesh's silhouette vertices go to 0 on the mesh side).
//
// With a distance scale s > 0 (what the estimators use), the zeroed vertices are replaced by the distance to
// the boundary itself: B = min(B_n, D_e) with B_n the interpolation of the normal term above at every
// vertex (no vertex zeroed) and D_e = e^{s r²/2} − 1 for the angle r, seen from the ray's origin, between the
// hit and the nearest silhouette or open edge of the hit triangle or vertex of it on such an edge (s = κ on
// the sphere, (pixels per radian)² / σ² on the film: D_e is the harmonic weights' own distance D to that
// point). The paper's vertex rule makes B vanish on whole triangles whose corners all touch a boundary (a
// two-triangle rectangle with open edges, a cube seen in general position): the harmonic weights are then
// singular on both sides of a silhouette and the field takes the occluded side's warp at the boundary, which
// biases the estimate (Appendix A's remark on sparse boundary functions). D_e vanishes only at the boundary
// and like the squared distance there, so the weights' integral still diverges at boundary points for γ ≥ 1
// (Eq. 8's limit). The distance term also takes creases, edges across which the shading normal jumps (flat-shaded
// shapes, split vertex normals): the radiance jumps there and the jump moves with the shape, which the field
// follows only approximately unless B vanishes (a rotating flat-shaded cube: z +5.5 → +1.9 on the film,
// with the film jackknife; the paper's meshes are smooth-shaded). The paper's mode (scale 0) keeps Appendix A.
//
// Implicit edges (paper §5.5's limitation, lifted here): where two triangles cross (ImplicitEdges), the
// surface seen changes along the crossing segment, inside both triangles. A hit on a triangle with segments
// gets B multiplied by the spread map of the sine u of the angle, seen from x, between the ray and the
// nearest segment: u / (1 − (1 − β)(1 − u)), the vertex term with c² replaced by u. Near a smooth silhouette
// c² grows linearly with the angular distance to it, so this gives the implicit edge the vertex term's
// profile: linear in the angular distance near the edge (slope 1/β), 1/2 at u ≈ β, → 1 away from it.
// Measuring the angle (not the distance on the surface) makes B vanish at the same rate on both sides of
// the edge, whatever the two surfaces' inclinations. Every crossing is zeroed, visible or not: B must vanish
// at discontinuities and may vanish elsewhere at a cost in variance only.
// What B cannot do: the harmonic weights then take, at the edge, the mean of the two sides' direct warps,
// while the edge moves as neither surface does in general (its velocity mixes both surfaces' normal speeds;
// a cube sliding on a static floor drags the edge with it, a cube lifted from it leaves the edge in place),
// so with material direct warps the field there is consistent only when both sides' agree across the edge.
// With the distance scale, B = min(B, e^{s u²/2} − 1) instead, u the angle to the nearest segment.
// edge_following_point (implicit_edges.h) gives the auxiliary hits next to an edge the edge's velocity as
// their direct warp (tests/test_was_implicit_edges.cpp: error 0.5 → 0.07 at N' = 32 on a sunk cube).
#pragma once
#include "diff/edges.h"
#include "diff/was/implicit_edges.h"
#include "scene/scene.h"

#include <memory>
#include <unordered_map>
#include <vector>

namespace penumbra {

class BoundaryTest {
  public:
    // `implicit_edges` = false keeps the paper's test (mesh edges only).
    explicit BoundaryTest(const Scene& scene, float spread = 0.01f, bool implicit_edges = true);

    // B(ω') for the ray from `origin` along `direction` that found `hit` (Appendix A, steps 1–3; with the
    // distance term when `scale` > 0).
    float operator()(const SurfaceInteraction3f& hit, const Vec3f& origin, const Vec3f& direction,
                     float scale = 0.f) const;
    // B_v of vertex v of `shape` (step 2).
    float vertex_value(const Shape& shape, uint32_t v, const Vec3f& origin, const Vec3f& direction) const;
    // The factor of the implicit edges inside the hit triangle (1 when it has none).
    float implicit_edge_factor(const SurfaceInteraction3f& hit, const Vec3f& origin,
                               const Vec3f& direction) const;
    // The crossing segments found at construction (none when implicit edges are off).
    const ImplicitEdges* implicit_edges() const { return implicit_.get(); }

  private:
    struct MeshEdges {
        std::vector<uint32_t> canonical;    // one id per distinct position (seams share their edges)
        std::vector<Edge> edges;            // discontinuity edges: open, or between non-coplanar faces
        std::vector<uint32_t> offsets, ids; // edges at each canonical vertex: ids[offsets[c] .. offsets[c+1])
        std::vector<Vec3f> normals;         // average face normal at each canonical vertex
        std::vector<uint8_t> crease;        // per edge: the shading normal jumps across it
    };
    const MeshEdges& edges_of(const Shape& shape) const;
    // The normal term of vertex v (step 2 without the zeroing).
    float normal_value(const MeshEdges& m, uint32_t v, const Vec3f& direction) const;
    // Whether a silhouette or open edge (seen from `origin`), or with `creases` a crease edge, ends at vertex
    // v; the edge to vertex `w`, if there is one, is reported in `to_w`.
    bool on_boundary(const Shape& shape, const MeshEdges& m, uint32_t v, uint32_t w, const Vec3f& origin,
                     bool creases, bool& to_w) const;
    // The spread map u / (1 − (1 − β)(1 − u)) of Appendix A step 2 (there u = c²), for the implicit edges.
    float spread_map(float u) const { return u / (1.f - (1.f - spread_) * (1.f - u)); }

    float spread_;
    std::unordered_map<const Shape*, MeshEdges> meshes_;
    std::unique_ptr<ImplicitEdges> implicit_;
};

} // namespace penumbra
