// The NaN policy (diff/method.h): a sample whose value or derivative is not finite is left out of the
// estimate, counted and reported, so that one bad sample never poisons an image or a gradient; and inputs
// that invite NaNs (degenerate and duplicate triangles, roughness 0 and 1e-8, a camera grazing a plane)
// render and differentiate with finite outputs.
#include "robustness_test_util.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

using namespace penumbra;
using namespace penumbra::test;

namespace {

bool warns_of_dropped_samples(const std::vector<std::string>& warnings) {
    for (const std::string& w : warnings)
        if (w.find("non-finite value or derivative were left out") != std::string::npos) return true;
    return false;
}

} // namespace

// A reflectance poisoned with NaN behind the loaders' checks (as a bug would): every sample through the box is
// non-finite; the images and gradients stay finite, and every front reports the count.
TEST(NanPolicy, PoisonedSamplesAreDroppedCountedAndReported) {
    auto scene = load_scene_string(scene_xml(R"(<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>)"));
    {
        Parameters params(*scene);
        params.find("box.bsdf.reflectance").data[1] = std::numeric_limits<float>::quiet_NaN();
    }
    for (const char* method : {"psdr", "interior"}) {
        const Outputs o = render_and_differentiate(*scene, "box.translate=1,0,0", method);
        std::printf("  %s: dropped %llu of the render's samples, %llu (derivative), %llu (gradient)\n",
                    method, (unsigned long long)o.render.dropped_samples,
                    (unsigned long long)o.derivative.cost.dropped,
                    (unsigned long long)o.gradient.cost.dropped);
        EXPECT_GT(o.render.dropped_samples, 0u);
        EXPECT_GT(o.derivative.cost.dropped, 0u) << method;
        EXPECT_TRUE(warns_of_dropped_samples(o.derivative.warnings)) << method;
        EXPECT_GT(o.gradient.cost.dropped, 0u) << method;
        EXPECT_TRUE(warns_of_dropped_samples(o.gradient.warnings)) << method;
    }
    // Path sampling (paper 002) differentiates the light's radiance.
    const Outputs p = render_and_differentiate(*scene, "light.emitter.radiance", "paths");
    EXPECT_GT(p.derivative.cost.dropped, 0u);
    EXPECT_GT(p.gradient.cost.dropped, 0u);
    EXPECT_TRUE(warns_of_dropped_samples(p.gradient.warnings));
}

// Nothing is dropped, and nothing said, in a healthy scene.
TEST(NanPolicy, AHealthySceneDropsNothing) {
    auto scene = load_scene_string(scene_xml(R"(<bsdf type="diffuse"/>)"));
    const Outputs o = render_and_differentiate(*scene, "box.translate=1,0,0");
    EXPECT_EQ(o.render.dropped_samples, 0u);
    EXPECT_EQ(o.derivative.cost.dropped, 0u);
    EXPECT_EQ(o.gradient.cost.dropped, 0u);
    EXPECT_FALSE(warns_of_dropped_samples(o.derivative.warnings));
}

// Inputs that invite NaNs render and differentiate with finite outputs.
TEST(NanPolicy, NearDegenerateInputsStayFinite) {
    const TempDir dir;
    // Two triangles of the unit square, a zero-area triangle (three collinear vertices), a duplicate face and
    // a face with a repeated vertex.
    const std::string mesh = dir.write("degenerate.obj", "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 0 0\n"
                                                         "f 1 3 2\nf 1 4 3\nf 1 5 3\nf 1 4 3\nf 2 2 3\n");
    const std::string glossy = R"(<bsdf type="roughconductor"><float name="alpha" value="%"/></bsdf>)";
    const auto alpha = [&](const char* a) { return std::string(glossy).replace(glossy.find('%'), 1, a); };
    struct Case {
        const char* name;
        std::string xml;
    };
    const Case cases[] = {
        {"degenerate and duplicate triangles",
         scene_xml(R"(<bsdf type="diffuse"/>)", R"(<bsdf type="diffuse"/>)",
                   R"(<shape type="obj" id="box"><string name="filename" value=")" + mesh + R"("/>)")},
        {"roughness 0", scene_xml(alpha("0"), alpha("0"))},
        {"roughness 1e-8", scene_xml(alpha("1e-8"), R"(<bsdf type="roughplastic"><float name="alpha" value="1e-8"/></bsdf>)")},
        {"a camera grazing the floor",
         scene_xml(alpha("0.1"), alpha("0.01"), R"(<shape type="cube" id="box">)",
                   R"(<lookat origin="0,0,4" target="0,0,0" up="0,1,0"/>)")},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        auto scene = load_scene_string(c.xml);
        render_and_differentiate(*scene, "box.translate=1,0,0");
    }
}

// A light of zero area is refused with a clear error, not rendered as NaNs.
TEST(NanPolicy, AZeroAreaLightIsAClearError) {
    std::string xml = scene_xml(R"(<bsdf type="diffuse"/>)");
    xml.replace(xml.find(R"(<scale value="0.5"/>)"), 20, R"(<scale x="0.5" y="0" z="1"/>)");
    try {
        load_scene_string(xml);
        FAIL() << "a zero-area light loaded";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("area"), std::string::npos) << e.what();
    }
}
