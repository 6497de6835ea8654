// Warped-area sampling at one vertex (paper 004 §3–4): harmonic weights, boundary test, the warp field and
// its divergence on synthetic fields, and the validation on a hemispherical-type integral with a moving
// occluder: I(θ) = ∫ s(ω) vis(ω, θ) dω over a cone of directions from the origin, with a tessellated square
// occluder at height 1 translating along x in front of a constant environment. dI/dθ is known by 1D
// quadrature of the boundary flux; the estimator ∂θL + ∇·(L V) (Algorithm 1) must match it, and without ∇·V
// it must not.
#include "core/rng.h"
#include "diff/film_sample.h"
#include "diff/was/auxiliary_rays.h"
#include "diff/was/control_variate.h"
#include "mesh_test_util.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

using namespace penumbra;

namespace {

struct Rng {
    PCG32 pcg;
    float next_1d() { return pcg.next_float(); }
    Vec2f next_2d() {
        const float a = pcg.next_float();
        return Vec2f(a, pcg.next_float());
    }
};

// The derivative of y along the enabled parameters' direction (forward mode on the current tape).
float derivative(const Var& y, const std::vector<float>& direction) {
    if (y.is_constant()) return 0.f;
    std::vector<float> tangent;
    Tape::current().forward(direction.data(), tangent);
    return tangent[size_t(y.id)];
}

struct Stats {
    double sum = 0, sum2 = 0;
    long n = 0;
    void add(double x) {
        sum += x;
        sum2 += x * x;
        ++n;
    }
    double mean() const { return sum / double(n); }
    double variance() const { return (sum2 - sum * sum / double(n)) / double(n - 1); }
};

// Mean and standard error from batch means (the batches are independent).
struct BatchMean {
    double mean, se;
};
BatchMean batch_mean(const std::vector<double>& batches) {
    Stats s;
    for (double b : batches)
        s.add(b);
    return {s.mean(), std::sqrt(s.variance() / double(s.n))};
}

} // namespace

TEST(WasHarmonicWeight, GradientMatchesFiniteDifference) {
    const Vec3f omega = normalize(Vec3f(0.2f, 0.1f, 1.f));
    for (float exponent : {1.f, 2.f, 3.f})
        for (float boundary : {0.f, 0.3f, 1.f}) {
            const HarmonicWeight h{1e3f, exponent};
            const Vec3f aux = normalize(omega + Vec3f(0.02f, -0.03f, 0.f));
            const auto at = [&](const Vec3f& o) {
                const double omc = 1.0 - double(dot(o, aux));
                return h(o, aux, float(omc), boundary);
            };
            const HarmonicWeight::Value v = at(omega);
            Vec3f s, t;
            coordinate_system(omega, s, t);
            for (const Vec3f& dir : {s, t}) {
                const float eps = 1e-3f;
                const double fd =
                    (at(normalize(omega + dir * eps)).w - at(normalize(omega - dir * eps)).w) / (2.0 * eps);
                EXPECT_NEAR(dot(v.gradient, dir), fd, 2e-2 * std::abs(fd) + 1e-9)
                    << "exponent " << exponent << " B " << boundary;
            }
        }
}

namespace {

// An n × n grid of quads over [x0, x1] × [y0, y1] at height z, as OBJ text.
std::string grid_obj(int n, float x0, float x1, float y0, float y1, float z) {
    std::ostringstream obj;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            obj << "v " << x0 + (x1 - x0) * float(i) / float(n) << ' ' << y0 + (y1 - y0) * float(j) / float(n)
                << ' ' << z << '\n';
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
            obj << "f " << a << ' ' << b << ' ' << d << "\nf " << a << ' ' << d << ' ' << c << '\n';
        }
    return obj.str();
}

// The occluder [X0, X1] × [Y0, Y1] at height H, seen from the origin over a constant environment.
constexpr float X0 = -0.4f, X1 = 0.6f, Y0 = -0.5f, Y1 = 0.5f, H = 1.f;
constexpr float CosCone = 0.6427876f; // cos 50°: the cone holds the occluder (38°) and the kernels around it

struct OccluderScene {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Parameters> params;
    std::unique_ptr<MaterialForm> form;
    std::unique_ptr<BoundaryTest> boundary;

    explicit OccluderScene(int tessellation) {
        static test::ScratchDir dir("penumbra_was_");
        const std::string name = "occluder" + std::to_string(tessellation) + ".obj";
        const std::string obj = test::write_file(dir.path, name, grid_obj(tessellation, X0, X1, Y0, Y1, H));
        scene =
            load_scene_string("<scene version=\"3.0.0\"><emitter type=\"constant\"><rgb name=\"radiance\" "
                              "value=\"1\"/></emitter><shape type=\"obj\" id=\"occluder\"><string "
                              "name=\"filename\" value=\"" +
                              obj + "\"/><bsdf type=\"diffuse\"/></shape></scene>");
        params = std::make_unique<Parameters>(*scene);
        params->enable({parse_param_selection("occluder.translate=1,0,0")});
        form = std::make_unique<MaterialForm>(*scene, *params, FirstVertex::Auto);
        boundary = std::make_unique<BoundaryTest>(*scene);
    }
};

