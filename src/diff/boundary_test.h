// The boundary test B(ω') of warped-area sampling for triangle meshes (paper 004 Appendix A): a soft
// indicator that vanishes at the visibility boundaries seen from a point x, so that the harmonic weights (Eq.
// 8) pull the warp field to the boundary's velocity there. Per hit triangle, each corner v gets
//   B_v = 0                                        if an edge at v is a silhouette from x (its two faces are
//                                                  turned differently toward x) or open (one face),
//   B_v = c² / (1 − (1 − β)(1 − c²)), c = ⟨ω', n_v⟩ otherwise (the paper's (1 − (1 − c²)) / (...)),
// with n_v the average normal of the faces around v and β the spread (0.01 in the paper), and B(ω') is the
// barycentric interpolation of the three B_v at the hit. Rays that escape get B = 1: no boundary is known
// there (an escaped ray next to a mesh still sees the mesh's silhouette vertices go to 0 on the mesh side).
// Limitation (paper §5.5): implicit edges where meshes intersect are not detected.
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
// (Eq. 8's limit).
#pragma once
#include "diff/edges.h"
#include "scene/scene.h"

#include <unordered_map>
#include <vector>

namespace penumbra {

class BoundaryTest {
  public:
    explicit BoundaryTest(const Scene& scene, float spread = 0.01f);

    // B(ω') for the ray from `origin` along `direction` that found `hit` (Appendix A, steps 1–3; with the
    // distance term when `scale` > 0).
    float operator()(const SurfaceInteraction3f& hit, const Vec3f& origin, const Vec3f& direction,
                     float scale = 0.f) const;
    // B_v of vertex v of `shape` (step 2).
    float vertex_value(const Shape& shape, uint32_t v, const Vec3f& origin, const Vec3f& direction) const;

  private:
    struct MeshEdges {
        std::vector<uint32_t> canonical;    // one id per distinct position (seams share their edges)
        std::vector<Edge> edges;            // discontinuity edges: open, or between non-coplanar faces
        std::vector<uint32_t> offsets, ids; // edges at each canonical vertex: ids[offsets[c] .. offsets[c+1])
        std::vector<Vec3f> normals;         // average face normal at each canonical vertex
    };
    const MeshEdges& edges_of(const Shape& shape) const;
    // The normal term of vertex v (step 2 without the zeroing).
    float normal_value(const MeshEdges& m, uint32_t v, const Vec3f& direction) const;
    // Whether a silhouette or open edge (seen from `origin`) ends at vertex v; the edge to vertex `w`, if
    // there is one, is reported in `to_w`.
    bool on_boundary(const Shape& shape, const MeshEdges& m, uint32_t v, uint32_t w, const Vec3f& origin,
                     bool& to_w) const;

    float spread_;
    std::unordered_map<const Shape*, MeshEdges> meshes_;
};

} // namespace penumbra
