// linearcurve / bsplinecurve: the curve file format, Mitsuba's uv convention and the silhouette of straight
// curves seen from the side (2 r L, plus pi r^2 for the end caps of a linear curve).
#include "diff/parameters.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "scene/scene.h"

#include "shape_test_util.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;

namespace {

std::string curve_shape(const std::string& type, const std::string& file) {
    return "<shape type=\"" + type + "\"><string name=\"filename\" value=\"" + file +
           "\"/><ref id=\"black\"/></shape>";
}

// Tolerance of a rendered projected area: 4 standard errors plus the tessellation's deficit (a ring of 32
// vertices is at least cos(pi/32) = 0.995 as wide as the tube; a cap sphere's outline (32-gon) keeps at least
// 98% of its area).
double tolerance(const test::ProjectedArea& a, double tube, double caps) {
    return 4.0 * a.stderr_value + 0.005 * tube + 0.02 * caps;
}

} // namespace

TEST(ShapeCurves, StraightLinearCurveCoversTwoRLPlusItsEndCaps) {
    test::TempDir dir;
    // Length 3 in the xz plane (tilted), radius 0.1, seen along +y.
    dir.write("line.txt", "-1.2 0 -0.9 0.1\n1.2 0 0.9 0.1\n");
    const auto scene =
        load_scene_string(test::projected_area_scene(curve_shape("linearcurve", "line.txt")), dir.str());
    const double tube = 2.0 * 0.1 * 3.0, caps = Pi * 0.01;
    const test::ProjectedArea a = test::projected_area(*scene, 16, 32);
    RecordProperty("area", std::to_string(a.value) + " +- " + std::to_string(a.stderr_value) + " (exact " +
                               std::to_string(tube + caps) + ")");
    EXPECT_NEAR(a.value, tube + caps, tolerance(a, tube, caps));
    EXPECT_GT(std::abs(a.value - tube), 4.0 * tolerance(a, tube, caps)); // the caps are resolved
}

TEST(ShapeCurves, StraightBSplineIsOpenEnded) {
    test::TempDir dir;
    // Collinear, evenly spaced points p0..p5 (spacing 0.5 along x): the spline runs from p1 to p4
    // (length 1.5).
    std::string text;
    for (int i = 0; i < 6; ++i)
        text += std::to_string(-1.25 + 0.5 * i) + " 0 0.3 0.15\n";
    dir.write("spline.txt", text);
    const auto scene =
        load_scene_string(test::projected_area_scene(curve_shape("bsplinecurve", "spline.txt")), dir.str());
    const double tube = 2.0 * 0.15 * 1.5;
    const test::ProjectedArea a = test::projected_area(*scene, 16, 32);
    RecordProperty("area", std::to_string(a.value) + " +- " + std::to_string(a.stderr_value) + " (exact " +
                               std::to_string(tube) + ")");
    EXPECT_NEAR(a.value, tube, tolerance(a, tube, 0.0));
}

// Mitsuba's frame: u_rot = +z made orthogonal to the tangent, u_rad = u_rot x tangent; u = 0 on u_rad,
// 1/4 on u_rot; v runs along the curve over all its segments.
TEST(ShapeCurves, UvFollowsMitsuba) {
    test::TempDir dir;
    dir.write("line.txt", "0 0 0 0.2\n1 0 0 0.2\n2 0 0 0.2\n");
    const auto scene = load_scene_string(
        test::scene("<shape type=\"linearcurve\"><string name=\"filename\" value=\"line.txt\"/></shape>"),
        dir.str());
    // Tangent +x: u_rot = +z, u_rad = z x x = +y.
    const SurfaceInteraction3f side = scene->intersect(Ray({1.5f, 5.f, 0.f}, {0.f, -1.f, 0.f}));
    ASSERT_TRUE(side.is_valid());
    EXPECT_NEAR(side.p.y, 0.2f, 1e-3f);
    EXPECT_NEAR(std::fmod(side.uv.x + 0.5f, 1.f), 0.5f, 0.02f); // u = 0 (or 1 across the seam)
    EXPECT_NEAR(side.uv.y, 0.75f, 1e-3f);                       // second of two segments, halfway
    const SurfaceInteraction3f top = scene->intersect(Ray({0.5f, 0.f, 5.f}, {0.f, 0.f, -1.f}));
    ASSERT_TRUE(top.is_valid());
    EXPECT_NEAR(top.uv.x, 0.25f, 0.02f);
    EXPECT_NEAR(top.uv.y, 0.25f, 1e-3f);
    EXPECT_NEAR(top.n.z, 1.f, 1e-2f);
}

