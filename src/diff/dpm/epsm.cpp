#include "diff/dpm/epsm.h"

#include "core/error.h"
#include "diff/material_form.h"
#include "scene/shape_interaction.h"

#include <Eigen/LU>

#include <string>

namespace penumbra {

namespace {

using Kind = EpsmConstraint::Kind;

// The vertices at barycentrics `bary` (Var: leaves, constants or solved values) and θ.
EpsmPath evaluate(const Parameters& params, const std::vector<EpsmVertex>& vertices,
                  const std::vector<Vec2<Var>>& bary) {
    EpsmPath out;
    out.x.resize(vertices.size());
    out.si.resize(vertices.size());
    for (size_t i = 0; i < vertices.size(); ++i) {
        const EpsmVertex& v = vertices[i];
        if (v.kind == EpsmVertex::Kind::Surface) {
            out.si[i] = surface_interaction<Var>(*v.shape, v.prim, bary[i], MovedVertices{*v.shape, params.motions(v.shape)});
            out.x[i] = out.si[i].p;
            continue;
        }
        // A point moves with the translations of its sensor or light (rotations turn it about itself).
        out.x[i] = v.kind == EpsmVertex::Kind::Camera ? camera_position(params, v.p)
                   : v.emitter                        ? light_position(params, *v.emitter, v.p)
                                                      : Vec3<Var>(v.p);
    }
    return out;
}

// C_k(X, θ): the two components of constraint k (Eqs. 3–5, 24).
Vec2<Var> constraint_value(const Parameters& params, const std::vector<EpsmVertex>& vertices, const EpsmPath& path,
                           const std::vector<Vec2<Var>>& bary, const EpsmConstraint& c) {
    const Vec3<Var>& xi = path.x[size_t(c.vertex)];
    const bool surface = vertices[size_t(c.vertex)].kind == EpsmVertex::Kind::Surface;
    const auto local = [&](const Vec3<Var>& w) {
        if (surface) {
            const Frame<Var>& f = path.si[size_t(c.vertex)].sh_frame;
            return Vec2<Var>(dot(w, f.s), dot(w, f.t));
        }
        // A point's frame: fixed in the world, built around the reference direction.
        // (For the eye, in the moving camera's frame.)
        const Vec3<Var> y =
            vertices[size_t(c.vertex)].kind == EpsmVertex::Kind::Camera ? direction_to_reference_camera(params, w) : w;
        const Frame3f f(normalize(Vec3f(w.x.v, w.y.v, w.z.v)));
        return Vec2<Var>(dot(y, Vec3<Var>(f.s)), dot(y, Vec3<Var>(f.t)));
    };
    switch (c.kind) {
    case Kind::HalfVector: {
        // Eq. 3 with the generalized half vector of a refraction (η_a ω_a + η_b ω_b ∥ n).
        const Vec3<Var> wa = normalize(path.x[size_t(c.a)] - xi), wb = normalize(path.x[size_t(c.b)] - xi);
        return local(normalize(wa + wb * Var(c.eta)));
    }
    case Kind::FixedPosition: return bary[size_t(c.vertex)]; // Eq. 4
    case Kind::FixedDirection: return local(normalize(path.x[size_t(c.a)] - xi)); // Eq. 5
    case Kind::VertexMerge: return local(path.x[size_t(c.a)] - xi);          // Eq. 24
    }
    return {};
}

void check_constraints(const std::vector<EpsmVertex>& vertices, const std::vector<EpsmConstraint>& constraints,
                       size_t unknowns) {
    const auto fail = [](size_t k, const std::string& why) {
        throw Error("EPSM constraint " + std::to_string(k) + ": " + why);
    };
    if (constraints.size() != unknowns)
        throw Error("EPSM: " + std::to_string(constraints.size()) + " constraints for " + std::to_string(unknowns) +
                    " vertices on surfaces (one 2-D constraint per moving vertex)");
    const auto valid = [&](int i) { return i >= 0 && size_t(i) < vertices.size(); };
    for (size_t k = 0; k < constraints.size(); ++k) {
        const EpsmConstraint& c = constraints[k];
        if (!valid(c.vertex)) fail(k, "vertex index out of range");
        const bool surface = vertices[size_t(c.vertex)].kind == EpsmVertex::Kind::Surface;
        switch (c.kind) {
        case Kind::HalfVector:
            if (!surface || !valid(c.a) || !valid(c.b) || c.a == c.vertex || c.b == c.vertex)
                fail(k, "a half vector needs a surface vertex and two other vertices");
            if (!(c.eta > 0.f)) fail(k, "the relative index of refraction must be positive");
            break;
        case Kind::FixedPosition:
            if (!surface) fail(k, "a fixed position is a surface vertex's (points are fixed already)");
            break;
        case Kind::FixedDirection:
            if (!valid(c.a) || c.a == c.vertex) fail(k, "a fixed direction needs another vertex to point to");
            break;
        case Kind::VertexMerge:
            if (!surface || !valid(c.a) || c.a == c.vertex)
                fail(k, "vertex merging needs a surface vertex (x_s) and the photon's vertex");
            break;
        }
    }
}

// C(X, θ) of every constraint, two components each.
std::vector<Var> constraint_values(const Parameters& params, const std::vector<EpsmVertex>& vertices,
                                   const EpsmPath& path, const std::vector<Vec2<Var>>& bary,
                                   const std::vector<EpsmConstraint>& constraints) {
    std::vector<Var> c(2 * constraints.size());
    for (size_t k = 0; k < constraints.size(); ++k) {
        const Vec2<Var> ck = constraint_value(params, vertices, path, bary, constraints[k]);
        c[2 * k] = ck.x;
        c[2 * k + 1] = ck.y;
    }
    return c;
}

// Tangents of the nodes recorded since `first` for a unit direction on leaf parameter `param` (nodes before
// `first` cannot depend on leaves recorded after it).
void sweep(const Tape& tape, size_t first, size_t first_leaf, int param, std::vector<float>& tangent) {
    const auto& nodes = tape.nodes();
    tangent.assign(nodes.size() - first, 0.f);
    for (size_t l = first_leaf; l < tape.leaves().size(); ++l)
        if (tape.leaves()[l].param == param) tangent[size_t(tape.leaves()[l].node) - first] = 1.f;
    const auto at = [&](int32_t id) { return id >= int32_t(first) ? tangent[size_t(id) - first] : 0.f; };
    for (size_t i = first; i < nodes.size(); ++i) {
        const Tape::Node& n = nodes[i];
        if (n.a < 0) continue;
        tangent[i - first] = n.da * at(n.a) + (n.b >= 0 ? n.db * at(n.b) : 0.f);
    }
}

} // namespace

bool solve_epsm(const Parameters& params, const std::vector<EpsmVertex>& vertices,
                const std::vector<EpsmConstraint>& constraints, EpsmPath& out) {
    std::vector<int> unknown(vertices.size(), -1);
    int m = 0;
    for (size_t i = 0; i < vertices.size(); ++i)
        if (vertices[i].kind == EpsmVertex::Kind::Surface) {
            if (!vertices[i].shape) throw Error("EPSM: surface vertex " + std::to_string(i) + " has no shape");
            unknown[i] = m++;
        }
    check_constraints(vertices, constraints, size_t(m));
    std::vector<Vec2<Var>> bary(vertices.size(), Vec2<Var>(Var(0.f)));
    for (size_t i = 0; i < vertices.size(); ++i) bary[i] = Vec2<Var>(vertices[i].bary);

    // ∂C/∂X: the constraints with the unknowns as scratch leaves (indices past the tape's leaves), one forward
    // sweep per unknown; then the scratch is dropped.
    Tape& tape = Tape::current();
    const size_t first = tape.size(), first_leaf = tape.leaf_count();
    const int dim = params.tape_dimension();
    std::vector<Vec2<Var>> leaves = bary;
    for (size_t i = 0; i < vertices.size(); ++i)
        if (unknown[i] >= 0)
            leaves[i] = Vec2<Var>(Var::parameter(vertices[i].bary.x, dim + 2 * unknown[i]),
                                  Var::parameter(vertices[i].bary.y, dim + 2 * unknown[i] + 1));
    const std::vector<Var> c =
        constraint_values(params, vertices, evaluate(params, vertices, leaves), leaves, constraints);
    Eigen::MatrixXd A(2 * m, 2 * m);
    std::vector<float> tangent;
    for (int col = 0; col < 2 * m; ++col) {
        sweep(tape, first, first_leaf, dim + col, tangent);
        for (int row = 0; row < 2 * m; ++row) {
            const int32_t id = c[size_t(row)].id;
            A(row, col) = id >= int32_t(first) ? double(tangent[size_t(id) - first]) : 0.0;
        }
    }
    tape.rewind(first, first_leaf);
    if (m == 0) {
        out = evaluate(params, vertices, bary);
        return true;
    }

    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(A);
    const double rcond = lu.rcond();
    if (!(rcond > 1e-6)) return false;
    const Eigen::MatrixXd M = -lu.inverse();

    // C(X0, θ): its tangent is ∂C/∂θ. Each unknown u(θ) = u0 + Σ_i M_ji C_i(X0, θ) (Eq. 2, first order).
    const std::vector<Var> ct =
        constraint_values(params, vertices, evaluate(params, vertices, bary), bary, constraints);
    std::vector<Vec2<Var>> solved = bary;
    for (size_t i = 0; i < vertices.size(); ++i) {
        if (unknown[i] < 0) continue;
        Var u[2];
        for (int d = 0; d < 2; ++d) {
            const int j = 2 * unknown[i] + d;
            Var s(0.f);
            for (int k = 0; k < 2 * m; ++k)
                if (!ct[size_t(k)].is_constant() && M(j, k) != 0.0) s += Var(float(M(j, k))) * ct[size_t(k)];
            u[d] = Var(d == 0 ? vertices[i].bary.x : vertices[i].bary.y) + (s - Var(s.v));
        }
        solved[i] = Vec2<Var>(u[0], u[1]);
    }
    out = evaluate(params, vertices, solved);
    out.condition = 1.0 / rcond;
    return true;
}

} // namespace penumbra
