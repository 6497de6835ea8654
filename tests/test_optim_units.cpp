// Building blocks of inverse rendering: losses (gradient check against finite differences), Adam (a
// quadratic), the configuration parser's errors and the line-plot writer.
#include "core/error.h"
#include "core/image_loss.h"
#include "core/plot.h"
#include "core/rng.h"
#include "optim/adam.h"
#include "optim/optimize.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

Image random_image(int w, int h, uint64_t seed, float scale) {
    PCG32 rng;
    rng.seed(seed, 1);
    Image img(w, h);
    for (Color3f& p : img.pixels)
        p = Color3f(rng.next_float(), rng.next_float(), rng.next_float()) * scale;
    return img;
}

// Central differences of the loss in every pixel and channel against the adjoint. h = 2^-10 is exact in
// float, the loss is quadratic in I so the central difference has no truncation error: only float rounding of
// the perturbed image (relative 1e-7 of values ≤ 2) limits the agreement, hence the 1e-4 relative tolerance.
void check_adjoint(LossKind kind) {
    const Image target = random_image(5, 4, 1, 1.f), image = random_image(5, 4, 2, 2.f);
    const LossResult at = compute_loss(kind, image, target);
    const float h = 1.f / 1024.f;
    for (size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            Image plus = image, minus = image;
            plus.pixels[i][c] += h;
            minus.pixels[i][c] -= h;
            const double fd =
                (compute_loss(kind, plus, target).value - compute_loss(kind, minus, target).value) /
                (2.0 * h);
            const double adjoint = at.adjoint.pixels[i][c];
            EXPECT_NEAR(adjoint, fd, 1e-4 * std::abs(fd) + 1e-9) << "pixel " << i << " channel " << c;
        }
}

} // namespace

TEST(OptimLoss, L2Value) {
    Image a(2, 1, Color3f(1.f)), t(2, 1, Color3f(0.f));
    a.pixels[1] = Color3f(3.f);
    // mean over 6 values of (1, 1, 1, 9, 9, 9) = 5
    EXPECT_DOUBLE_EQ(l2_loss(a, t).value, 5.0);
    EXPECT_NEAR(relative_l2_loss(a, t).value, 5.0 / 0.01, 1e-9);
}

TEST(OptimLoss, L2AdjointMatchesFiniteDifferences) { check_adjoint(LossKind::L2); }
TEST(OptimLoss, RelativeL2AdjointMatchesFiniteDifferences) { check_adjoint(LossKind::RelativeL2); }

TEST(OptimLoss, RejectsSizeMismatchAndUnknownKind) {
    EXPECT_THROW(l2_loss(Image(2, 2), Image(2, 3)), Error);
    EXPECT_THROW(parse_loss_kind("l1"), Error);
    EXPECT_EQ(parse_loss_kind("rel_l2"), LossKind::RelativeL2);
}

// f(x) = Σ a_k (x_k − c_k)², ∇f = 2 a (x − c), with curvatures spanning 100×: Adam's per-coordinate scaling
// reaches the minimum of every coordinate at a similar rate. With a constant rate the iterate oscillates
// around the minimum with an amplitude of order lr, so we decay the rate to 1e-4 × lr and ask for 1e-3.
TEST(OptimAdam, MinimizesQuadratic) {
    const std::vector<double> a{0.1, 1.0, 10.0}, c{1.5, -2.0, 0.25};
    std::vector<double> x{0.0, 0.0, 0.0};
    Adam adam({{"p", 0, 2, 0.05}, {"q", 2, 1, 0.02}}, 3);
    const int steps = 3000;
    for (int t = 0; t < steps; ++t) {
        std::vector<double> g(3);
        for (int k = 0; k < 3; ++k)
            g[k] = 2 * a[k] * (x[k] - c[k]);
        adam.step(x, g, std::pow(1e-4, double(t) / steps));
    }
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(x[k], c[k], 1e-3) << k;
    EXPECT_EQ(adam.steps(), steps);
}

TEST(OptimAdam, FirstStepHasTheLearningRate) {
    // With bias correction, m̂ = g and v̂ = g² after one step: the step is lr · g/|g| whatever |g|.
    std::vector<double> x{1.0, 1.0};
    Adam adam({{"p", 0, 2, 0.1}}, 2);
    adam.step(x, {1e-3, -50.0});
    EXPECT_NEAR(x[0], 0.9, 1e-6);
    EXPECT_NEAR(x[1], 1.1, 1e-6);
}

TEST(OptimAdam, ClampsToBounds) {
    // Minimum at c = 2, outside the box [0, 1]: the projected iterate stops at the bound.
    std::vector<double> x{0.5};
    Adam adam({{"p", 0, 1, 0.05, 0.0, 1.0}}, 1);
    for (int t = 0; t < 200; ++t)
        adam.step(x, {2 * (x[0] - 2.0)});
    EXPECT_DOUBLE_EQ(x[0], 1.0);
}

TEST(OptimAdam, RejectsBadGroups) {
    EXPECT_THROW(Adam({{"p", 0, 1, 0.1}}, 2), Error);                   // index 1 not covered
    EXPECT_THROW(Adam({{"p", 0, 2, 0.1}, {"q", 1, 1, 0.1}}, 2), Error); // overlap
    EXPECT_THROW(Adam({{"p", 0, 1, 0.0}}, 1), Error);                   // zero rate
    EXPECT_THROW(Adam({{"p", 0, 1, 0.1, 1.0, 0.0}}, 1), Error);         // lower > upper
}