TEST(ShapeCurves, FileErrorsNameTheFileAndLine) {
    test::TempDir dir;
    dir.write("short.txt", "0 0 0 0.1\n1 0 0 0.1\n2 0 0 0.1\n\n0 1 0 0.1\n1 1 0 0.1\n2 1 0 0.1\n3 1 0 0.1\n");
    dir.write("bad.txt", "0 0 0 0.1\n1 0 zero 0.1\n");
    auto error = [&](const std::string& type, const std::string& file) {
        try {
            load_scene_string(test::scene("<shape type=\"" + type + "\"><string name=\"filename\" value=\"" +
                                          file + "\"/></shape>"),
                              dir.str());
        } catch (const LoadError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string few = error("bsplinecurve", "short.txt");
    EXPECT_NE(few.find("short.txt:1: a bsplinecurve needs at least 4 control points"), std::string::npos)
        << few;
    EXPECT_NE(few.find("<string>:2"), std::string::npos) << few;
    const std::string bad = error("linearcurve", "bad.txt");
    EXPECT_NE(bad.find("bad.txt:2: expected a control point"), std::string::npos) << bad;
    EXPECT_EQ(error("linearcurve", "short.txt"), "no error");
    try {
        load_scene_string(test::scene(R"(<shape type="linearcurve"><string name="filename" value="short.txt"/>
            <emitter type="area"/></shape>)"),
                          dir.str());
        ADD_FAILURE() << "a linearcurve emitter was accepted";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("a linearcurve cannot carry an area emitter"), std::string::npos)
            << e.what();
    }
}

// The tessellation's vertices are not parameters (Mitsuba's curves expose control_points instead).
TEST(ShapeCurves, TessellationVerticesAreNotParameters) {
    test::TempDir dir;
    dir.write("line.txt", "0 0 0 0.1\n1 0 0 0.1\n");
    const auto scene = load_scene_string(
        test::scene(
            R"(<shape type="linearcurve" id="curve"><string name="filename" value="line.txt"/></shape>)"),
        dir.str());
    Parameters params(*scene);
    EXPECT_THROW(params.find("curve.vertex_positions"), Error);
    EXPECT_NO_THROW(params.find("curve.translate"));
}

// Curves are meshes, so their motions are differentiated like any shape's: a bent curve moving sideways in
// front of an emitting panel (max_depth 1: the primary boundary term of its silhouette) against central
// differences (diff_check.h tolerances). Before the ring seams were welded (curve_tube.cpp), the seam ran
// along the silhouette as a pair of boundary edges and this failed (relerr4 0.8-2.0, |z| > 20).
class CurveDerivative : public ::testing::TestWithParam<const char*> {};

TEST_P(CurveDerivative, TranslateMatchesFiniteDifferences) {
    test::TempDir dir;
    dir.write("bent.txt",
              "-0.9 -0.5 0 0.08\n-0.6 -0.5 0 0.08\n0.1 0.4 0 0.1\n0.6 -0.3 0.1 0.06\n0.8 -0.3 0.1 0.06\n");
    const auto scene =
        load_scene_string(R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="1"/></integrator>
      <sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film></sensor>
      <shape type=")" + std::string(GetParam()) +
                              R"(" id="curve"><string name="filename" value="bent.txt"/></shape>
      <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform>
        <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
    </scene>)",
                          dir.str());
    Parameters params(*scene);
    params.enable({parse_param_selection("curve.translate=1,0.5,0")});
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.batches = 16;
    o.interior.seed = 3;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 16;
    o.direct_spp = o.indirect_spp = o.pixel_spp = 0; // max_depth 1: no light paths; the camera does not move
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 256;
    ro.seed = 5;
    const FiniteDifference fd = finite_difference(*scene, params, 2e-3, ro, 16);
    const test::DiffCheck c = test::check_against(d, fd);
    RecordProperty("check", test::describe(c));
    EXPECT_TRUE(c.passes()) << test::describe(c);
}

INSTANTIATE_TEST_SUITE_P(ShapeCurves, CurveDerivative, ::testing::Values("linearcurve", "bsplinecurve"));
