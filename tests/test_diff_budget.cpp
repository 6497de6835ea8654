// The calibrated split of one sample budget over psdr's terms (diff/psdr/budget.h): it spends the budget where the
// variance is, beating the equal split at equal cost, and stays reproducible per seed.
#include "diff/psdr/budget.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

const std::string validation = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

// Σ per-pixel variance of the total times the work it took: the inverse efficiency of a split.
double variance_times_cost(const DerivativeImage& d) {
    double variance = 0, cost = 0;
    for (const Color3f& s : d.stderr_img.pixels)
        variance += double(s.x) * s.x + double(s.y) * s.y + double(s.z) * s.z;
    for (const DerivativeTerm& t : d.terms)
        cost += t.cost.units();
    return variance * cost;
}

PsdrOptions base_options(const Scene& scene) {
    PsdrOptions o;
    o.interior.batches = 8;
    o.interior.seed = 3;
    o.interior.path = path_settings(scene);
    return o;
}

} // namespace

// The area light's soft shadow of an occluder out of view: all of the derivative is the direct term's, and the
// calibration gives it most of the budget. At the same cost the equal split (Mitsuba's sppc = sppp = sppi) has
// 2.2–2.7 times the variance (seeds 1–6).
TEST(Budget, CalibratedSplitBeatsTheEqualSplitAtEqualCost) {
    auto scene = load_scene(validation + "shadow.xml", {{"res", "24"}});
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const int spp = 128;
    const PsdrOptions calibrated = psdr_budget(*scene, params, base_options(*scene), spp);
    PsdrOptions equal = base_options(*scene);
    equal.interior.spp = equal.primary_spp = equal.direct_spp = equal.indirect_spp = equal.pixel_spp = spp / 8;
    std::printf("  calibrated: %s\n", describe_budget(calibrated).c_str());
    EXPECT_GT(calibrated.direct_spp, 2 * calibrated.interior.spp) << describe_budget(calibrated);
    const double ratio = variance_times_cost(psdr_derivative(*scene, params, equal)) /
                         variance_times_cost(psdr_derivative(*scene, params, calibrated));
    std::printf("  variance x cost: equal split / calibrated = %.2f\n", ratio);
    EXPECT_GT(ratio, 2.0);
}

// The split comes from counted work (rays, tape nodes), not from timings: the same for any thread count, and
// so is the image.
TEST(Budget, SameSplitAndImageForAnyThreadCount) {
    auto scene = load_scene(validation + "silhouette.xml", {{"res", "16"}});
    Parameters params(*scene);
    params.enable({parse_param_selection("box.translate=1,0,0")});
    PsdrOptions one = base_options(*scene), two = base_options(*scene);
    one.interior.threads = 1;
    two.interior.threads = 2;
    const PsdrOptions a = psdr_budget(*scene, params, one, 64), b = psdr_budget(*scene, params, two, 64);
    EXPECT_EQ(describe_budget(a), describe_budget(b));
    const DerivativeImage da = psdr_derivative(*scene, params, a), db = psdr_derivative(*scene, params, b);
    for (size_t i = 0; i < da.derivative.pixels.size(); ++i)
        ASSERT_EQ(da.derivative.pixels[i], db.derivative.pixels[i]) << "pixel " << i;
}

// Reverse mode: the split for a gradient, and the gradient with it, are those of the same calibration.
TEST(Budget, GradientBudgetFollowsTheVariance) {
    auto scene = load_scene(validation + "shadow.xml", {{"res", "24"}});
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    Image adjoint(24, 24);
    for (Color3f& a : adjoint.pixels) a = Color3f(1.f);
    PsdrOptions base = base_options(*scene);
    base.interior.batches = 1;
    const PsdrOptions o = psdr_gradient_budget(*scene, params, adjoint, base, 128);
    std::printf("  gradient budget: %s\n", describe_budget(o).c_str());
    EXPECT_GT(o.direct_spp, 2 * o.interior.spp) << describe_budget(o);
    EXPECT_TRUE(std::isfinite(psdr_gradient(*scene, params, adjoint, o).values[0]));
}
