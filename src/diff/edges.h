// Mesh edges that can carry a visibility discontinuity (paper 001 §5.2; Zhang et al. 2020): boundary edges
// (one adjacent face) and edges whose two faces are not coplanar. Flat interior edges are excluded.
#pragma once
#include "scene/shape.h"

#include <vector>

namespace penumbra {

struct Edge {
    uint32_t v0, v1;   // vertex indices
    int32_t f0, f1;    // adjacent faces (f1 = -1 for a boundary edge)
};

// The (unnormalized) geometric normal of face f: (p1 − p0) × (p2 − p0).
Vec3f face_normal(const TriangleMesh& mesh, int32_t f);

// Edges of a mesh, merged by position (meshes often duplicate vertices along uv seams and hard edges).
std::vector<Edge> discontinuity_edges(const TriangleMesh& mesh);

// Whether the edge separates a face turned toward `eye` from one turned away (or is a boundary edge).
bool is_silhouette(const TriangleMesh& mesh, const Edge& e, const Vec3f& eye);
// The same for a parallel projection looking along `forward`.
bool is_silhouette_parallel(const TriangleMesh& mesh, const Edge& e, const Vec3f& forward);

} // namespace penumbra
