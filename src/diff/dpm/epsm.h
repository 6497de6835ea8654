// Extended path space manifolds (paper 003 §3.1; Xing et al. 2023): the vertices of a path are defined
// implicitly by one 2-D constraint per moving vertex, C(X, θ) = 0 (Eq. 1), and follow the scene parameters θ
// with the geometric derivatives dX/dθ = −(∂C/∂X)⁻¹ ∂C/∂θ (Eq. 2). The constraint types are
//   half vector     the generalized half vector of x_i's two path directions fixed in x_i's shading frame
//                   (Eq. 3): h ∝ ω_a + η ω_b, with η = η_b / η_a the relative index across a refraction
//                   (1 for reflection), so a specular vertex keeps reflecting (refracting) its neighbours;
//   fixed position  x_i's material point (barycentrics) fixed (Eq. 4);
//   fixed direction the direction from x_i to its neighbour fixed in x_i's frame (Eq. 5): for the eye, in
//                   the camera's frame, for a point light in the world's;
//   vertex merging  the photon x*_s fixed in the local frame of the density-estimation vertex x_s (Eq. 24).
//
// The unknowns are the barycentrics (b1, b2) of every vertex on a mesh; each constraint determines one of
// them (their counts must match). solve_epsm puts the solution on the AD tape (core/var.h): each unknown
// becomes u(θ) = u0 + Σ_i M_{ji} C_i(X0, θ), M = −(∂C/∂X)⁻¹ at θ0, a linear combination of the constraints'
// θ-dependence. Everything evaluated downstream from the returned vertices — contributions (Eq. 14, 23),
// kernels, screen positions (Eq. 7) — then carries Eq. 2's derivatives in forward and in reverse mode, and a
// BSDF term that the constraints hold constant (e.g. D(h) under a half-vector constraint, §4.2.2's
// decomposition) has zero derivative there by construction.
#pragma once
#include "core/var.h"
#include "diff/parameters.h"
#include "scene/interaction.h"

#include <vector>

namespace penumbra {

class Emitter;
class Shape;

// A path vertex: a material point on a mesh (its barycentrics are unknowns), the camera's center of projection
// (moves with the sensor's motions), or a point light's position (moves with the emitter's motions).
struct EpsmVertex {
    enum class Kind { Surface, Camera, Point };
    Kind kind = Kind::Surface;
    const Shape* shape = nullptr; // Surface
    uint32_t prim = 0;            // Surface
    Vec2f bary;                   // Surface: the material point at θ0
    Vec3f p;                      // Camera, Point: the position at θ0
    const Emitter* emitter = nullptr; // Point (optional): whose motions move it

    static EpsmVertex surface(const SurfaceInteraction3f& si) {
        EpsmVertex v;
        v.shape = si.shape;
        v.prim = si.prim_index;
        v.bary = si.bary;
        v.p = si.p;
        return v;
    }
    static EpsmVertex camera(const Vec3f& p) {
        EpsmVertex v;
        v.kind = Kind::Camera;
        v.p = p;
        return v;
    }
    static EpsmVertex point(const Vec3f& p, const Emitter* emitter = nullptr) {
        EpsmVertex v;
        v.kind = Kind::Point;
        v.p = p;
        v.emitter = emitter;
        return v;
    }
};

// One 2-D constraint of the path, written at `vertex` (an index into the path's vertices).
struct EpsmConstraint {
    enum class Kind { HalfVector, FixedPosition, FixedDirection, VertexMerge };
    Kind kind;
    int vertex;     // x_i
    int a = -1;     // HalfVector: one neighbour; FixedDirection: the vertex the direction points to;
                    // VertexMerge: the photon x*_s
    int b = -1;     // HalfVector: the other neighbour
    float eta = 1.f; // HalfVector: η_b / η_a (1: reflection)

    static EpsmConstraint half_vector(int i, int a, int b, float eta = 1.f) { return {Kind::HalfVector, i, a, b, eta}; }
    static EpsmConstraint fixed_position(int i) { return {Kind::FixedPosition, i}; }
    static EpsmConstraint fixed_direction(int i, int toward) { return {Kind::FixedDirection, i, toward}; }
    static EpsmConstraint vertex_merge(int density_vertex, int photon) {
        return {Kind::VertexMerge, density_vertex, photon};
    }
};

// The path on the tape: every vertex x_i(θ) (and, for mesh vertices, its interaction) with Eq. 2's
// derivatives.
struct EpsmPath {
    std::vector<Vec3<Var>> x;
    std::vector<SurfaceInteraction<Var>> si; // valid for Surface vertices only
    double condition = 0.0;                  // 1-norm condition estimate of ∂C/∂X
};

// Solves Eq. 2 for the path and records it on the current tape. Throws Error when the constraints do not
// match the unknowns (a count or an index is wrong); returns false when ∂C/∂X is singular (a degenerate
// configuration: the implicit function does not exist there), leaving the tape as it was.
bool solve_epsm(const Parameters& params, const std::vector<EpsmVertex>& vertices,
                const std::vector<EpsmConstraint>& constraints, EpsmPath& out);

} // namespace penumbra