// The smooth factor s(ω) of the integrand: its ω-gradient makes ⟨∂ω L, V⟩ matter.
template <typename T> T smooth(const Vec3<T>& w) { return T(1.f) + T(0.5f) * w.x + T(0.25f) * w.y; }

// dI/dθ = −d/dθ ∫_{occluder(θ)} s dω = −∫ [G(X1, y) − G(X0, y)] dy with G = s(ω) H / r³ (dω = H / r³ dA),
// by Simpson's rule.
double exact_derivative() {
    const auto g = [](double x, double y) {
        const double r = std::sqrt(x * x + y * y + double(H) * H);
        const Vec3<double> w(x / r, y / r, double(H) / r);
        return smooth(w) * double(H) / (r * r * r);
    };
    const int n = 2000;
    const double h = (double(Y1) - Y0) / n;
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
        const double y = Y0 + i * h, weight = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += weight * (g(X1, y) - g(X0, y));
    }
    return -sum * h / 3.0;
}

// One sample of the derivative estimator: ω uniform in the cone, d/dθ [L(ω_warped) J] / pdf (Algorithm 1
// lines 5–7 with ∂θ L = 0: the emitter is static and the occluder black), or without the divergence Jacobian.
// `reverse`, when given, receives the same derivative by a backward sweep (reverse mode).
double occluder_sample(const OccluderScene& o, const WarpOptions& options, Rng& rng, bool with_divergence,
                       double* reverse = nullptr) {
    Tape::current().clear();
    const Vec2f u = rng.next_2d();
    const float cos_theta = 1.f - u.x * (1.f - CosCone), sin_theta = std::sqrt(1.f - cos_theta * cos_theta);
    const Vec3f omega(sin_theta * std::cos(2.f * Pi * u.y), sin_theta * std::sin(2.f * Pi * u.y), cos_theta);
    const double pdf = 1.0 / (2.0 * double(Pi) * (1.0 - double(CosCone)));
    if (o.scene->intersect(Ray(Vec3f(0.f), omega)).is_valid()) return 0.0; // L = 0 on the occluder
    const WarpVertex x{Interaction3f(), Vec3<Var>(Var(0.f))};
    const WarpEstimate e = estimate_warp_at(*o.scene, *o.form, *o.boundary, x, omega, options, rng);
    const Var f = smooth(e.direction) * (with_divergence ? e.jacobian : Var(1.f));
    if (reverse) {
        double gradient = 0.0;
        std::vector<float> adjoint;
        Tape::current().backward({{f.id, 1.f}}, &gradient, adjoint);
        *reverse = gradient / pdf;
    }
    return double(derivative(f, o.params->direction())) / pdf;
}

struct OccluderRun {
    BatchMean estimate;
    double variance; // per sample
};
OccluderRun run_occluder(const OccluderScene& o, const WarpOptions& options, bool with_divergence,
                         int batches, int per_batch, uint64_t seed) {
    std::vector<double> means;
    Stats all;
    for (int b = 0; b < batches; ++b) {
        Rng rng{PCG32(seed, uint64_t(b))};
        double sum = 0.0;
        for (int i = 0; i < per_batch; ++i) {
            const double v = occluder_sample(o, options, rng, with_divergence);
            sum += v;
            all.add(v);
        }
        means.push_back(sum / per_batch);
    }
    return {batch_mean(means), all.variance()};
}

WarpOptions occluder_options() {
    WarpOptions o;
    o.weight.kappa = 1e3f; // the occluder spans ~1 rad: κ = 1e3 is a kernel of ~0.03 rad
    return o;
}

} // namespace

// The index of the mesh vertex nearest to p (loaders may reorder vertices).
uint32_t vertex_at(const TriangleMesh& mesh, const Vec3f& p) {
    uint32_t best = 0;
    for (uint32_t v = 1; v < mesh.vertex_count(); ++v)
        if (norm(mesh.positions[v] - p) < norm(mesh.positions[best] - p)) best = v;
    return best;
}

