// Implicit edges of a scene (paper 004 §5.5): the curves where two triangles that share no vertex cross, e.g.
// where an object is sunk into a floor or leaves of a foliage mesh pierce one another. They run through
// triangle interiors, so no mesh edge marks them, yet the surface seen from a point changes there: a
// visibility discontinuity that the per-vertex boundary test cannot see.
//
// Found once: an Embree BVH–BVH collision (rtcCollide over one user geometry per shape, the scene against
// itself) pairs triangles with overlapping bounds, and an exact triangle–triangle test keeps the pairs that
// cross, with the segment along which they do. Each crossing triangle stores its segments. Instanced shape
// groups are not searched (BoundaryTest does not know their shapes either); coplanar overlaps and contacts
// at a single point are not curves and give no segment.
#pragma once
#include "scene/scene.h"

#include <array>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

namespace penumbra {

class MaterialForm;

// A crossing segment, stored in each of its two triangles with the other one.
struct ImplicitSegment {
    Vec3f a, b;
    const Shape* other = nullptr; // the triangle it crosses
    uint32_t other_face = 0;
};

// The segment nearest to a ray in angle, and that angle's sine u = |P (q − x)| / |q − x| at its point q
// nearest to the ray's line (P the projection across the ray).
struct NearestSegment {
    const ImplicitSegment* segment = nullptr; // none: u = 1
    float sine = 1.f;
    Vec3f point;
};

using Triangle3f = std::array<Vec3f, 3>;

// The segment along which two triangles cross (plane clipping: each triangle's crossing of the other's plane
// is an interval of the planes' common line, and the segment is the two intervals' overlap), or nothing when
// they do not, touch at one point, or are coplanar.
std::optional<ImplicitSegment> triangle_intersection(const Triangle3f& t0, const Triangle3f& t1);

// The implicit edge's point c(θ) through c0 as the two crossing faces move with `form` (shape0's face0 and
// shape1's face1): the solution of ⟨n_k(θ), c − p_k(θ)⟩ = 0 for both moving planes and ⟨t, c − c0⟩ = 0, t the
// edge direction n0 × n1 at θ0 (Cramer's rule on the tape). Its tangent ∂θ c is the edge's velocity across
// its own direction, ⟨∂θ c, n_k⟩ = ⟨∂θ p_k, n_k⟩ + ⟨∂θ n_k, p_k − c⟩: the two surfaces' normal speeds fix it
// together, so in general it is neither surface's material velocity.
Vec3<Var> moving_edge_point(const MaterialForm& form, const Shape& shape0, uint32_t face0,
                            const Shape& shape1, uint32_t face1, const Vec3f& c0);

// The point an auxiliary hit p should follow for its direct warp (Eq. 6) when its triangle has implicit
// edges: y(θ) = p + φ (X(p, θ) − p) + (1 − φ) (c(θ) − c0), with X(p, θ) = `material_point`, c the nearest
// edge's moving point through its point c0 nearest to the ray, and φ the implicit-edge factor of B at the
// hit. Where B vanishes at the edge, the direct warp is the edge's velocity (boundary consistency, which the
// harmonic weights alone cannot give there: they average the two sides); away from edges, it is the
// material's, as at the triangle's other boundaries.
Vec3<Var> edge_following_point(const MaterialForm& form, const SurfaceInteraction3f& hit,
                               const NearestSegment& nearest, const Vec3<Var>& material_point, float factor);

class ImplicitEdges {
  public:
    explicit ImplicitEdges(const Scene& scene);

    // The segments inside face `face` of `shape` (empty for a shape that is not in the scene).
    std::span<const ImplicitSegment> segments(const Shape& shape, uint32_t face) const;
    // The segment of the hit's triangle nearest to the ray from `origin` along the unit `direction`.
    NearestSegment nearest(const SurfaceInteraction3f& hit, const Vec3f& origin,
                           const Vec3f& direction) const;
    // The number of crossing triangle pairs (each segment is stored in both triangles).
    size_t pair_count() const { return pairs_; }

  private:
    struct ShapeSegments {
        std::vector<uint32_t> offsets; // face f's segments: segments[offsets[f] .. offsets[f + 1])
        std::vector<ImplicitSegment> segments;
    };
    std::unordered_map<const Shape*, ShapeSegments> shapes_; // only shapes with at least one segment
    size_t pairs_ = 0;
};

} // namespace penumbra
