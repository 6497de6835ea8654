#include "diff/vertex_normals.h"

#include "scene/mesh.h"

#include <tbb/parallel_for.h>

namespace penumbra {

Vec3<Var> recomputed_vertex_normal(const Shape& owner, uint32_t v) {
    const int base = owner.vertex_param_index;
    const auto at = [&](uint32_t w) {
        const Vec3f g = owner.mesh.positions[w];
        return Vec3<Var>(Var::parameter(g.x, base + 3 * int(w)), Var::parameter(g.y, base + 3 * int(w) + 1),
                         Var::parameter(g.z, base + 3 * int(w) + 2));
    };
    Vec3<Var> sum(Var(0.f));
    const auto [first, last] = owner.faces_around(v);
    for (const uint32_t* f = first; f != last; ++f) {
        const uint32_t* i = &owner.mesh.indices[3 * size_t(*f)];
        const Vec3<Var> p[3] = {at(i[0]), at(i[1]), at(i[2])};
        sum += corner_normal(p, i[0] == v ? 0 : i[1] == v ? 1 : 2);
    }
    if (!(norm(sum).v > 0.f)) return Vec3<Var>(owner.mesh.normals[v]);
    return normalize(sum);
}

namespace {

// Runs f(n, tape) for n(v) recorded on this thread's tape, then drops what was recorded.
template <typename F> void with_recorded_normal(const Shape& shape, uint32_t v, const F& f) {
    Tape& tape = Tape::current();
    const size_t nodes = tape.size(), leaves = tape.leaf_count();
    f(recomputed_vertex_normal(shape, v), tape);
    tape.rewind(nodes, leaves);
}

} // namespace

std::vector<float> tape_direction(const Parameters& params) {
    std::vector<float> direction = params.direction();
    direction.resize(size_t(params.tape_dimension()), 0.f);
    for (const Shape* shape : params.normal_leaf_shapes()) {
        const float* d = params.direction().data() + shape->vertex_param_index;
        float* out = direction.data() + shape->vertex_normal_param_index;
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, uint32_t(shape->mesh.positions.size()), 1024),
                          [&](const tbb::blocked_range<uint32_t>& r) {
            std::vector<float> tangent;
            for (uint32_t v = r.begin(); v < r.end(); ++v) {
                // n(v) moves only when a vertex of its one-ring does.
                bool moves = false;
                const auto [first, last] = shape->faces_around(v);
                for (const uint32_t* f = first; f != last && !moves; ++f)
                    for (int k = 0; k < 9 && !moves; ++k)
                        moves = d[3 * size_t(shape->mesh.indices[3 * size_t(*f) + size_t(k / 3)]) + size_t(k % 3)] != 0.f;
                if (!moves) continue;
                with_recorded_normal(*shape, v, [&](const Vec3<Var>& n, Tape& tape) {
                    tape.forward(direction.data(), tangent);
                    for (int k = 0; k < 3; ++k) out[3 * v + uint32_t(k)] = n[k].id >= 0 ? tangent[size_t(n[k].id)] : 0.f;
                });
            }
        });
    }
    return direction;
}

void chain_vertex_normal_gradient(const Parameters& params, std::vector<double>& gradient) {
    std::vector<std::pair<int32_t, float>> seeds(3);
    std::vector<float> scratch;
    for (const Shape* shape : params.normal_leaf_shapes())
        for (uint32_t v = 0; v < uint32_t(shape->mesh.positions.size()); ++v) {
            const double* adjoint = gradient.data() + shape->vertex_normal_param_index + 3 * size_t(v);
            if (adjoint[0] == 0.0 && adjoint[1] == 0.0 && adjoint[2] == 0.0) continue;
            with_recorded_normal(*shape, v, [&](const Vec3<Var>& n, Tape& tape) {
                for (int k = 0; k < 3; ++k) seeds[size_t(k)] = {n[k].id, float(adjoint[k])};
                tape.backward(seeds, gradient.data(), scratch);
            });
        }
    gradient.resize(size_t(params.dimension()));
}

} // namespace penumbra