TEST(WasBoundaryTest, OpenAndSilhouetteVerticesVanish) {
    const OccluderScene o(4);
    const Shape& shape = *o.scene->shapes[0];
    TriangleMesh& mesh = o.scene->shapes[0]->mesh;
    const Vec3f eye(0.f), up(0.f, 0.f, 1.f);
    // A corner (open edges) and an interior vertex of the 5 × 5 grid.
    const uint32_t corner = vertex_at(mesh, Vec3f(X0, Y0, H)),
                   interior = vertex_at(mesh, Vec3f(-0.15f, -0.25f, H));
    EXPECT_EQ(o.boundary->vertex_value(shape, corner, eye, up), 0.f);
    EXPECT_NEAR(o.boundary->vertex_value(shape, interior, eye, up), 1.f, 1e-6f);
    // B_v = c² / (1 − (1 − β)(1 − c²)) at an oblique direction.
    const Vec3f oblique = normalize(Vec3f(1.f, 0.f, 0.2f));
    const float c2 = oblique.z * oblique.z;
    EXPECT_NEAR(o.boundary->vertex_value(shape, interior, eye, oblique), c2 / (1.f - 0.99f * (1.f - c2)),
                1e-6f);
    // Barycentric interpolation at a hit: B vanishes toward the open border.
    const auto b_at = [&](float x, float y) {
        const Vec3f d = normalize(Vec3f(x, y, H));
        return (*o.boundary)(o.scene->intersect(Ray(eye, d)), eye, d);
    };
    EXPECT_LT(b_at(X0 + 0.01f, 0.f), 0.1f);
    EXPECT_GT(b_at(X0 + 0.3f, 0.f), 0.5f);
    EXPECT_EQ(b_at(2.f, 0.f), 1.f); // an escaped ray
    // A ridge: fold the grid down along x = 0.1; seen from a point just above the flat half, the folded half
    // is turned away: the fold's vertices are on a silhouette, the flat half's interior is not.
    const uint32_t fold = vertex_at(mesh, Vec3f(0.1f, 0.f, H));
    for (Vec3f& p : mesh.positions)
        if (p.x > 0.15f) p.z = H - (p.x - 0.1f);
    const BoundaryTest folded(*o.scene);
    const Vec3f side_eye(-2.f, 0.f, H + 0.05f);
    EXPECT_EQ(folded.vertex_value(shape, fold, side_eye, normalize(mesh.positions[fold] - side_eye)), 0.f);
    EXPECT_GT(folded.vertex_value(shape, interior, side_eye, normalize(mesh.positions[interior] - side_eye)),
              0.f);
    // From above both halves face the eye: no silhouette at the fold.
    const Vec3f top_eye(0.1f, 0.f, 3.f);
    EXPECT_GT(folded.vertex_value(shape, fold, top_eye, normalize(mesh.positions[fold] - top_eye)), 0.f);
}

// Creases (distance mode): the shading of a flat-shaded cube jumps across its edges, which move with it, so B
// vanishes there as at silhouettes; a smooth-shaded sphere has none (B stays up next to its triangles' edges).
TEST(WasBoundaryTest, CreasesOfFlatShadedMeshesVanish) {
    const auto b_at = [](const std::string& shape, const Vec3f& eye, const Vec3f& target) {
        const auto scene = load_scene_string(R"(<scene version="3.0.0">)" + shape + "</scene>");
        const BoundaryTest b(*scene);
        const Vec3f d = normalize(target - eye);
        return b(scene->intersect(Ray(eye, d)), eye, d, 1e4f);
    };
    const Vec3f eye(3.f, 2.5f, 4.f);
    const std::string cube = R"(<shape type="cube"/>)";
    // On the +z face 0.01 from its edge with the +x face (both face the eye), and at the face's middle.
    const float near_edge = b_at(cube, eye, Vec3f(0.99f, 0.2f, 1.f));
    const float middle = b_at(cube, eye, Vec3f(0.f, 0.f, 1.f));
    // A sphere's point seen head-on, wherever it falls on its triangles.
    const float sphere = b_at(R"(<shape type="sphere"/>)", Vec3f(0.f, 0.f, 4.f), Vec3f(0.013f, 0.007f, 1.f));
    std::printf("flat cube: B near the crease %.4f, mid-face %.4f; smooth sphere %.4f\n", near_edge, middle,
                sphere);
    EXPECT_LT(near_edge, 0.05f);
    EXPECT_GT(middle, 0.3f);
    EXPECT_GT(sphere, 0.5f);
}

namespace {

// Synthetic auxiliary samples at ω with B = boundary and direct warp V(ω') = θ (μ + J (ω' − ω)), J acting on
// the tangent frame (s, t) of ω with the given 2 × 2 entries: the field's divergence at ω is J00 + J11.
struct LinearField {
    Vec3f mu;
    float j[2][2];
    Vec3f at(const Frame3f& f, const Vec3f& w) const {
        const Vec3f d = w - f.n;
        const float a = dot(d, f.s), b = dot(d, f.t);
        return mu + f.s * (j[0][0] * a + j[0][1] * b) + f.t * (j[1][0] * a + j[1][1] * b);
    }
};
double synthetic_divergence(const Vec3f& omega, const LinearField& field, const WarpOptions& o, Rng& rng,
                            Vec3f* warp = nullptr) {
    Tape::current().clear();
    const Var theta = Var::parameter(0.f, 0);
    const Frame3f frame(omega);
    std::vector<AuxiliarySample> aux;
    for (const VmfSample& s : sample_auxiliary(omega, o, rng))
        aux.push_back({s, 1.f, Vec3<Var>(s.direction) + Vec3<Var>(field.at(frame, s.direction)) * theta});
    const WarpEstimate e = estimate_warp(omega, aux, o);
    const std::vector<float> direction = {1.f};
    if (warp)
        *warp = Vec3f(derivative(e.direction.x, direction), derivative(e.direction.y, direction),
                      derivative(e.direction.z, direction));
    return derivative(e.jacobian, direction);
}

} // namespace

