// Each bidirectional strategy alone (strategy_s, strategy_t: no MIS weights) is an unbiased estimator of the
// paths of s + t - 1 segments, so every strategy of a given length must agree with next-event estimation
// (s = 1) of that length. This checks each contribution on its own, which the MIS-weighted sum cannot (a
// wrong strategy with a small weight barely shows). The scene mixes surfaces and a scattering medium (a
// null-bounded cube inside the box), so surface and medium vertices meet in every kind of connection. The
// camera is outside the medium: connecting medium points arbitrarily close to the camera (t = 1, W / d²)
// would make the unweighted light tracing estimate's variance infinite.
// Tolerance: image-mean |z| < 4 with standard errors from 16 independent renders of each (~30 degrees of
// freedom: P(|t| > 4) ~ 4e-4 per strategy). Unweighted strategies have heavy-tailed estimates (connections
// of nearby vertices, the light hit through the medium), hence many samples per render: with few, the spread
// of the renders underestimates the standard error.
#include "test_bdpt_util.h"

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string foggy_box(int s, int t) {
    const int depth = s + t - 1;
    return "<scene version=\"3.0.0\">" +
           integrator_xml("bdpt", "<integer name=\"max_depth\" value=\"" + std::to_string(depth) +
                                      "\"/><integer name=\"strategy_s\" value=\"" + std::to_string(s) +
                                      "\"/><integer name=\"strategy_t\" value=\"" + std::to_string(t) +
                                      "\"/>") +
           bdpt_sensor("perspective", "<lookat origin=\"0,0,-0.95\" target=\"0,0,1\" up=\"0,1,0\"/>", 70.f,
                       16) +
           "<shape type=\"cube\"><boolean name=\"flip_normals\" value=\"true\"/><bsdf type=\"diffuse\"><rgb "
           "name=\"reflectance\" value=\"0.6,0.5,0.4\"/></bsdf></shape>"
           "<shape type=\"sphere\"><point name=\"center\" value=\"0.35,-0.6,0.3\"/><float name=\"radius\" "
           "value=\"0.35\"/><bsdf type=\"diffuse\"/></shape>"
           "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.45\"/><translate "
           "value=\"-0.3,-0.2,0.3\"/></transform><bsdf type=\"null\"/><medium type=\"homogeneous\" "
           "name=\"interior\"><float name=\"sigma_t\" value=\"1.5\"/><float name=\"albedo\" value=\"0.8\"/>"
           "<phase type=\"hg\"><float name=\"g\" value=\"0.3\"/></phase></medium></shape>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.5\"/><rotate x=\"1\" "
           "angle=\"90\"/><translate value=\"0,0.95,0\"/></transform><emitter type=\"area\"><rgb "
           "name=\"radiance\" value=\"4\"/></emitter></shape></scene>";
}

TEST(BDPTStrategies, EachStrategyAloneAgreesWithNextEventEstimation) {
    for (int depth = 2; depth <= 3; ++depth) {
        const auto nee = load_scene_string(foggy_box(1, depth));
        const BlockStats reference = block_stats(*nee, 16, 64, 7);
        for (int s = 0; s <= depth; ++s) {
            const int t = depth + 1 - s;
            if (s == 1) continue;
            const auto scene = load_scene_string(foggy_box(s, t));
            const BlockStats b = block_stats(*scene, 16, 128, 1007);
            const double z = z_scores(b, reference)[0];
            std::printf("[bdpt strategy (%d, %d)] mean %.5f (stderr %.5f) vs NEE (1, %d) %.5f (stderr %.5f), "
                        "z = %.2f\n",
                        s, t, b.mean[0], b.stderr_[0], depth, reference.mean[0], reference.stderr_[0], z);
            EXPECT_GT(b.mean[0], 0.0);
            EXPECT_LT(std::abs(z), 4.0) << "strategy (" << s << ", " << t << ")";
        }
    }
}

} // namespace
