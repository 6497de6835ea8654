// The shading terminator seen from the camera: inside a triangle shaded with interpolated vertex normals, the
// curve where the shading normal turns away from the camera, G(b) = n(b) · (c − x(b)) = 0, with n(b) and x(b)
// the barycentric interpolations of the vertex normals and positions and c the camera's center. BSDFs that
// require the incident direction in the shading frame's upper hemisphere (Mitsuba 3's cos θ_i > 0 test, e.g.
// diffuse) make the radiance seen jump there, and the curve moves with the vertices: a discontinuity of the
// image inside triangles that the edges do not cover (diff/psdr/primary_boundary.cpp samples it).
// G is quadratic in the barycentrics: with b0 = 1 − b1 − b2, G = Σ_ij b_i b_j n_i · (c − p_j).
#pragma once
#include "scene/mesh.h"

namespace penumbra {

// Whether G changes sign on triangle `prim` (conservative: some n_i · (c − p_j) of each sign).
bool crosses_shading_terminator(const TriangleMesh& mesh, uint32_t prim, const Vec3f& eye);

// A point of the curve: barycentrics (b1, b2) and the partials of G̃ = G / |n(b)| (the sign of the cosine
// between the unit shading normal and the direction to the camera, scaled by the distance to it).
struct TerminatorPoint {
    Vec2f bary;
    float dG_db1, dG_db2;
};

// The points of the curve on a line of sweep `sweep` (0, 1 or 2) at u in [0, 1]: the line b_sweep = u, where
// b0 = 1 − b1 − b2 (0, 1 or 2 points); returns how many. Each sweep's lines cover the triangle once with unit
// Jacobian, so ∫ δ(G̃(b)) h(b) db = ∫ du Σ_points h / |∂G̃/∂w| for w along the lines: ∂G̃/∂b2 (sweep 1),
// ∂G̃/∂b1 (sweep 2), ∂G̃/∂b1 − ∂G̃/∂b2 (sweep 0).
int shading_terminator_points(const TriangleMesh& mesh, uint32_t prim, const Vec3f& eye, int sweep, float u,
                              TerminatorPoint out[2]);

} // namespace penumbra
