// Entropic optimal transport (core/sinkhorn.h) and the DPM-G matching loss (diff/dpm/matching_loss.h, paper 003
// Eq. 25). The references are exact: a translated or permuted cloud has a unique optimal assignment whose
// cost gap to any other is far above ε, so the entropic plan is that assignment up to exp(−gap/ε) ≈ 0.
#include "core/error.h"
#include "core/sinkhorn.h"
#include "diff/dpm/matching_loss.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

using namespace penumbra;

namespace {

Points5 random_points(int n, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Points5 p(n, 5);
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < 5; ++k)
            p(i, k) = u(rng);
    return p;
}

Eigen::VectorXd random_weights(int n, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.5, 2.0);
    Eigen::VectorXd w(n);
    for (int i = 0; i < n; ++i)
        w[i] = u(rng);
    return w;
}

// Random colours on an 8 x 8 grid of positions spaced 1/8 apart.
Points5 grid_cloud(std::mt19937& rng) {
    Points5 p = random_points(64, rng);
    for (int i = 0; i < 64; ++i) {
        p(i, 3) = (i % 8 + 0.5) / 8;
        p(i, 4) = (i / 8 + 0.5) / 8;
    }
    return p;
}

} // namespace

// The plan's rows are exact by construction (float exp: relative 1e-7; the error floor measured is 6e-9) and
// its column error, computed here from the dense plan, is the reported one and below the tolerance.
TEST(Sinkhorn, MarginalsWithinTolerance) {
    std::mt19937 rng(16001);
    const Points5 x = random_points(120, rng), y = random_points(90, rng);
    const Eigen::VectorXd a = random_weights(120, rng), b = random_weights(90, rng);
    SinkhornOptions o;
    o.blur = 0.1; // at blur 0.05 this unbalanced problem needs ~5000 iterations for 1e-7 (measured)
    o.tolerance = 1e-7;
    o.max_iterations = 2000;
    const SinkhornResult r = sinkhorn(x, a, y, b, o);
    EXPECT_LT(r.marginal_error, o.tolerance);
    EXPECT_LT(r.iterations, o.max_iterations);
    const Eigen::MatrixXd plan = transport_plan(x, a, y, b, r, o);
    const double row_error = (plan.rowwise().sum() - a / a.sum()).cwiseAbs().sum();
    const double column_error = (plan.colwise().sum().transpose() - b / b.sum()).cwiseAbs().sum();
    EXPECT_LT(row_error, 1e-6);
    EXPECT_NEAR(column_error, r.marginal_error, 1e-6);
    EXPECT_LT(column_error, o.tolerance + 1e-6);
    // The matching is the plan's barycentric projection.
    const Points5 projected = (plan * y).array().colwise() / plan.rowwise().sum().array();
    EXPECT_LT((projected - r.matched).cwiseAbs().maxCoeff(), 1e-6);
}

// ε-scaling is a warm start only: with and without it the solution at ε = 0.01 is the same plan.
TEST(Sinkhorn, AnnealingReachesTheSamePlan) {
    std::mt19937 rng(16002);
    const Points5 x = random_points(80, rng), y = random_points(70, rng);
    const Eigen::VectorXd a = random_weights(80, rng), b = random_weights(70, rng);
    SinkhornOptions annealed;
    annealed.blur = 0.1;
    annealed.tolerance = 1e-9;
    annealed.max_iterations = 2000;
    SinkhornOptions direct = annealed;
    direct.scaling = 0;
    const SinkhornResult ra = sinkhorn(x, a, y, b, annealed), rd = sinkhorn(x, a, y, b, direct);
    EXPECT_GT(ra.annealing_steps, 10);
    EXPECT_EQ(rd.annealing_steps, 0);
    const Eigen::MatrixXd pa = transport_plan(x, a, y, b, ra, annealed),
                          pd = transport_plan(x, a, y, b, rd, direct);
    EXPECT_LT((pa - pd).cwiseAbs().sum(), 1e-7);
}

// Target = source + t: for the quadratic cost every assignment σ costs Σ ½‖x_i − x_σ(i)‖² + const, so the
// identity is optimal with a gap ≥ (1/8)² ≫ ε = 1e-4 (blur 0.01, the paper's), and each point's match is x_i
// + t.
TEST(Sinkhorn, TranslationRecovered) {
    std::mt19937 rng(16003);
    const Points5 x = grid_cloud(rng);
    Eigen::Matrix<double, 1, 5> t;
    t << 0.05, -0.1, 0.2, 0.3, -0.2;
    const Points5 y = x.rowwise() + t;
    const Eigen::VectorXd w = Eigen::VectorXd::Ones(64);
    SinkhornOptions o;
    o.tolerance = 1e-8;
    const SinkhornResult r = sinkhorn(x, w, y, w, o);
    EXPECT_LT(r.marginal_error, o.tolerance);
    EXPECT_LT((r.matched - y).cwiseAbs().maxCoeff(), 1e-6);
}