TEST(WasWarpField, UniformFieldIsReproducedExactly) {
    // Self-normalized weights reproduce a constant field exactly, and its divergence is the sphere's −2⟨ω, V⟩
    // = 0.
    const Vec3f omega = normalize(Vec3f(0.1f, 0.3f, 1.f));
    const Frame3f frame(omega);
    const LinearField field{frame.s * 0.7f - frame.t * 0.2f, {{0.f, 0.f}, {0.f, 0.f}}};
    for (bool unbiased : {false, true}) {
        WarpOptions o;
        o.weight.kappa = 1e4f;
        o.unbiased = unbiased;
        Rng rng{PCG32(11)};
        for (int trial = 0; trial < 50; ++trial) {
            Vec3f v;
            const double div = synthetic_divergence(omega, field, o, rng, &v);
            EXPECT_LT(norm(v - field.mu), 1e-4f) << "unbiased " << unbiased;
            EXPECT_NEAR(div, 0.0, 1e-3) << "unbiased " << unbiased;
        }
    }
}

namespace {

struct FieldRun {
    BatchMean divergence;
    double divergence_variance, warp_variance; // per estimate; the warp's x component
};
FieldRun run_linear_field(const LinearField& field, const WarpOptions& o, uint64_t seed) {
    const Vec3f omega = normalize(Vec3f(-0.2f, 0.1f, 1.f));
    Rng rng{PCG32(5, seed)};
    std::vector<double> means;
    Stats div, warp;
    for (int b = 0; b < 20; ++b) {
        double sum = 0.0;
        for (int i = 0; i < 1000; ++i) {
            Vec3f v;
            const double d = synthetic_divergence(omega, field, o, rng, &v);
            sum += d;
            div.add(d);
            warp.add(v.x);
        }
        means.push_back(sum / 1000.0);
    }
    return {batch_mean(means), div.variance(), warp.variance()};
}

// A linear field with B = 1 everywhere (no boundary): E[∇·V] = tr J = 3 up to O(1/κ) curvature terms.
const LinearField Linear{Vec3f(0.f), {{2.f, 0.5f}, {-0.3f, 1.f}}};
constexpr double LinearTrace = 3.0;

WarpOptions linear_options(bool unbiased, bool antithetic, int aux_count = 8) {
    WarpOptions o;
    o.weight.kappa = 1e4f;
    o.unbiased = unbiased;
    o.antithetic = antithetic;
    o.aux_count = aux_count;
    return o;
}

} // namespace

TEST(WasWarpField, UnbiasedDivergenceOfLinearField) {
    for (bool antithetic : {false, true}) {
        const FieldRun r =
            run_linear_field(Linear, linear_options(true, antithetic), 1 + uint64_t(antithetic));
        const double z = (r.divergence.mean - LinearTrace) / r.divergence.se;
        std::printf("linear field, unbiased, antithetic %d: ∇·V = %.4f ± %.4f (exact %.1f, z = %.2f), "
                    "variance %.4g\n",
                    int(antithetic), r.divergence.mean, r.divergence.se, LinearTrace, z,
                    r.divergence_variance);
        EXPECT_LT(std::abs(z), 4.0) << "antithetic " << antithetic;
    }
}

TEST(WasWarpField, ConsistentDivergenceConverges) {
    // The self-normalized estimator (Algorithm 2) is biased at finite N', by O(1/N').
    double bias[2];
    for (int k = 0; k < 2; ++k) {
        const int n = k == 0 ? 8 : 64;
        const FieldRun r = run_linear_field(Linear, linear_options(false, false, n), 3 + uint64_t(k));
        bias[k] = r.divergence.mean - LinearTrace;
        std::printf("linear field, consistent N'=%d: ∇·V = %.4f ± %.4f (exact %.1f, relative bias %.4f)\n", n,
                    r.divergence.mean, r.divergence.se, LinearTrace, bias[k] / LinearTrace);
    }
    EXPECT_LT(std::abs(bias[1]), 0.25 * std::abs(bias[0]));
    EXPECT_LT(std::abs(bias[1]) / LinearTrace, 0.02);
}

