// The velocity field of warped-area reparameterization in material path space (diff/war/velocity_field.h, paper 000
// Algorithm 1) on synthetic auxiliary samples: the weight's gradient against central differences, a uniform
// discontinuity velocity reproduced exactly with zero divergence, and the divergence of a linear field.
#include "diff/war/velocity_field.h"

#include <gtest/gtest.h>

#include <random>

using namespace penumbra;

namespace {

// The tangent of v along θ (one parameter, direction 1).
float tangent(const Var& v, const std::vector<float>& t) { return v.id < 0 ? 0.f : t[v.id]; }

// n = +z, p = 0 and the neighbour y on the normal at distance r0 (so r0 does not vary in the tangent plane).
const Vec3f n(0.f, 0.f, 1.f);
constexpr float R0 = 2.f;
const Vec3f p_minus_y(0.f, 0.f, -R0);

// Auxiliary samples q − p ~ N(0, s² I) in the tangent plane, in antithetic pairs, with velocities V(q) (as
// tangents of θ) and boundary values B(q).
template <typename Field, typename Boundary>
std::vector<WarAuxiliary> synthetic(int count, float s, const Var& theta, Field&& V, Boundary&& B,
                                    uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<float> g(0.f, s);
    std::vector<WarAuxiliary> aux;
    while (int(aux.size()) < count) {
        const Vec3f o(g(rng), g(rng), 0.f);
        const float pdf = std::exp(-0.5f * squared_norm(o) / (s * s)) / (2.f * Pi * s * s);
        for (const Vec3f& q : {o, o * -1.f}) {
            WarAuxiliary a;
            a.offset = q;
            a.pdf = pdf;
            a.boundary = B(q);
            a.velocity = Vec3<Var>(V(q)) * theta;
            aux.push_back(a);
        }
    }
    return aux;
}

TEST(WarField, WeightGradientMatchesFiniteDifferences) {
    WarFieldOptions o;
    const Vec3f q(0.013f, -0.007f, 0.002f), p_y(0.3f, 0.4f, -1.9f);
    const WarWeight w = war_weight(q, p_y, 0.2f, o);
    constexpr float h = 1e-4f;
    for (int k = 0; k < 3; ++k) {
        Vec3f e(0.f);
        e[k] = h;
        // p + e: q − p shrinks by e, p − y grows by e.
        const double fd =
            (war_weight(q - e, p_y + e, 0.2f, o).w - war_weight(q + e, p_y - e, 0.2f, o).w) / (2 * h);
        EXPECT_NEAR(w.gradient[k], fd, 2e-3 * std::abs(fd) + 1e-3) << k;
    }
}

// v_dis = V everywhere: v = P V (the tangent part) and ∇·v = 0, whatever the weights (Σ coefficients = 1 and
// Σ divergence coefficients = 0 hold sample by sample).
TEST(WarField, UniformVelocityReproducesItself) {
    Tape& tape = Tape::current();
    tape.clear();
    const Var theta = Var::parameter(0.f, 0);
    const Vec3f V(0.3f, -1.2f, 0.5f);
    WarFieldOptions o;
    const auto aux = synthetic(
        16, 0.012f * R0, theta, [&](const Vec3f&) { return V; },
        [](const Vec3f& q) { return q.x > 0.f ? 0.05f : 1.f; }, 7);
    const WarEstimate e = estimate_war_field(n, p_minus_y, aux, o);
    std::vector<float> t;
    const float direction = 1.f;
    tape.forward(&direction, t);
    EXPECT_NEAR(tangent(e.velocity.x, t), V.x, 1e-5);
    EXPECT_NEAR(tangent(e.velocity.y, t), V.y, 1e-5);
    EXPECT_NEAR(tangent(e.velocity.z, t), 0.f, 1e-6); // projected on the tangent plane
    EXPECT_NEAR(tangent(e.divergence, t), 0.f, 1e-4);
    tape.clear();
}

// v_dis(q) = A (q − p) + c with B constant: the kernel is symmetric, so v(p) = c and ∇·v = tr(A) (in
// expectation; the antithetic pairs make v exact). Consistent estimator: checked with many samples.
TEST(WarField, DivergenceOfALinearField) {
    Tape& tape = Tape::current();
    tape.clear();
    const Var theta = Var::parameter(0.f, 0);
    const float a[2][2] = {{0.7f, -0.4f}, {0.9f, 1.6f}};
    const Vec3f c(0.2f, 0.1f, 0.f);
    WarFieldOptions o;
    const auto field = [&](const Vec3f& q) {
        return Vec3f(a[0][0] * q.x + a[0][1] * q.y, a[1][0] * q.x + a[1][1] * q.y, 0.f) + c;
    };
    const auto aux = synthetic(
        20000, 0.012f * R0, theta, field, [](const Vec3f&) { return 1.f; }, 11);
    const WarEstimate e = estimate_war_field(n, p_minus_y, aux, o);
    std::vector<float> t;
    const float direction = 1.f;
    tape.forward(&direction, t);
    EXPECT_NEAR(tangent(e.velocity.x, t), c.x, 1e-4);
    EXPECT_NEAR(tangent(e.velocity.y, t), c.y, 1e-4);
    const float trace = a[0][0] + a[1][1];
    EXPECT_NEAR(tangent(e.divergence, t), trace, 0.03 * trace);
    tape.clear();
}

} // namespace
