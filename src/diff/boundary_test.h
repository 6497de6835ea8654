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
#pragma once
#include "diff/edges.h"
#include "scene/scene.h"

#include <unordered_map>
#include <vector>

namespace penumbra {

class BoundaryTest {
  public:
    explicit BoundaryTest(const Scene& scene, float spread = 0.01f);

    // B(ω') for the ray from `origin` along `direction` that found `hit` (Appendix A, steps 1–3).
    float operator()(const SurfaceInteraction3f& hit, const Vec3f& origin, const Vec3f& direction) const;
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

    float spread_;
    std::unordered_map<const Shape*, MeshEdges> meshes_;
};

} // namespace penumbra