TEST(WasWarpField, AntitheticVarianceRatios) {
    // §4.2: reflected pairs cancel the odd part of the weights' gradients. They make the warp V of a linear
    // field exact (asserted); the consistent divergence of a linear field is even in the reflection (a pair's
    // two terms are equal), so there they cost variance; the unbiased divergence is heavy-tailed (the Russian
    // roulette's 1/P(N ≥ k) grows geometrically while F_k − F_{k−1} decays as 1/k), so its ratio is printed,
    // not asserted.
    const FieldRun ub0 = run_linear_field(Linear, linear_options(true, false), 7),
                   ub1 = run_linear_field(Linear, linear_options(true, true), 7);
    const FieldRun c0 = run_linear_field(Linear, linear_options(false, false), 8),
                   c1 = run_linear_field(Linear, linear_options(false, true), 8);
    std::printf("antithetic variance ratios, linear field: unbiased ∇·V %.3f, consistent ∇·V %.3f, "
                "consistent V %.3g\n",
                ub1.divergence_variance / ub0.divergence_variance,
                c1.divergence_variance / c0.divergence_variance, c1.warp_variance / c0.warp_variance);
    EXPECT_LT(c1.warp_variance, 0.1 * c0.warp_variance);
}

TEST(WasOccluder, DerivativeMatchesQuadrature) {
    // The consistent estimator converges as N' grows (N' = 8 is printed: its O(1/N') bias, ~10% here, is
    // about 2 standard errors at this sample count); N' = 32 and the unbiased estimator are asserted.
    const OccluderScene o(16);
    const double exact = exact_derivative();
    struct Case {
        bool unbiased;
        int aux;
        bool asserted;
    };
    for (const Case c : {Case{false, 8, false}, Case{false, 32, true}, Case{true, 0, true}}) {
        WarpOptions options = occluder_options();
        options.unbiased = c.unbiased;
        options.aux_count = c.aux;
        const OccluderRun r = run_occluder(o, options, true, 40, c.aux == 32 ? 15000 : 30000, 1);
        const double z = (r.estimate.mean - exact) / r.estimate.se;
        std::printf("occluder, %s N'=%d: dI/dθ = %.5f ± %.5f, exact %.5f, z = %.2f, variance %.4g\n",
                    c.unbiased ? "unbiased" : "consistent", c.aux, r.estimate.mean, r.estimate.se, exact, z,
                    r.variance);
        if (c.asserted) {
            EXPECT_LT(std::abs(z), 4.0) << "unbiased " << c.unbiased << " N' " << c.aux;
        }
    }
}

TEST(WasOccluder, ReverseModeMatchesForwardMode) {
    // The divergence depends on θ only through the auxiliary intersections on the tape: one sweep either way.
    const OccluderScene o(16);
    for (bool unbiased : {false, true}) {
        WarpOptions options = occluder_options();
        options.unbiased = unbiased;
        Rng rng{PCG32(17)};
        int nonzero = 0;
        for (int i = 0; i < 2000; ++i) {
            double reverse = 0.0;
            const double forward = occluder_sample(o, options, rng, true, &reverse);
            EXPECT_NEAR(reverse, forward, 1e-4 * (1.0 + std::abs(forward)));
            nonzero += forward != 0.0;
        }
        EXPECT_GT(nonzero, 20);
    }
}

TEST(WasOccluder, WithoutDivergenceFails) {
    // Negative control: the warp alone (⟨∂ω L, V⟩) misses the boundary term.
    const OccluderScene o(16);
    const double exact = exact_derivative();
    const OccluderRun r = run_occluder(o, occluder_options(), false, 40, 500, 2);
    const double z = (r.estimate.mean - exact) / r.estimate.se;
    std::printf("occluder without ∇·V: %.5f ± %.5f, exact %.5f, z = %.1f\n", r.estimate.mean, r.estimate.se,
                exact, z);
    EXPECT_GT(std::abs(z), 4.0);
}

TEST(WasOccluder, AntitheticVarianceRatios) {
    const OccluderScene o(16);
    for (bool unbiased : {false, true}) {
        WarpOptions options = occluder_options();
        options.unbiased = unbiased;
        options.antithetic = false;
        const double plain = run_occluder(o, options, true, 20, 5000, 3).variance;
        options.antithetic = true;
        const double paired = run_occluder(o, options, true, 20, 5000, 3).variance;
        std::printf("occluder, %s: antithetic variance ratio %.3f (%.4g / %.4g)\n",
                    unbiased ? "unbiased" : "consistent", paired / plain, paired, plain);
    }
}