// A shuffled copy: each point is matched to itself; its row of the plan holds all of its mass on its copy.
TEST(Sinkhorn, PermutationRecovered) {
    std::mt19937 rng(16004);
    const Points5 x = grid_cloud(rng);
    std::vector<int> perm(64);
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    Points5 y(64, 5);
    for (int j = 0; j < 64; ++j)
        y.row(j) = x.row(perm[j]);
    const Eigen::VectorXd w = Eigen::VectorXd::Ones(64);
    SinkhornOptions o;
    o.tolerance = 1e-8;
    const SinkhornResult r = sinkhorn(x, w, y, w, o);
    EXPECT_LT((r.matched - x).cwiseAbs().maxCoeff(), 1e-6);
    const Eigen::MatrixXd plan = transport_plan(x, w, y, w, r, o);
    for (int j = 0; j < 64; ++j)
        EXPECT_GT(plan(perm[j], j), (1 - 1e-6) / 64) << "target " << j;
}

// The xy weight w: with w large the position dominates; a cloud whose colours are reversed along x is matched
// by position (w = 100) but by colour (w = 0.01).
TEST(Sinkhorn, PositionWeight) {
    Points5 x(2, 5), y(2, 5);
    x << 0, 0, 0, 0.2, 0.5, 1, 1, 1, 0.8, 0.5;
    y << 1, 1, 1, 0.25, 0.5, 0, 0, 0, 0.75, 0.5;
    const Eigen::VectorXd w = Eigen::VectorXd::Ones(2);
    SinkhornOptions o;
    o.tolerance = 1e-9;
    o.position_weight = 100;
    EXPECT_NEAR(sinkhorn(x, w, y, w, o).matched(0, 3), 0.25, 1e-6);
    o.position_weight = 0.01;
    EXPECT_NEAR(sinkhorn(x, w, y, w, o).matched(0, 3), 0.75, 1e-6);
}

// Rows are computed whole in a fixed order: 1 and 2 threads give bit-identical potentials and matches.
TEST(Sinkhorn, DeterministicAcrossThreads) {
    std::mt19937 rng(16005);
    const Points5 x = random_points(300, rng), y = random_points(250, rng);
    const Eigen::VectorXd a = random_weights(300, rng), b = random_weights(250, rng);
    SinkhornOptions o;
    o.max_iterations = 50;
    SinkhornResult r1, r2;
    tbb::task_arena(1).execute([&] { r1 = sinkhorn(x, a, y, b, o); });
    tbb::task_arena(2).execute([&] { r2 = sinkhorn(x, a, y, b, o); });
    EXPECT_EQ(r1.iterations, r2.iterations);
    EXPECT_TRUE(r1.f == r2.f);
    EXPECT_TRUE(r1.g == r2.g);
    EXPECT_TRUE(r1.matched == r2.matched);
}

TEST(Sinkhorn, BadInputs) {
    std::mt19937 rng(16006);
    const Points5 x = random_points(10, rng);
    const Eigen::VectorXd w = Eigen::VectorXd::Ones(10);
    const SinkhornOptions o;
    EXPECT_THROW(sinkhorn(Points5(0, 5), Eigen::VectorXd(0), x, w, o), Error);
    EXPECT_THROW(sinkhorn(x, w, Points5(0, 5), Eigen::VectorXd(0), o), Error);
    EXPECT_THROW(sinkhorn(x, Eigen::VectorXd::Ones(9), x, w, o), Error);
    Points5 nan_points = x;
    nan_points(3, 4) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(sinkhorn(nan_points, w, x, w, o), Error);
    Eigen::VectorXd bad_weights = w;
    bad_weights[2] = 0;
    EXPECT_THROW(sinkhorn(x, w, x, bad_weights, o), Error);
    bad_weights[2] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(sinkhorn(x, bad_weights, x, w, o), Error);
    for (double blur : {0.0, -0.01, std::numeric_limits<double>::quiet_NaN()}) {
        SinkhornOptions bad = o;
        bad.blur = blur;
        EXPECT_THROW(sinkhorn(x, w, x, w, bad), Error) << "blur " << blur;
    }
    SinkhornOptions bad = o;
    bad.scaling = 1;
    EXPECT_THROW(sinkhorn(x, w, x, w, bad), Error);
    bad = o;
    bad.position_weight = 0;
    EXPECT_THROW(sinkhorn(x, w, x, w, bad), Error);
    try {
        sinkhorn(x, Eigen::VectorXd::Ones(9), x, w, o);
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("10 points but 9 weights"), std::string::npos) << e.what();
    }
}

