// The equal-time study of derivative methods (studies/equal_time.h, `penumbra equal-time`) at a reduced size:
// the method specifications, the rows, and that variance × time does not depend on the sample count (the
// premise of comparing methods by it). The measured ratios are in docs/differentiable-media.md.
#include "core/error.h"
#include "scene/scene.h"
#include "studies/equal_time.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

using namespace penumbra;

namespace {

const std::string validation = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

} // namespace

TEST(EqualTime, MethodSpecifications) {
    const MethodSpec psdr = parse_method_spec("psdr --direct-spp 8 --no-guiding");
    EXPECT_EQ(psdr.name, "psdr");
    EXPECT_EQ(psdr.options.values().at("direct-spp"), "8");
    EXPECT_EQ(psdr.options.values().at("no-guiding"), "true");
    EXPECT_THROW(parse_method_spec("--no-guiding"), Error);
    EXPECT_THROW(parse_method_spec("psdr 8"), Error);
    EXPECT_THROW(parse_method_spec("psdr --q 0.3"), Error); // an option of another method
    EXPECT_THROW(parse_method_spec("nope"), Error);
}

// The same method at 8 and 32 spp per batch: the variance falls about 4x, the time rises about 4x, and their
// product stays within a factor of 2 (CPU time on a shared machine is good to ~20%, the variance of 4 batches
// over 16² pixels to ~10%). The interior method on a medium parameter: every sample goes to one term, so the
// variance scales with the sample count (psdr with fixed boundary budgets would not).
TEST(EqualTime, VarianceTimesTimeIsIndependentOfTheSampleCount) {
    auto scene = load_scene(validation + "medium_params.xml", {{"res", "16"}});
    Parameters params(*scene);
    params.enable({parse_param_selection("smoke.scale")});
    const std::vector<MethodSpec> methods = {parse_method_spec("interior")};
    EqualTimeOptions o;
    o.batches = 4;
    o.warm_up = false;
    o.spp = 8;
    const EqualTimeRow low = equal_time_study(*scene, params, methods, o).at(0);
    o.spp = 32;
    const EqualTimeRow high = equal_time_study(*scene, params, methods, o).at(0);
    std::printf("  8 spp: %.3f s, variance %.4g; 32 spp: %.3f s, variance %.4g\n", low.seconds_per_batch,
                low.variance, high.seconds_per_batch, high.variance);
    ASSERT_GT(low.variance, 0.0);
    EXPECT_GT(low.variance / high.variance, 2.0);
    EXPECT_GT(high.variance_time / low.variance_time, 0.5);
    EXPECT_LT(high.variance_time / low.variance_time, 2.0);
}
