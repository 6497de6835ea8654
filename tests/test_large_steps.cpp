// The large-steps parameterization (optim/large_steps.h, Nicolet et al. 2021): the operator I + λL on small
// meshes where it is known by hand, the solve inverting it on a real mesh, the chain rule of the latent
// gradient against central finite differences of a quadratic, and the errors.
#include "core/error.h"
#include "optim/adam.h"
#include "optim/large_steps.h"
#include "scene/mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>

using namespace penumbra;

namespace {

uint64_t test_seed() {
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    return env ? std::strtoull(env, nullptr, 10) : 0;
}

std::vector<double> random_values(size_t n, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> v(n);
    for (double& x : v)
        x = u(rng);
    return v;
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
    double d = 0;
    for (size_t k = 0; k < a.size(); ++k)
        d = std::max(d, std::abs(a[k] - b[k]));
    return d;
}

TriangleMesh sphere() { return make_sphere_mesh(Vec3f(0.f), 1.f, 24, 48); }

} // namespace

// A tetrahedron: every vertex has degree 3 and every pair is an edge, so L = 4I − 11ᵀ and
// (I + λL) x = (1 + 4λ) x − λ Σ_j x_j per coordinate.
TEST(LargeSteps, OperatorOfATetrahedron) {
    const std::vector<uint32_t> tet = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
    const double lambda = 2.5;
    const LargeSteps ls(tet, 4, lambda);
    std::mt19937_64 rng(test_seed());
    const std::vector<double> x = random_values(12, rng);
    const std::vector<double> u = ls.to_latent(x);
    for (int c = 0; c < 3; ++c) {
        const double sum = x[size_t(c)] + x[size_t(3 + c)] + x[size_t(6 + c)] + x[size_t(9 + c)];
        for (int i = 0; i < 4; ++i)
            EXPECT_NEAR(u[size_t(3 * i + c)], (1 + 4 * lambda) * x[size_t(3 * i + c)] - lambda * sum, 1e-12);
    }
    // Constants are in L's null space: (I + λL) 1 = 1, so a translation passes through unchanged.
    const std::vector<double> ones(12, 1.0);
    EXPECT_LT(max_abs_difference(ls.from_latent(ones), ones), 1e-12);
}

// On a 1,225-vertex UV sphere (duplicated seam and pole vertices, some in no triangle), the solve inverts the
// operator both ways to rounding: from_latent(to_latent(x)) = x and to_latent(from_latent(u)) = u.
TEST(LargeSteps, SolveInvertsTheOperator) {
    const TriangleMesh mesh = sphere();
    const int n = int(mesh.vertex_count());
    std::mt19937_64 rng(test_seed() + 1);
    for (double lambda : {0.5, 19.0, 500.0}) {
        const LargeSteps ls(mesh.indices, n, lambda);
        const std::vector<double> x = random_values(3 * size_t(n), rng),
                                  u = random_values(3 * size_t(n), rng);
        // Conditioning of I + λL is ≤ 1 + λ · 2 max deg; double precision leaves ~1e-16 × that.
        EXPECT_LT(max_abs_difference(ls.from_latent(ls.to_latent(x)), x), 1e-9) << "lambda " << lambda;
        EXPECT_LT(max_abs_difference(ls.to_latent(ls.from_latent(u)), u), 1e-9) << "lambda " << lambda;
    }
}