// Eq. 25 is quadratic, so central differences are exact up to rounding (step 1e-4, values O(1): ~1e-12).
TEST(MatchingLoss, GradientMatchesCentralDifferences) {
    std::mt19937 rng(16007);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int n = 7;
    ScreenSamples paths{Eigen::MatrixX2d(n, 2), Eigen::MatrixX3d(n, 3)}, targets = paths;
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 2; ++k)
            paths.position(i, k) = u(rng), targets.position(i, k) = u(rng);
        for (int k = 0; k < 3; ++k)
            paths.colour(i, k) = 2 * u(rng), targets.colour(i, k) = u(rng);
    }
    const double lambda1 = 0.5, lambda2 = 0.5, h = 1e-4;
    const MatchingLossResult r = matching_loss(paths, targets, lambda1, lambda2);
    EXPECT_NEAR(r.value,
                (lambda1 * (paths.position - targets.position).squaredNorm() +
                 lambda2 * (paths.colour - targets.colour).squaredNorm()) /
                    n,
                1e-14);
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 5; ++k) {
            ScreenSamples plus = paths, minus = paths;
            double& vp = k < 2 ? plus.position(i, k) : plus.colour(i, k - 2);
            double& vm = k < 2 ? minus.position(i, k) : minus.colour(i, k - 2);
            vp += h;
            vm -= h;
            const double fd = (matching_loss(plus, targets, lambda1, lambda2).value -
                               matching_loss(minus, targets, lambda1, lambda2).value) /
                              (2 * h);
            const double analytic = k < 2 ? r.d_position(i, k) : r.d_colour(i, k - 2);
            EXPECT_NEAR(analytic, fd, 1e-9) << "path " << i << " coordinate " << k;
        }
    }
}

TEST(MatchingLoss, BadInputs) {
    ScreenSamples a{Eigen::MatrixX2d::Zero(3, 2), Eigen::MatrixX3d::Zero(3, 3)};
    ScreenSamples b{Eigen::MatrixX2d::Zero(2, 2), Eigen::MatrixX3d::Zero(2, 3)};
    EXPECT_THROW(matching_loss(a, b), Error);
    ScreenSamples uneven{Eigen::MatrixX2d::Zero(3, 2), Eigen::MatrixX3d::Zero(2, 3)};
    EXPECT_THROW(matching_loss(uneven, uneven), Error);
    ScreenSamples nan = a;
    nan.colour(1, 2) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(matching_loss(nan, a), Error);
    ScreenSamples none{Eigen::MatrixX2d(0, 2), Eigen::MatrixX3d(0, 3)};
    EXPECT_THROW(matching_loss(none, none), Error);
    EXPECT_THROW(image_samples(Image()), Error);
    EXPECT_THROW(match_to_image(a, Eigen::VectorXd::Ones(3), Image()), Error);
}

// Pixel matching of a rendered image against its target: a white 2 x 2 square on black, moved by two pixels
// in x. Colour separates the square from the background (cost 1.5 ≫ any position cost), and within the square
// the translation argument applies: each square pixel is matched to its own position + (2/8, 0), in white.
TEST(MatchingLoss, ImageMatchingFollowsAMovedSquare) {
    Image rendered(8, 8), target(8, 8);
    for (int y = 3; y < 5; ++y)
        for (int x = 2; x < 4; ++x) {
            rendered.at(x, y) = Color3f(1.f);
            target.at(x + 2, y) = Color3f(1.f);
        }
    const ScreenSamples source = image_samples(rendered);
    SinkhornOptions o;
    o.tolerance = 1e-8;
    const ScreenSamples matched = match_to_image(source, Eigen::VectorXd::Ones(64), target, o);
    for (int y = 3; y < 5; ++y)
        for (int x = 2; x < 4; ++x) {
            const int i = y * 8 + x;
            EXPECT_NEAR(matched.position(i, 0), source.position(i, 0) + 2.0 / 8, 1e-6) << x << "," << y;
            EXPECT_NEAR(matched.position(i, 1), source.position(i, 1), 1e-6) << x << "," << y;
            EXPECT_NEAR(matched.colour(i, 0), 1.0, 1e-6);
        }
    // The loss pulls the square toward the target: ∂L/∂p_x < 0 on its pixels.
    const MatchingLossResult loss = matching_loss(source, matched);
    EXPECT_LT(loss.d_position(3 * 8 + 2, 0), 0);
}