TEST(WasControlVariate, TiltedFlatEmitterInPixel) {
    // Appendix D's setting: a flat emitter at an angle seen through a pixel with a Gaussian filter (σ = 1/2
    // px): radiance g and warp V vary about linearly across the pixel (with small quadratic terms).
    const float sigma = 0.5f;
    const auto g = [](const Vec2f& x) { return 1.f + 0.3f * x.x + 0.2f * x.y + 0.05f * x.x * x.x; };
    const auto v = [](const Vec2f& x) {
        return Vec2f(0.5f + 0.4f * x.x - 0.1f * x.y, 0.2f + 0.1f * x.x + 0.3f * x.y + 0.02f * x.y * x.y);
    };
    const auto m = [&](const Vec2f& x) {
        const Vec2f vx = v(x);
        return -g(x) * (x.x * vx.x + x.y * vx.y) / (sigma * sigma);
    };
    // E[M] = −E[∇·(g V)] (integration by parts against the filter): by quadrature over ±6σ.
    double exact = 0.0, total = 0.0;
    const int n = 600;
    const double h = 12.0 * sigma / n;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const Vec2f x(float(-6.0 * sigma + (i + 0.5) * h), float(-6.0 * sigma + (j + 0.5) * h));
            const double k = std::exp(-(x.x * x.x + x.y * x.y) / (2.0 * sigma * sigma));
            exact += k * m(x);
            total += k;
        }
    exact /= total;
    // A from a pilot of independent samples (means of g, ∂g, V, ∂V by central differences).
    Rng rng{PCG32(9)};
    const auto gaussian = [&]() {
        const Vec2f u = rng.next_2d();
        const float r = sigma * std::sqrt(-2.f * std::log(1.f - u.x));
        return Vec2f(r * std::cos(2.f * Pi * u.y), r * std::sin(2.f * Pi * u.y));
    };
    LinearControlVariate cv;
    cv.sigma = sigma;
    const int pilot = 64;
    const float e = 1e-3f;
    for (int i = 0; i < pilot; ++i) {
        const Vec2f x = gaussian(), dx(e, 0.f), dy(0.f, e);
        cv.mu_g += g(x) / pilot;
        cv.grad_g = cv.grad_g + Vec2f(g(x + dx) - g(x - dx), g(x + dy) - g(x - dy)) * (0.5f / e / pilot);
        cv.mu_v = cv.mu_v + v(x) * (1.f / pilot);
        const Vec2f vdx = (v(x + dx) - v(x - dx)) * (0.5f / e / pilot),
                    vdy = (v(x + dy) - v(x - dy)) * (0.5f / e / pilot);
        cv.jac_v[0] = cv.jac_v[0] + Vec2f(vdx.x, vdy.x);
        cv.jac_v[1] = cv.jac_v[1] + Vec2f(vdx.y, vdy.y);
    }
    Stats plain, controlled;
    std::vector<double> means;
    for (int b = 0; b < 20; ++b) {
        double sum = 0.0;
        for (int i = 0; i < 5000; ++i) {
            const Vec2f x = gaussian();
            plain.add(m(x));
            const double q = cv.controlled(m(x), x);
            controlled.add(q);
            sum += q;
        }
        means.push_back(sum / 5000.0);
    }
    const BatchMean q = batch_mean(means);
    const double z = (q.mean - exact) / q.se;
    std::printf("control variate: E[Q] = %.5f ± %.5f, exact %.5f, z = %.2f, variance ratio %.4f\n", q.mean,
                q.se, exact, z, controlled.variance() / plain.variance());
    EXPECT_LT(std::abs(z), 4.0);
    EXPECT_LT(controlled.variance(), 0.1 * plain.variance());
}

// The control variate's known mean where the film's edge cuts the filter (hdrfilm without sample_border):
// E[C] = −tr(A) + the cut's flux, checked against the mean of C over the film sampler's own draws at a corner
// pixel, an edge pixel and an interior one (no cut), for a linear model with every term nonzero.
TEST(WasControlVariate, KnownMeanWhereTheFilmCutsTheFilter) {
    const auto scene = load_scene_string(R"(<scene version="3.0.0">
      <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="6"/>
        <integer name="height" value="5"/><boolean name="sample_border" value="false"/>
        <rfilter type="gaussian"/></film></sensor>
    </scene>)");
    const Film& film = *scene->sensor->film;
    LinearControlVariate cv;
    cv.mu_g = 0.8f;
    cv.grad_g = Vec2f(0.3f, -0.5f);
    cv.mu_v = Vec2f(1.5f, -0.7f);
    cv.jac_v[0] = Vec2f(0.4f, 0.9f);
    cv.jac_v[1] = Vec2f(-0.6f, 0.2f);
    const int pixels[3][2] = {{0, 0}, {2, 4}, {3, 2}};
    for (const auto& px : pixels) {
        const std::vector<FilmCut> cuts = film_cuts(film, px[0], px[1]);
        EXPECT_EQ(cuts.size(), size_t(px[0] == 0 ? 2 : px[1] == 4 ? 1 : 0));
        Sampler sampler;
        std::vector<double> means;
        for (int b = 0; b < 16; ++b) {
            double sum = 0.0;
            const int n = 400000;
            for (int i = 0; i < n; ++i) {
                sampler.start(7, uint64_t(b), uint64_t(i));
                const FilmSample fs = sample_film(*film.rfilter, sampler, false);
                const Vec2f score = filter_gradient_ratio(film, px[0], px[1], fs.offset, fs.pdf);
                // −correction = C − E[C]: zero mean if E[C] is right.
                sum -= control_correction(cv, cuts, fs.offset, score);
            }
            means.push_back(sum / n);
        }
        const BatchMean m = batch_mean(means);
        std::printf("pixel (%d, %d), %zu cuts: E[C − E[C]] = %.5f ± %.5f\n", px[0], px[1], cuts.size(), m.mean,
                    m.se);
        EXPECT_LT(std::abs(m.mean), 4.0 * m.se + 1e-4);
    }
    // Without the cut's flux the mean is off at the corner pixel (the check can fail).
    const std::vector<FilmCut> corner = film_cuts(film, 0, 0);
    const float flux =
        control_correction(cv, corner, Vec2f(0.f), Vec2f(0.f)) - control_correction(cv, {}, Vec2f(0.f), Vec2f(0.f));
    EXPECT_GT(std::abs(flux), 0.05f);
}

