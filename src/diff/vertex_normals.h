// The recomputed vertex normals of a mesh whose `vertex_positions` are differentiated (Mitsuba 3's
// Mesh::parameters_changed recomputes them from the positions, so they move with the vertices around them).
// n(v) = normalize(Σ_f corner_normal(f, v)) depends on the whole one-ring of v; instead of recording that on the
// tape at every hit, each normal is a leaf of the tape with an index past the parameters'
// (Shape::vertex_normal_index(), Parameters::tape_dimension()), and its derivative is chained to the positions
// once per pass: its tangent along the direction before a forward-mode pass (tape_direction), its adjoint back
// to the positions after a reverse-mode pass (chain_vertex_normal_gradient).
#pragma once
#include "core/var.h"
#include "diff/parameters.h"

#include <functional>
#include <vector>

namespace penumbra {

// n(v) of `owner` (a mesh with differentiated positions) on the tape, from leaves of its vertex positions
// (recompute_vertex_normals' formula); its stored normal when the faces around v have no area.
Vec3<Var> recomputed_vertex_normal(const Shape& owner, uint32_t v);

// The direction of a forward-mode pass in the tape's leaves: params.direction(), then the tangent of every
// recomputed vertex normal along it (tape_dimension() values). Evaluated at the current geometry.
std::vector<float> tape_direction(const Parameters& params);

// After a reverse-mode pass into `gradient` (tape_dimension() values): the adjoints of the vertex normals are
// swept back to the vertex positions, and `gradient` is cut to params.dimension().
void chain_vertex_normal_gradient(const Parameters& params, std::vector<double>& gradient);

// Adds the threads' reverse-mode sums (each tape_dimension() values; `gradient_of(thread)` when a thread's state
// holds more than its sum) to `gradient` (dimension() values), the vertex normals' adjoints chained to the
// positions.
template <typename Threads, typename GradientOf = std::identity>
void add_chained_gradient(const Parameters& params, const Threads& threads, std::vector<double>& gradient,
                          GradientOf gradient_of = {}) {
    std::vector<double> sum(size_t(params.tape_dimension()), 0.0);
    for (const auto& thread : threads) {
        const std::vector<double>& g = std::invoke(gradient_of, thread);
        for (size_t k = 0; k < sum.size(); ++k) sum[k] += g[k];
    }
    chain_vertex_normal_gradient(params, sum);
    for (size_t k = 0; k < sum.size(); ++k) gradient[k] += sum[k];
}

} // namespace penumbra
