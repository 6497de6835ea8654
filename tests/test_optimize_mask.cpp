// The `free` mask of a vertex_positions broadcast from 3 booleans (x, y, z of every vertex; optim/problem.h),
// alone and with the large-steps parameterization (optim/large_steps.h), on the height-field slab of
// scenes/dpm/image (65 x 65 vertices).
#include "core/error.h"
#include "optim/optimize.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

using namespace penumbra;

namespace {

const std::string image_dir = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/dpm/image/";

OptimizedParameter heights(double large_steps_lambda) {
    OptimizedParameter p{"slab_top.vertex_positions", {}, 0.01};
    p.free = {false, true, false};
    p.large_steps_lambda = large_steps_lambda;
    return p;
}

// Five Adam steps with a dense random gradient: x and z stay bit-identical, y moves at every vertex.
void expect_heights_only(double large_steps_lambda) {
    auto scene = load_scene(image_dir + "scene.xml", {{"res", "8"}});
    InverseProblem problem(*scene, {heights(large_steps_lambda)});
    ASSERT_EQ(problem.dimension(), 3 * 65 * 65);
    const std::vector<double> before = problem.values();
    Adam adam(problem.adam_groups(), problem.dimension());
    std::mt19937 rng(7);
    std::normal_distribution<double> normal;
    for (int i = 0; i < 5; ++i) {
        std::vector<double> g(before.size());
        for (double& v : g)
            v = normal(rng);
        problem.adam_step(adam, g, 1.0);
    }
    const std::vector<double> after = problem.values();
    int moved = 0;
    for (size_t k = 0; k < after.size(); ++k) {
        if (k % 3 != 1)
            ASSERT_EQ(after[k], before[k]) << "component " << k;
        else
            moved += after[k] != before[k];
    }
    EXPECT_EQ(moved, 65 * 65);
}

} // namespace

TEST(OptimizeMask, VertexMaskMovesHeightsOnly) { expect_heights_only(0); }

TEST(OptimizeMask, VertexMaskWithLargeSteps) { expect_heights_only(19); }

TEST(OptimizeMask, BadMasksAreErrors) {
    auto scene = load_scene(image_dir + "scene.xml", {{"res", "8"}});
    const auto error_of = [&](const OptimizedParameter& p) {
        try {
            InverseProblem problem(*scene, {p});
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    OptimizedParameter p = heights(0);
    p.free = {true, false};
    EXPECT_NE(error_of(p).find("'free' has 2 entries for 12675 components (or 3: x, y, z of every vertex)"),
              std::string::npos)
        << error_of(p);
    p = heights(19);
    p.free.assign(3 * 65 * 65, true);
    EXPECT_NE(error_of(p).find("takes a 'free' mask of 3 components only"), std::string::npos) << error_of(p);
    p = heights(19);
    p.upper = 3;
    EXPECT_NE(error_of(p).find("the large-steps parameterization takes no bounds"), std::string::npos)
        << error_of(p);
    OptimizedParameter translate{"slab_top.translate", {}, 0.01};
    translate.free = {false, true, false, true};
    EXPECT_NE(error_of(translate).find("'free' has 4 entries for 3 components"), std::string::npos)
        << error_of(translate);
    EXPECT_EQ(error_of(heights(19)), "");
}