TEST(WasWarpedVertex, FollowsMovingPlaneAndWarpedDirection) {
    // The occluder plane z = H + θ and the direction ω + θ v from the origin: the hit is p(θ) = d(θ) (H + θ)
    // / d_z(θ), so ∂θ p = ω / ω_z + H (v / ω_z − ω v_z / ω_z²).
    const OccluderScene o(4);
    o.params->enable({parse_param_selection("occluder.translate=0,0,1")});
    const Vec3f omega = normalize(Vec3f(0.1f, -0.2f, 1.f)), v(0.3f, 0.1f, -0.05f);
    Tape::current().clear();
    const SurfaceInteraction3f hit = o.scene->intersect(Ray(Vec3f(0.f), omega));
    ASSERT_TRUE(hit.is_valid());
    const Var theta = Var::parameter(0.f, 0);
    const Vec3<Var> direction = Vec3<Var>(omega) + Vec3<Var>(v) * theta;
    const SurfaceInteraction<Var> y = warped_vertex(*o.params, hit, Vec3<Var>(Var(0.f)), direction);
    const std::vector<float> unit = {1.f};
    const Vec3f dp(derivative(y.p.x, unit), derivative(y.p.y, unit), derivative(y.p.z, unit));
    const Vec3f expected = omega / omega.z + (v / omega.z - omega * (v.z / (omega.z * omega.z))) * H;
    EXPECT_LT(norm(dp - expected), 1e-4f) << dp.x << ' ' << dp.y << ' ' << dp.z;
    EXPECT_LT(norm(Vec3f(y.p.x.v, y.p.y.v, y.p.z.v) - hit.p), 1e-5f);
}

namespace {

// The film-space estimator on V(x') = θ (μ + J (x' − x)) with B = 1: E[∇·V] = tr J, and V = μ exactly for J =
// 0.
double pixel_divergence(const Vec2f& mu, const float (&j)[2][2], const WarpOptions& o, float sigma, Rng& rng,
                        Vec2f* warp = nullptr) {
    Tape::current().clear();
    const Var theta = Var::parameter(0.f, 0);
    const Vec2f x(3.5f, 7.25f);
    std::vector<PixelAuxiliarySample> aux = sample_pixel_auxiliary(sigma, o, rng);
    for (PixelAuxiliarySample& a : aux) {
        const Vec2f d = a.offset;
        const Vec2f v(mu.x + j[0][0] * d.x + j[0][1] * d.y, mu.y + j[1][0] * d.x + j[1][1] * d.y);
        a.warp = Vec2<Var>(Var(x.x + d.x) + theta * Var(v.x), Var(x.y + d.y) + theta * Var(v.y));
    }
    const PixelWarpEstimate e = estimate_pixel_warp(x, aux, sigma, o);
    const std::vector<float> unit = {1.f};
    if (warp) *warp = Vec2f(derivative(e.position.x, unit), derivative(e.position.y, unit));
    EXPECT_EQ(e.position.x.v, x.x);
    return derivative(e.jacobian, unit);
}

} // namespace