// The debiased matching (match_image_debiased): an image matched to itself stays where it is (the self term
// cancels the entropic shrinkage exactly), and the moved square above (now on a graded background) is still
// matched to its position + (2/8, 0).
TEST(MatchingLoss, DebiasedMatchingVanishesAtTheTargetAndFollowsAMovedSquare) {
    Image rendered(8, 8), target(8, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) rendered.at(x, y) = target.at(x, y) = Color3f(0.05f * float(x + y));
    for (int y = 3; y < 5; ++y)
        for (int x = 2; x < 4; ++x) {
            rendered.at(x, y) = Color3f(1.f);
            target.at(x + 2, y) = Color3f(1.f);
        }
    SinkhornOptions o;
    o.tolerance = 1e-8;
    const ScreenSamples source = image_samples(rendered);
    const ScreenSamples self = match_image_debiased(rendered, rendered, o);
    EXPECT_EQ((self.position - source.position).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((self.colour - source.colour).cwiseAbs().maxCoeff(), 0.0);
    const ScreenSamples moved = match_image_debiased(rendered, target, o);
    for (int y = 3; y < 5; ++y)
        for (int x = 2; x < 4; ++x) {
            const int i = y * 8 + x;
            EXPECT_NEAR(moved.position(i, 0), source.position(i, 0) + 2.0 / 8, 1e-6) << x << "," << y;
        }
}

// The jackknife over two halves of an image's passes (jackknife_matching_loss): the gradient is
// w0 g(Î) + w (g(Î1) + g(Î2)) with no 1/passes term, w0 = 2, w = −½ for equal halves, w0 = 1.6, w = −0.3 for
// 1 + 3 passes (1.6/4 − 0.3 (1 + 1/3) = 0), the value the whole image's; identical halves give the plain
// matching.
TEST(MatchingLoss, JackknifeCombinesTheMatchingsOfTheHalves) {
    Image target(8, 8), first(8, 8), second(8, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const float base = (x >= 3 && x < 5 && y >= 3 && y < 5) ? 0.8f : 0.05f * float(x + y) / 14.f;
            target.at(x, y) = Color3f(base);
            first.at(x, y) = Color3f(base * (1.f + 0.3f * std::sin(float(3 * x + y))));
            second.at(x, y) = Color3f(base * (1.f + 0.3f * std::cos(float(x + 5 * y))));
        }
    SinkhornOptions o;
    o.scaling = 0.5;
    o.max_iterations = 1;
    auto expect_combination = [&](int n1, int n2, double w0, double w) {
        const SplitImage split{first, second, n1, n2};
        const MatchingLossResult r = jackknife_matching_loss(split, target, o);
        const MatchingLossResult whole = image_matching_loss(split.whole(), target, o);
        const MatchingLossResult a = image_matching_loss(first, target, o),
                                 b = image_matching_loss(second, target, o);
        EXPECT_NEAR((r.d_position - (w0 * whole.d_position + w * (a.d_position + b.d_position)))
                        .cwiseAbs()
                        .maxCoeff(),
                    0.0, 1e-12);
        EXPECT_NEAR(
            (r.d_colour - (w0 * whole.d_colour + w * (a.d_colour + b.d_colour))).cwiseAbs().maxCoeff(), 0.0,
            1e-12);
        EXPECT_EQ(r.value, whole.value);
    };
    expect_combination(2, 2, 2.0, -0.5);
    expect_combination(1, 3, 1.6, -0.3);
    const MatchingLossResult plain = image_matching_loss(first, target, o);
    const MatchingLossResult same = jackknife_matching_loss({first, first, 4, 4}, target, o);
    EXPECT_NEAR((same.d_position - plain.d_position).cwiseAbs().maxCoeff(), 0.0, 1e-12);
    EXPECT_NEAR((same.d_colour - plain.d_colour).cwiseAbs().maxCoeff(), 0.0, 1e-12);
    EXPECT_THROW(jackknife_matching_loss({first, Image(4, 4), 2, 2}, target, o), Error);
    EXPECT_THROW(jackknife_matching_loss({first, second, 0, 2}, target, o), Error);
}
