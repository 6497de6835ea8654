#include "optim/large_steps.h"

#include "core/error.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <string>
#include <utility>

namespace penumbra {

struct LargeSteps::Factorization {
    Eigen::SparseMatrix<double> m; // I + λL
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> cholesky;
};

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

void check_size(std::span<const double> v, int vertex_count, const char* what) {
    if (v.size() != size_t(vertex_count) * 3)
        throw Error(std::string("large steps: ") + what + " has " + std::to_string(v.size()) +
                    " values; expected 3 per vertex (" + std::to_string(3 * size_t(vertex_count)) + ")");
}

} // namespace

// I + λL with the uniform Laplacian L = D − A of the mesh's edge graph (Nicolet et al. 2021, §4.2).
LargeSteps::LargeSteps(std::span<const uint32_t> indices, int vertex_count, double lambda)
    : factorization_(std::make_unique<Factorization>()), vertex_count_(vertex_count), lambda_(lambda) {
    if (!(lambda > 0.0)) throw Error("large steps: lambda must be positive, got " + std::to_string(lambda));
    if (indices.size() % 3 != 0 || vertex_count <= 0)
        throw Error("large steps: expected a triangle mesh (3 indices per triangle) with vertices");
    // Each undirected edge once (a shared edge appears in two triangles).
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    edges.reserve(indices.size());
    for (size_t t = 0; t < indices.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = indices[t + size_t(k)], b = indices[t + size_t(k + 1) % 3];
            if (a >= uint32_t(vertex_count) || b >= uint32_t(vertex_count))
                throw Error("large steps: triangle " + std::to_string(t / 3) +
                            " has a vertex index out of range");
            if (a != b) edges.emplace_back(std::min(a, b), std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

    std::vector<double> degree(size_t(vertex_count), 0.0);
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(2 * edges.size() + size_t(vertex_count));
    for (const auto& [a, b] : edges) {
        degree[a] += 1.0, degree[b] += 1.0;
        entries.emplace_back(int(a), int(b), -lambda);
        entries.emplace_back(int(b), int(a), -lambda);
    }
    // A vertex in no triangle has an identity row: it keeps x = u.
    for (int i = 0; i < vertex_count; ++i)
        entries.emplace_back(i, i, 1.0 + lambda * degree[size_t(i)]);
    Eigen::SparseMatrix<double>& m = factorization_->m;
    m.resize(vertex_count, vertex_count);
    m.setFromTriplets(entries.begin(), entries.end());
    factorization_->cholesky.compute(m);
    if (factorization_->cholesky.info() != Eigen::Success)
        throw Error("large steps: the Cholesky factorization of I + lambda L failed");
}

LargeSteps::~LargeSteps() = default;

std::vector<double> LargeSteps::to_latent(std::span<const double> x) const {
    check_size(x, vertex_count_, "x");
    std::vector<double> u(x.size());
    Eigen::Map<const RowMatrix> xm(x.data(), vertex_count_, 3);
    Eigen::Map<RowMatrix> um(u.data(), vertex_count_, 3);
    um = factorization_->m * xm;
    return u;
}

std::vector<double> LargeSteps::from_latent(std::span<const double> u) const {
    check_size(u, vertex_count_, "u");
    std::vector<double> x(u.size());
    Eigen::Map<const RowMatrix> um(u.data(), vertex_count_, 3);
    Eigen::Map<RowMatrix> xm(x.data(), vertex_count_, 3);
    xm = factorization_->cholesky.solve(Eigen::MatrixXd(um));
    return x;
}

} // namespace penumbra