// The chain rule: for f(x) = ½ xᵀ A x + bᵀ x with A diagonal and positive, g(u) = f(x(u)), x = (I + λL)⁻¹ u,
// is quadratic in u, so central differences are exact up to rounding: (g(u + h e) − g(u − h e)) / 2h must
// equal ⟨latent_gradient(∇f(x)), e⟩ along random directions e (and unit coordinate directions).
TEST(LargeSteps, LatentGradientMatchesFiniteDifferencesOfAQuadratic) {
    const TriangleMesh mesh = sphere();
    const int n = int(mesh.vertex_count());
    const LargeSteps ls(mesh.indices, n, 19.0);
    std::mt19937_64 rng(test_seed() + 2);
    const std::vector<double> a = [&] {
        std::vector<double> v = random_values(3 * size_t(n), rng);
        for (double& x : v)
            x = 1.5 + x; // in [0.5, 2.5]
        return v;
    }();
    const std::vector<double> b = random_values(3 * size_t(n), rng);
    auto f = [&](const std::vector<double>& x) {
        double s = 0;
        for (size_t k = 0; k < x.size(); ++k)
            s += 0.5 * a[k] * x[k] * x[k] + b[k] * x[k];
        return s;
    };
    const std::vector<double> u = random_values(3 * size_t(n), rng);
    const std::vector<double> x = ls.from_latent(u);
    std::vector<double> grad_x(x.size());
    for (size_t k = 0; k < x.size(); ++k)
        grad_x[k] = a[k] * x[k] + b[k];
    const std::vector<double> grad_u = ls.latent_gradient(grad_x);

    std::vector<std::vector<double>> directions = {random_values(u.size(), rng),
                                                   random_values(u.size(), rng)};
    for (size_t k : {size_t(0), size_t(3 * 17 + 1), u.size() - 1}) {
        directions.emplace_back(u.size(), 0.0);
        directions.back()[k] = 1.0;
    }
    const double h = 1e-3;
    for (const std::vector<double>& e : directions) {
        std::vector<double> up = u, um = u;
        double predicted = 0;
        for (size_t k = 0; k < u.size(); ++k) {
            up[k] += h * e[k], um[k] -= h * e[k];
            predicted += grad_u[k] * e[k];
        }
        const double fd = (f(ls.from_latent(up)) - f(ls.from_latent(um))) / (2 * h);
        // Exact for a quadratic; the bound is the rounding of f (~1e-16 × Σ|terms| ≈ 1e-13) divided by 2h.
        EXPECT_NEAR(fd, predicted, 1e-8 + 1e-8 * std::abs(predicted));
    }
    // Negative control: the untransformed gradient dL/dx is not dL/du.
    double dot_wrong = 0, dot_right = 0;
    for (size_t k = 0; k < u.size(); ++k)
        dot_wrong += grad_x[k] * directions[0][k], dot_right += grad_u[k] * directions[0][k];
    EXPECT_GT(std::abs(dot_wrong - dot_right), 1e-3 * std::abs(dot_right));
}

// Uniform Adam (one second moment per group, Nicolet et al. 2021 §5): the first step is −lr g / max|g|, the
// gradient's direction, where per-scalar Adam steps −lr sign(g); a group that is not uniform is unchanged.
TEST(LargeSteps, UniformAdamKeepsTheGradientDirection) {
    const std::vector<double> g = {0.5, -2.0, 0.25, 1.0};
    AdamGroup uniform{"u", 0, 2, 0.1};
    uniform.uniform = true;
    Adam adam({uniform, AdamGroup{"s", 2, 2, 0.1}}, 4);
    std::vector<double> x(4, 0.0);
    adam.step(x, g);
    // Bias-corrected moments after one step: m̂ = g, v̂ = g²; ε = 1e-8 shifts a step by ≤ lr ε / 0.25 = 4e-9.
    EXPECT_NEAR(x[0], -0.1 * 0.5 / 2.0, 1e-8);
    EXPECT_NEAR(x[1], -0.1 * -2.0 / 2.0, 1e-8);
    EXPECT_NEAR(x[2], -0.1, 1e-8);
    EXPECT_NEAR(x[3], -0.1, 1e-8);
}

TEST(LargeSteps, Errors) {
    const std::vector<uint32_t> tri = {0, 1, 2};
    EXPECT_THROW(LargeSteps(tri, 3, 0.0), Error);
    EXPECT_THROW(LargeSteps(tri, 2, 1.0), Error); // index out of range
    // A vertex in no triangle keeps x = u.
    const std::vector<double> u = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    const std::vector<double> x = LargeSteps(tri, 4, 1.0).from_latent(u);
    for (int k = 9; k < 12; ++k)
        EXPECT_NEAR(x[size_t(k)], u[size_t(k)], 1e-12);
    const LargeSteps ls(tri, 3, 1.0);
    EXPECT_THROW(ls.from_latent(std::vector<double>(8)), Error); // not 3 per vertex
}
