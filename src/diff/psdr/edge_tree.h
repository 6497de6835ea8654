// The scene's discontinuity edges in a bounding-volume hierarchy, sampled as seen from a receiver x with its
// BSDF (as redner's secondary edge sampling, Li et al. 2018 §5.2): from the root down, a child is taken in
// proportion to its importance
//     I(node) = length(node) · max f(x, ω) |cos| over the directions toward the node / distance,
// the angular length of the edges an outgoing lobe covers (the boundary integral in directions at x is over
// the edges' angular length, dℓ_ω = sin α dℓ / r); at a leaf (one edge) the importance is the edge's own
// angular length times f toward its midpoint, zero if the line from x does not graze it (no discontinuity
// there). The point on the edge is uniform in length. The density of any edge point can be evaluated
// (pdf), for combining the technique with others by multiple importance sampling: it is zero where the
// importance is, which the other techniques must cover.
#pragma once
#include "diff/psdr/boundary_segment.h"

#include <array>
#include <vector>

namespace penumbra {

// The receiver the edges are seen from: a surface point with the direction its light leaves toward (wi of
// the BSDF, world), e.g. toward the camera. For the tree's nodes its lobe f |cos| is modelled as a lobe about
// the mirror direction m with a microfacet-like tail (~θ⁻⁴) plus a cosine term,
//     lobe(d) ≈ P / (1 + θ² / 2w)² + D max(0, d·n),   θ the angle between d and m,
// fitted to the BSDF at m, 0.05 rad from m and at the shading normal.
struct EdgeViewer {
    SurfaceInteraction3f si;                       // si.wi set to the local `toward` direction
    Vec3f mirror, normal;                          // world
    float peak = 0.f, width2 = 0.f, diffuse = 0.f; // P, w (0: a flat lobe), D
    EdgeViewer(const SurfaceInteraction3f& at, const Vec3f& toward);
    // f |cos| toward direction d (world), summed over the channels: the BSDF itself.
    float lobe(const Vec3f& d) const;
    // The model's mean over a cone of directions about `axis` with half-angle `half` (radians): the glossy
    // part blurred by the cone's spread (w + half²/2 for w), the cosine term at the cone's direction nearest
    // the normal.
    float cone_lobe(const Vec3f& axis, float half) const;
};

class EdgeTree {
  public:
    static constexpr int Pieces = 8; // a leaf's edge is weighed in this many equal pieces

    explicit EdgeTree(const SceneEdges& edges);
    // An edge point seen from `viewer` and its density per unit length (0: no edge has importance).
    EdgePoint sample(const EdgeViewer& viewer, float u_edge, float u_point, float& pdf) const;
    // The density per unit length with which sample() draws x_b.
    float pdf(const EdgeViewer& viewer, const EdgePoint& x_b) const;

  private:
    struct Node {
        Vec3f lo, hi;
        Vec3f centroid{0.f}; // of the edges' points, by length
        float spread = 0.f;  // RMS distance of the edges' points from the centroid
        float length = 0.f;
        int32_t left = -1, right = -1; // children; a leaf has left = -1
        int32_t parent = -1;
        uint32_t edge = 0; // a leaf's edge (index into SceneEdges::edges)
    };
    int32_t build(std::vector<uint32_t>& order, size_t begin, size_t end, int32_t parent);
    // A leaf's importance piece by piece (zero if the line from the viewer does not graze the edge), and
    // their sum.
    float leaf_pieces(const EdgeViewer& viewer, const Node& leaf, std::array<float, Pieces>& w) const;
    float importance(const EdgeViewer& viewer, const Node& node) const;
    // The probability of taking `child` at its parent.
    float choice(const EdgeViewer& viewer, const Node& parent, int32_t child) const;

    const SceneEdges& edges_;
    std::vector<Node> nodes_;
    std::vector<int32_t> leaf_of_; // per SceneEdges::edges index: its leaf (-1: not in the tree)
};

} // namespace penumbra
