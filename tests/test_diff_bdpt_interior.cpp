// The bidirectional estimator of the interior term (paper 001 §7; src/diff/psdr/bdpt_interior.h) against central
// finite differences of the bdpt renderer: a point light in or above a fog-filled box (homogeneous, or a
// heterogeneous grid) over a floor, with and without a rough-glass sphere (a caustic that only light subpaths
// find from a point light); derivatives w.r.t. σt, the albedo, the HG g, a grid's scale, a surface
// reflectance and the point light's translation (no occluder: the light's motion moves no visibility edge, so
// the interior term is the whole derivative), with image-space and material-form first vertices. Also:
// bidirectional and unidirectional estimators agree (medium, floor and light motions), forward and reverse
// mode are adjoint, and the bidirectional derivative of a small light's caustic has a lower variance at equal
// samples.
#include "diff_check.h"
#include "media_test_util.h"
#include "xml_test_util.h"

#include "core/rng.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A fog-filled box (null boundary, camera outside) with a diffuse floor inside and a point light `lamp` above
// it (`small_area_light`: a small emitting sphere instead, which path tracing can hit through the ball);
// `sphere` adds a rough dielectric ball between them. Grey σt: bdpt's per-channel free flights stay
// unweighted, so the FD references have light tails.
std::string lamp_scene(bool sphere, bool small_area_light = false, const char* lamp = "0.1, 0.7, 0",
                       const char* sigma_t = "0.6") {
    const int size = 16;
    return R"(<scene version="3.0.0">
      <integrator type="bdpt"><integer name="max_depth" value="5"/></integrator>
      <medium type="homogeneous" id="fog">
        <rgb name="sigma_t" value=")" +
           std::string(sigma_t) + R"("/><rgb name="albedo" value="0.8, 0.7, 0.6"/>
        <phase type="hg"><float name="g" value="0.3"/></phase></medium>
      <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 0.3, 4" target="0, -0.2, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value=")" +
           std::to_string(size) + R"("/><integer name="height" value=")" + std::to_string(size) + R"("/>
          <rfilter type="gaussian"/></film>
      </sensor>
      <shape type="cube" id="box"><bsdf type="null"/><ref name="interior" id="fog"/></shape>
      <shape type="rectangle" id="floor">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/><translate value="0,-0.9,0"/></transform>
        <bsdf type="diffuse" id="floor_bsdf"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf>
      </shape>
      )" +
           (small_area_light ? R"(<shape type="sphere"><point name="center" value="0.1, 0.7, 0"/>
        <float name="radius" value="0.05"/><emitter type="area"><rgb name="radiance" value="95, 95, 95"/></emitter></shape>)"
                             : R"(<emitter type="point" id="lamp"><point name="position" value=")" +
                                   std::string(lamp) + R"("/>
        <rgb name="intensity" value="3, 3, 3"/></emitter>)") +
           (sphere ? R"(
      <shape type="sphere" id="ball"><point name="center" value="0, 0.05, 0"/><float name="radius" value="0.4"/>
        <bsdf type="roughdielectric"><float name="alpha" value="0.3"/></bsdf></shape>)"
                   : "") +
           R"(
    </scene>)";
}

DiffOptions options_for(const Scene& scene, int spp, InteriorEstimator estimator) {
    DiffOptions o;
    o.spp = spp;
    o.batches = 16;
    o.seed = 7;
    o.path = path_settings(scene);
    o.path.max_depth = 5; // bdpt's
    o.estimator = estimator;
    return o;
}

DiffCheck bdpt_check(Scene& scene, const std::string& selection, int spp, int spp_fd, double h) {
    Parameters params(scene);
    params.enable({parse_param_selection(selection)});
    const DerivativePair r = derivative_and_fd(scene, params, spp, spp_fd, h);
    return check_against(r.derivative, r.fd);
}

struct BdptParam {
    bool sphere;
    const char* selection;
    double h;
    int spp, spp_fd;
};

class BdptInterior : public ::testing::TestWithParam<BdptParam> {};

// The mean squared standard error of an image's pixels and channels.
double mean_variance(const Image& stderr_img) {
    double v = 0;
    for (const Color3f& p : stderr_img.pixels)
        v += double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z;
    return v / (3.0 * stderr_img.pixels.size());
}

} // namespace