TEST(WasPixelWarp, UniformExactAndLinearDivergenceUnbiased) {
    const float sigma = 0.25f;
    const float zero[2][2] = {{0.f, 0.f}, {0.f, 0.f}}, j[2][2] = {{1.5f, 0.2f}, {-0.4f, 0.5f}};
    for (bool unbiased : {false, true}) {
        WarpOptions o;
        o.unbiased = unbiased;
        Rng rng{PCG32(23, uint64_t(unbiased))};
        for (int i = 0; i < 20; ++i) {
            Vec2f v;
            EXPECT_NEAR(pixel_divergence(Vec2f(0.3f, -0.7f), zero, o, sigma, rng, &v), 0.0, 1e-4);
            EXPECT_NEAR(v.x, 0.3f, 1e-4f);
            EXPECT_NEAR(v.y, -0.7f, 1e-4f);
        }
    }
    WarpOptions o;
    o.unbiased = true;
    o.antithetic = false;
    Rng rng{PCG32(29)};
    std::vector<double> means;
    for (int b = 0; b < 20; ++b) {
        double sum = 0.0;
        for (int i = 0; i < 1000; ++i)
            sum += pixel_divergence(Vec2f(0.f), j, o, sigma, rng);
        means.push_back(sum / 1000.0);
    }
    const BatchMean m = batch_mean(means);
    const double z = (m.mean - 2.0) / m.se;
    std::printf("film-space linear field, unbiased: ∇·V = %.4f ± %.4f (exact 2.0, z = %.2f)\n", m.mean, m.se,
                z);
    EXPECT_LT(std::abs(z), 4.0);
}

// The film warp's jackknife (consistent variant, WarpOptions::film_jackknife): Algorithm 2's ratio
// overestimates the divergence of a linear field even with B = 1 (the self-normalized weights' O(1/N') bias);
// the delete-a-pair jackknife removes that term and leaves O(1/N'²). Measured (σ = 0.25, 40k estimates):
// N' = 8: +27% → −15%; 16: +11% → −3%; 32 (the default): +4.7% → −0.7%; 64: +2.1% → −0.3%.
TEST(WasPixelWarp, JackknifeRemovesTheRatioBias) {
    const float sigma = 0.25f, j[2][2] = {{1.5f, 0.2f}, {-0.4f, 0.5f}};
    double bias[2];
    for (bool jackknife : {false, true}) {
        WarpOptions o;
        o.aux_count = 32;
        o.film_jackknife = jackknife;
        Rng rng{PCG32(31)};
        std::vector<double> means;
        for (int b = 0; b < 20; ++b) {
            double sum = 0.0;
            for (int i = 0; i < 2000; ++i)
                sum += pixel_divergence(Vec2f(0.f), j, o, sigma, rng);
            means.push_back(sum / 2000.0);
        }
        const BatchMean m = batch_mean(means);
        bias[jackknife] = m.mean - 2.0;
        std::printf("N' = 32, jackknife %d: ∇·V = %.4f ± %.4f (exact 2.0)\n", int(jackknife), m.mean, m.se);
        if (jackknife) EXPECT_LT(std::abs(bias[1]), std::max(4.0 * m.se, 0.04));
        else EXPECT_GT(std::abs(bias[0]), 10.0 * m.se);
    }
    EXPECT_LT(std::abs(bias[1]), 0.25 * std::abs(bias[0]));
}

// The paper's flat emitter at an angle (§4.2, Fig. 8): its film motion is linear across the pixel, V(x') = μ +
// J (x' − x). Antithetic offsets (a point reflection about x) make the estimated field exact, V̂(x) = μ: the
// linear parts of each pair cancel under the pair's equal weights (B = 1); independent offsets leave noise in
// V̂, and hence in the terms ⟨∂x L, V⟩ and ⟨∂x P, V⟩ of the pixel integral. (The divergence of Algorithm 2
// is a self-normalized ratio, exact for a uniform field either way: antithetic pairs do not lower its
// variance, docs/warped-area-sampling.md.)
TEST(WasPixelWarp, AntitheticOffsetsMakeTheLinearFieldExact) {
    const float sigma = 0.5f;
    const float j[2][2] = {{0.6f, 0.1f}, {-0.2f, 0.3f}};
    double variance[2] = {0.0, 0.0};
    for (const bool antithetic : {true, false}) {
        WarpOptions o;
        o.antithetic = antithetic;
        Rng rng{PCG32(37, uint64_t(antithetic))};
        double sum = 0.0, sum2 = 0.0;
        constexpr int n = 2000;
        for (int i = 0; i < n; ++i) {
            Vec2f v;
            pixel_divergence(Vec2f(0.3f, -0.7f), j, o, sigma, rng, &v);
            sum += v.x;
            sum2 += double(v.x) * double(v.x);
        }
        variance[antithetic ? 0 : 1] = sum2 / n - (sum / n) * (sum / n);
        std::printf("tilted flat emitter, %s offsets: V_x = %.5f, variance %.3g\n",
                    antithetic ? "antithetic" : "independent", sum / n, variance[antithetic ? 0 : 1]);
    }
    EXPECT_LT(variance[0], 1e-3 * variance[1]);
    EXPECT_GT(variance[1], 1e-4);
}