namespace {

nlohmann::json minimal_config() {
    return nlohmann::json::parse(
        R"({"scene": "s.xml", "parameters": {"mat.alpha": {"lr": 0.01, "bounds": [0.01, 1]}},
                                     "target": {"image": "t.exr"}})");
}

std::string config_error(const nlohmann::json& j) {
    try {
        parse_optimize_config(j, "/base", "cfg.json");
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(OptimConfig, ParsesAndResolvesPaths) {
    nlohmann::json j = minimal_config();
    j["defines"] = {{"res", 32}, {"name", "x"}};
    j["parameters"]["light.emitter.radiance"] = {{"init", {1, 2, 3}}, {"lr", 0.1}, {"bounds", {0, nullptr}}};
    const OptimizeConfig c = parse_optimize_config(j, "/base", "cfg.json");
    EXPECT_EQ(c.scene, "/base/s.xml");
    EXPECT_EQ(c.target_image, "/base/t.exr");
    EXPECT_EQ(c.defines.at("res"), "32");
    ASSERT_EQ(c.parameters.size(), 2u);
    const OptimizedParameter& radiance =
        c.parameters[0].name == "light.emitter.radiance" ? c.parameters[0] : c.parameters[1];
    EXPECT_EQ(radiance.init, (std::vector<float>{1, 2, 3}));
    EXPECT_EQ(radiance.lower, 0.0);
    EXPECT_TRUE(std::isinf(radiance.upper));
}

TEST(OptimConfig, ErrorsNameTheKey) {
    nlohmann::json j = minimal_config();
    j["iteratons"] = 10;
    EXPECT_NE(config_error(j).find("unknown key 'iteratons'"), std::string::npos) << config_error(j);

    j = minimal_config();
    j["iterations"] = "10";
    EXPECT_NE(config_error(j).find("'iterations': expected an integer, got string"), std::string::npos)
        << config_error(j);

    j = minimal_config();
    j["parameters"]["mat.alpha"]["learning_rate"] = 0.1;
    EXPECT_NE(config_error(j).find("'parameters.mat.alpha.learning_rate'"), std::string::npos)
        << config_error(j);

    j = minimal_config();
    j["parameters"]["mat.alpha"]["bounds"] = {0, "1"};
    EXPECT_NE(config_error(j).find("'parameters.mat.alpha.bounds'"), std::string::npos) << config_error(j);

    j = minimal_config();
    j["target"] = {{"values", {{"other.reflectance", 0.5}}}};
    EXPECT_NE(config_error(j).find("unknown key 'target.values.other.reflectance'"), std::string::npos)
        << config_error(j);

    j = minimal_config();
    j["target"]["values"] = nlohmann::json::object();
    EXPECT_NE(config_error(j).find("exactly one of"), std::string::npos) << config_error(j);

    j = minimal_config();
    j.erase("scene");
    EXPECT_NE(config_error(j).find("missing key 'scene'"), std::string::npos) << config_error(j);
}

TEST(OptimConfig, RelativeDistance) {
    EXPECT_NEAR(relative_distance({3.0, 4.0}, {0.0, 5.0}), std::sqrt(9.0 + 1.0) / 5.0, 1e-12);
    EXPECT_DOUBLE_EQ(relative_distance({3.0}, {0.0}), 3.0);
}

TEST(Plot, DrawsSeriesAxesAndLegend) {
    PlotSeries a{"a", {}, {}}, b{"b", {}, {}};
    for (int i = 0; i < 50; ++i) {
        a.x.push_back(i), a.y.push_back(std::exp(-0.1 * i));
        b.x.push_back(i), b.y.push_back(i == 10 ? 0.0 : 0.5 * std::exp(-0.05 * i)); // y = 0 breaks a log line
    }
    const Image img = plot_lines({a, b}, {"title", "iteration", "loss", true, 400, 300});
    ASSERT_EQ(img.width, 400);
    ASSERT_EQ(img.height, 300);
    // Both palette colors (blue, orange) and black text/axes appear on a white background.
    int blue = 0, orange = 0, black = 0, white = 0;
    for (const Color3f& p : img.pixels) {
        blue += p.z > 0.3f && p.x < 0.05f;
        orange += p.x > 0.9f && p.z < 0.05f && p.y > 0.1f;
        black += p.x + p.y + p.z < 0.01f;
        white += p.x + p.y + p.z > 2.99f;
    }
    EXPECT_GT(blue, 100);
    EXPECT_GT(orange, 100);
    EXPECT_GT(black, 500);
    EXPECT_GT(white, 400 * 300 / 2);
}

TEST(Plot, RejectsEmptyData) {
    EXPECT_THROW(plot_lines({{"a", {1, 2}, {0, -1}}}, {"", "", "", true, 400, 300}), Error); // nothing > 0
    EXPECT_THROW(plot_lines({{"a", {1, 2}, {1}}}, {}), Error);                       // length mismatch
    EXPECT_THROW(plot_lines({{"a", {1}, {1}}}, {"", "", "", false, 50, 50}), Error); // too small
}