TEST_P(BdptInterior, MatchesFiniteDifferences) {
    const BdptParam& p = GetParam();
    // The moving lamp hangs above the fog: medium vertices near a point light make the derivative of its
    // 1/ℓ² falloff heavy-tailed (∝ 1/ℓ³), which batch standard errors do not capture.
    auto scene = load_scene_string(p.sphere ? lamp_scene(true) : lamp_scene(false, false, "0.1, 1.3, 0"));
    const DiffCheck c = bdpt_check(*scene, p.selection, p.spp, p.spp_fd, p.h);
    std::printf("%s: %s\n", p.selection, describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}

INSTANTIATE_TEST_SUITE_P(Parameters, BdptInterior,
                         ::testing::Values(BdptParam{true, "fog.sigma_t", 0.04, 16, 128},
                                           BdptParam{true, "fog.albedo", 0.02, 16, 128},
                                           BdptParam{false, "fog.phase_function.g", 0.05, 16, 128},
                                           BdptParam{false, "floor_bsdf.reflectance", 0.02, 16, 128},
                                           BdptParam{false, "lamp.translate=0.5,1,0", 0.02, 16, 128}),
                         [](const auto& info) {
                             std::string name =
                                 std::string(info.param.sphere ? "ball_" : "open_") + info.param.selection;
                             for (char& ch : name)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return name;
                         });

// A heterogeneous fog (a smooth blob of density over the box): free flights by delta tracking along the
// subpaths and ratio tracking along connections, re-evaluated from their records.
TEST(BdptInterior, HeterogeneousMediumMatchesFiniteDifferences) {
    TempDir dir;
    write_bytes(dir.str() + "/density.vol",
                vol_bytes({8, 8, 8}, 1, Vec3f(-1.f), Vec3f(1.f), [](int x, int y, int z, int) {
                    const float u = x / 7.f - 0.5f, v = y / 7.f - 0.4f, w = z / 7.f - 0.5f;
                    return 0.3f + 1.5f * std::exp(-(u * u + v * v + w * w) / 0.08f);
                }));
    std::string xml = lamp_scene(false, false, "0.1, 1.3, 0");
    const size_t begin = xml.find("<medium"), end = xml.find("</medium>") + 9;
    xml.replace(begin, end - begin, R"(<medium type="heterogeneous" id="fog">
        <volume type="gridvolume" name="sigma_t"><string name="filename" value="density.vol"/></volume>
        <float name="scale" value="0.8"/><rgb name="albedo" value="0.8, 0.7, 0.6"/>
        <phase type="hg"><float name="g" value="0.3"/></phase></medium>)");
    auto scene = load_scene_string(xml, dir.str());
    const DiffCheck c = bdpt_check(*scene, "fog.scale", 32, 256, 0.05);
    std::printf("heterogeneous fog.scale: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}

// The material-form first vertex (the camera factor of the film, antithetic pairs) in the same estimator.
TEST(BdptInterior, MaterialFormFirstVertexMatchesFiniteDifferences) {
    auto scene = load_scene_string(lamp_scene(false, false, "0.1, 1.3, 0"));
    Parameters params(*scene);
    params.enable({parse_param_selection("lamp.translate=0.5,1,0")});
    DiffOptions o = options_for(*scene, 16, InteriorEstimator::Bidirectional);
    o.first_vertex = FirstVertex::Material;
    const DerivativeImage d = render_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 128;
    ro.seed = 1234;
    const FiniteDifference fd = finite_difference(*scene, params, 0.02, ro, 16);
    const DiffCheck c = check_against(d, fd);
    std::printf("material form: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}

// Both estimators are unbiased for the same interior term (the same material form, the same image-space first
// vertex), whether or not the parameter moves visibility edges (a moving floor does at the box's faces):
// their images agree within their standard errors. Thin fog: medium vertices next to the moving floor make
// the derivative of the connections' 1/ℓ² heavy-tailed (∝ 1/ℓ³) in both estimators, and in a dense fog the
// image means of 16 × 8 samples swing by several of their (underestimated) standard errors.
class BdptAgreement : public ::testing::TestWithParam<const char*> {};

TEST_P(BdptAgreement, AgreesWithTheUnidirectionalEstimator) {
    auto scene = load_scene_string(lamp_scene(false, false, "0.1, 1.3, 0", "0.1"));
    Parameters params(*scene);
    params.enable({parse_param_selection(GetParam())});
    const DerivativeImage bi =
        render_derivative(*scene, params, options_for(*scene, 8, InteriorEstimator::Bidirectional));
    const DerivativeImage uni =
        render_derivative(*scene, params, options_for(*scene, 8, InteriorEstimator::Unidirectional));
    const DiffCheck c = check_against(bi.derivative, bi.stderr_img, uni.derivative, uni.stderr_img);
    std::printf("%s, bidirectional vs unidirectional: %s\n", GetParam(), describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}

INSTANTIATE_TEST_SUITE_P(Parameters, BdptAgreement,
                         ::testing::Values("fog.sigma_t", "floor.translate=0,1,0", "lamp.translate=0.5,1,0"),
                         [](const auto& info) {
                             std::string name = info.param;
                             for (char& ch : name)
                                 if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                             return name;
                         });

// The caustic of a small light through the ball (in the fog and on the floor), which path tracing finds only
// by hitting the light through the glass: at equal samples the bidirectional derivative's variance is lower.
TEST(BdptInterior, LowerVarianceThanUnidirectionalOnTheCaustic) {
    auto scene = load_scene_string(lamp_scene(true, true));
    Parameters params(*scene);
    params.enable({parse_param_selection("fog.albedo")});
    const DerivativeImage bi =
        render_derivative(*scene, params, options_for(*scene, 8, InteriorEstimator::Bidirectional));
    const DerivativeImage uni =
        render_derivative(*scene, params, options_for(*scene, 8, InteriorEstimator::Unidirectional));
    const double ratio = mean_variance(uni.stderr_img) / mean_variance(bi.stderr_img);
    std::printf("variance ratio unidirectional / bidirectional %.2f; seconds %.2f vs %.2f\n", ratio,
                uni.seconds, bi.seconds);
    EXPECT_GT(ratio, 1.0);
}

// ⟨a, J v⟩ = ⟨Jᵀ a, v⟩ with medium, surface and light parameters together.
TEST(BdptInterior, ForwardAndReverseModeAreAdjoint) {
    auto scene = load_scene_string(lamp_scene(true));
    Parameters params(*scene);
    params.enable({parse_param_selection("fog.sigma_t=0.7,0.7,0.7"),
                   parse_param_selection("fog.albedo=0.2,0.3,0.1"),
                   parse_param_selection("fog.phase_function.g=0.5"),
                   parse_param_selection("floor_bsdf.reflectance=0.3,0.2,0.1"),
                   parse_param_selection("lamp.translate=1,0.5,0")});
    DiffOptions o = options_for(*scene, 4, InteriorEstimator::Bidirectional);
    o.batches = 1;
    const DerivativeImage forward = render_derivative(*scene, params, o);
    Image adjoint(16, 16);
    PCG32 rng(5);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    const Gradient reverse = render_gradient(*scene, params, adjoint, o);
    const AdjointPair p = adjoint_pair(adjoint, forward.derivative, reverse.values, params.direction());
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale)
        << "⟨a, Jv⟩ = " << p.forward << ", ⟨Jᵀa, v⟩ = " << p.reverse;
    EXPECT_GT(p.scale, 1e-3);
}

namespace penumbra::test {

// The derivative estimators take max_depth, rr_depth and hide_emitters from a bdpt integrator as from path
// (they ignored it: psdr's boundary terms then sampled depths the image does not have).
TEST(BdptInterior, PathSettingsComeFromTheBdptIntegrator) {
    const auto scene = load_scene_string(R"(<scene version="3.0.0"><integrator type="bdpt">
      <integer name="max_depth" value="3"/><integer name="rr_depth" value="7"/>
      <boolean name="hide_emitters" value="true"/></integrator></scene>)");
    const PathSettings s = path_settings(*scene);
    EXPECT_EQ(s.max_depth, 3);
    EXPECT_EQ(s.rr_depth, 7);
    EXPECT_TRUE(s.hide_emitters);
}

} // namespace penumbra::test
