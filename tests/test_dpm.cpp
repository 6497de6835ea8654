// Differentiable photon mapping (paper 003, diff/dpm/dpm.h): DPM-C's derivative images against central finite
// differences of SPPM renders at a fixed radius (alpha 1, the smooth kernel) with common random numbers, on
// caustics only photon mapping renders: a spot light refracted twice by a rotating glass block, and paper 003's
// Fig. 6 (a curved mirror) and a bumpy glass slab against stored references, each onto a diffuse floor the
// camera sees alone (no moving visibility edge, which DPM does not differentiate). DPM-G's screen-space motion
// against the finite-difference motion of a caustic's centroid. Reverse mode against forward mode,
// determinism across thread counts, errors.
#include "core/error.h"
#include "core/image.h"
#include "diff/dpm/dpm.h"
#include "diff/method.h"
#include "diff_cases.h"
#include "diff_check.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A spot light (8° cone, linear falloff to zero: no beam edge) reflected down by a mirror tilted 30°, or
// refracted by a glass block below it; the camera looks at the caustic on the floor from where it sees neither
// the mirror nor the block (`camera`: its lookat and fov).
std::string scene_xml(const std::string& optics, const std::string& camera) {
    return R"(<scene version="3.0.0">
    <integrator type="sppm">
        <integer name="photon_count" value="4000"/>
        <float name="initial_radius" value="0.15"/>
        <float name="alpha" value="1"/>
        <string name="kernel" value="smooth"/>
    </integrator>
    <sensor type="perspective">)" + camera + R"(
        <sampler type="independent"/>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle" id="floor">
        <transform name="to_world"><scale value="5"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"/>
    </shape>)" + optics + "</scene>";
}

const std::string above = R"(<float name="fov" value="25"/>
        <transform name="to_world"><lookat origin="-2.5, 3, 0" target="-0.4, 0, 0" up="0, 1, 0"/></transform>)";
const std::string low = R"(<float name="fov" value="20"/>
        <transform name="to_world"><lookat origin="-3.2, 0.6, 0" target="-0.45, 0, 0" up="0, 1, 0"/></transform>)";

const std::string mirror = R"(
    <emitter type="spot" id="light">
        <rgb name="intensity" value="40"/>
        <float name="cutoff_angle" value="8"/>
        <float name="beam_width" value="1"/>
        <transform name="to_world"><lookat origin="-1.5, 1.2, 0" target="0, 1.2, 0" up="0, 1, 0"/></transform>
    </emitter>
    <shape type="rectangle" id="mirror">
        <transform name="to_world">
            <scale value="0.6"/><rotate y="1" angle="-90"/><rotate z="1" angle="30"/><translate value="0.3, 1.2, 0"/>
        </transform>
        <bsdf type="conductor"/>
    </shape>)";

// The spot shines down through the block's top and bottom faces only (its cone's footprint is inside them).
const std::string glass = R"(
    <emitter type="spot" id="light">
        <rgb name="intensity" value="20"/>
        <float name="cutoff_angle" value="10"/>
        <float name="beam_width" value="1"/>
        <transform name="to_world"><lookat origin="-0.2, 2.2, 0" target="-0.5, 0, 0" up="1, 0, 0"/></transform>
    </emitter>
    <shape type="cube" id="block">
        <transform name="to_world"><scale x="0.7" y="0.15" z="0.7"/><rotate z="1" angle="15"/>
            <translate value="-0.3, 1.0, 0"/></transform>
        <bsdf type="dielectric"/>
    </shape>)";

struct Case {
    std::string optics, camera, param;
    double h;
};

DiffCheck run_case(const Case& c, DerivativeImage* out = nullptr) {
    auto scene = load_scene_string(scene_xml(c.optics, c.camera));
    Parameters params(*scene);
    params.enable({parse_param_selection(c.param)});
    DpmOptions o;
    o.spp = 4; // passes per batch
    o.batches = 16;
    o.pixel_fraction = 1.0;
    o.paths = 8;
    o.seed = 11 + 1000 * test_seed();
    const DerivativeImage d = dpm_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 4;
    ro.seed = 5 + 1000 * test_seed();
    const FiniteDifference fd = finite_difference(*scene, params, c.h, ro, 16);
    if (out) *out = d;
    return check_against(d, fd);
}

} // namespace

// (The mirror's rotation and the light's translation are checked on paper 003's Fig. 6 below.) A spot's rotation
// turns its beam across the mirror: the photons keep their world directions, the intensity profile moves.
TEST(DpmC, SpotRotationMatchesFiniteDifferences) {
    const DiffCheck c = run_case({mirror, above, "light.rotate=0,0,1", 0.005});
    EXPECT_TRUE(c.passes()) << describe(c);
}

TEST(DpmC, GlassRotationMatchesFiniteDifferences) {
    const DiffCheck c = run_case({glass, low, "block.rotate=0,0,1", 0.01});
    EXPECT_TRUE(c.passes()) << describe(c);
}

// d/dθ of the caustic's centroid (channel 0, pixel centres) from DPM-G's screen-space motion and contribution
// derivatives, dc/dθ = [Σ I dp/dθ + Σ dI/dθ (p − c)] / Σ I, against the centroid's central difference; with the
// standard error of each (pixels independent).
struct Centroid {
    double dx, dy, se_x, se_y;
};

Centroid centroid_motion(const Image& primal, const Image& d, const Image& d_se, const Image* sx, const Image* sy,
                         const Image* sx_se, const Image* sy_se) {
    double total = 0, cx = 0, cy = 0;
    for (int y = 0; y < primal.height; ++y)
        for (int x = 0; x < primal.width; ++x) {
            const double i = primal.at(x, y).x;
            total += i;
            cx += i * (x + 0.5);
            cy += i * (y + 0.5);
        }
    cx /= total;
    cy /= total;
    Centroid c{0, 0, 0, 0};
    for (int y = 0; y < primal.height; ++y)
        for (int x = 0; x < primal.width; ++x) {
            const double di = d.at(x, y).x, s = d_se.at(x, y).x, ux = x + 0.5 - cx, uy = y + 0.5 - cy;
            c.dx += di * ux;
            c.dy += di * uy;
            double vx = s * ux, vy = s * uy;
            if (sx) {
                c.dx += sx->at(x, y).x;
                c.dy += sy->at(x, y).x;
                vx = std::hypot(vx, double(sx_se->at(x, y).x));
                vy = std::hypot(vy, double(sy_se->at(x, y).x));
            }
            c.se_x += vx * vx;
            c.se_y += vy * vy;
        }
    return {c.dx / total, c.dy / total, std::sqrt(c.se_x) / total, std::sqrt(c.se_y) / total};
}

class DpmG : public testing::TestWithParam<std::string> {};

TEST_P(DpmG, ScreenSpaceMotionMatchesTheCentroidsFiniteDifference) {
    auto scene = load_scene_string(scene_xml(mirror, above));
    Parameters params(*scene);
    params.enable({parse_param_selection(GetParam())});
    DpmOptions o;
    o.variant = DpmVariant::G;
    o.spp = 4;
    o.batches = 16;
    o.pixel_fraction = 1.0;
    o.paths = 8;
    o.seed = 11 + 1000 * test_seed();
    const DerivativeImage g = dpm_derivative(*scene, params, o);
    const DerivativeTerm &screen_x = g.term("screen_x"), &screen_y = g.term("screen_y");
    RenderOptions ro;
    ro.spp = 4;
    ro.seed = 5 + 1000 * test_seed();
    const FiniteDifference fd = finite_difference(*scene, params, 0.01, ro, 16);
    const Centroid test = centroid_motion(g.primal, g.derivative, g.stderr_img, &screen_x.derivative,
                                          &screen_y.derivative, &screen_x.stderr_img, &screen_y.stderr_img);
    const Centroid ref =
        centroid_motion(g.primal, fd.derivative, fd.stderr_img, nullptr, nullptr, nullptr, nullptr);
    const std::string what = "DPM-G (" + std::to_string(test.dx) + ", " + std::to_string(test.dy) + ") ± (" +
                             std::to_string(test.se_x) + ", " + std::to_string(test.se_y) + "), FD (" +
                             std::to_string(ref.dx) + ", " + std::to_string(ref.dy) + ") ± (" +
                             std::to_string(ref.se_x) + ", " + std::to_string(ref.se_y) + ") pixels per unit";
    EXPECT_LT(std::abs(test.dx - ref.dx), 4 * std::hypot(test.se_x, ref.se_x) + 0.02 * std::abs(ref.dx)) << what;
    EXPECT_LT(std::abs(test.dy - ref.dy), 4 * std::hypot(test.se_y, ref.se_y) + 0.02 * std::abs(ref.dy)) << what;
    // The caustic moves by pixels per unit (the test sees a motion), and both EPSMs carry part of it.
    EXPECT_GT(std::hypot(ref.dx, ref.dy), 20 * std::hypot(ref.se_x, ref.se_y)) << what;
    const Centroid contribution_only =
        centroid_motion(g.primal, g.derivative, g.stderr_img, nullptr, nullptr, nullptr, nullptr);
    EXPECT_GT(std::abs(contribution_only.dx - test.dx) + std::abs(contribution_only.dy - test.dy),
              0.2 * std::hypot(ref.dx, ref.dy))
        << what;
    std::printf("%s\n", what.c_str());
}

INSTANTIATE_TEST_SUITE_P(Motions, DpmG, testing::Values("light.translate=0,0,1", "mirror.rotate=0,0,1"));

// Paper 003's Fig. 6 and a glass slab (scenes/dpm/, docs/dpm-validation.md) against stored central differences
// of SPPM at 256 passes (tests/data/dpm/, scripts/make_dpm_references.sh): the expectation at a fixed radius
// does not depend on the photon count or the passes, so DPM-C runs with fewer of both.
struct StoredCase {
    std::string scene, param, reference;
    int passes, paths;
};

class DpmCStored : public testing::TestWithParam<StoredCase> {};

TEST_P(DpmCStored, MatchesStoredFiniteDifferences) {
    const StoredCase& c = GetParam();
    const std::string root = std::string(PENUMBRA_SOURCE_DIR) + "/";
    // Photons shared by many paths' gathers are cheap next to the paths' solves: few photons, more paths.
    auto scene = load_scene(root + "scenes/dpm/" + c.scene + ".xml", {{"photons", "5000"}});
    Parameters params(*scene);
    params.enable({parse_param_selection(c.param)});
    DpmOptions o;
    o.spp = c.passes / 16;
    o.batches = 16;
    o.pixel_fraction = 1.0;
    o.paths = c.paths;
    o.seed = 21 + 1000 * test_seed();
    const DerivativeImage d = dpm_derivative(*scene, params, o);
    const std::string ref = root + "tests/data/dpm/" + c.reference;
    const DiffCheck check = check_against(d.derivative, d.stderr_img, read_image(ref + ".exr", false),
                                          read_image(ref + "_stderr.exr", false));
    // The image mean's z from the spread of the batch means (pixels share photons: their errors correlate);
    // the reference's share, from its pixels, is the smaller by an order of magnitude.
    const double ref_se = std::abs(check.comparison.mean_ref - check.comparison.mean_test) /
                          std::max(1e-30, std::abs(check.comparison.mean_z));
    const double z = (check.comparison.mean_test - check.comparison.mean_ref) / std::hypot(d.mean_stderr, ref_se);
    const bool passes = std::abs(z) < 4.0 && check.outliers_4sigma < 0.02 &&
                        check.comparison.relerr < 1.5 * check.noise_relerr + 0.02 &&
                        check.comparison4.relerr < 1.5 * check.comparison4.noise_relerr + 0.02;
    EXPECT_TRUE(passes) << describe(check) << ", z of the batch means " << z;
    std::printf("%s: %s, z of the batch means %.2f\n", c.reference.c_str(), describe(check).c_str(), z);
}

INSTANTIATE_TEST_SUITE_P(
    Fig6, DpmCStored,
    testing::Values(StoredCase{"reflector", "reflector.rotate@2,1.5,0=0,1,0", "reflector_rotate_y", 64, 16},
                    StoredCase{"reflector", "light.translate=1,0,0", "reflector_light_x", 64, 16},
                    StoredCase{"slab", "slab_top.translate=0,1,0", "slab_thickness", 32, 8},
                    StoredCase{"slab", "slab_top.deform@0.15,2.2,-0.1=0,1,0", "slab_bulge", 32, 8}),
    [](const testing::TestParamInfo<StoredCase>& info) { return info.param.reference; });

namespace {

// DPM-C at a few samples in forward mode and in reverse mode (against a fixed adjoint image a): checks
// <a, J d> = <J^T a, d> and returns both passes.
struct ForwardAndReverse {
    DerivativeImage forward;
    Gradient reverse;
};

ForwardAndReverse expect_reverse_equals_forward(const Scene& scene, const Parameters& params) {
    DpmOptions o;
    o.spp = 4;
    o.pixel_fraction = 0.5;
    o.paths = 2;
    ForwardAndReverse r{dpm_derivative(scene, params, o), {}};
    Image adjoint(16, 16);
    for (size_t i = 0; i < adjoint.pixels.size(); ++i)
        adjoint.pixels[i] = Color3f(float(i % 7) - 3.f, 1.f, float(i % 3));
    r.reverse = dpm_gradient(scene, params, adjoint, o);
    if (r.reverse.values.size() != size_t(params.dimension())) {
        ADD_FAILURE() << "the gradient has " << r.reverse.values.size() << " values for " << params.dimension()
                      << " parameters";
        return r;
    }
    const AdjointPair p = adjoint_pair(adjoint, r.forward.derivative, r.reverse.values, params.direction());
    EXPECT_GT(p.scale, 0.0);
    EXPECT_NEAR(p.forward, p.reverse, 1e-4 * p.scale);
    return r;
}

} // namespace

TEST(DpmC, ReverseModeEqualsForwardMode) {
    auto scene = load_scene_string(scene_xml(mirror, above));
    Parameters params(*scene);
    params.enable({parse_param_selection("mirror.rotate=0,0,1")});
    const ForwardAndReverse r = expect_reverse_equals_forward(*scene, params);
    // Both passes render the same SPPM image.
    for (size_t i = 0; i < r.forward.primal.pixels.size(); ++i)
        EXPECT_EQ(r.forward.primal.pixels[i], r.reverse.primal.pixels[i]);
}

// Under vertex_positions a mesh's smooth normals are tape leaves chained to the positions once per pass
// (diff/vertex_normals.h): DPM's reverse mode chains their adjoints as its forward mode does their tangents.
TEST(DpmC, ReverseModeEqualsForwardModeUnderVertexPositions) {
    const TempDir dir;
    // The mirror as a shallow bowl over the rectangle's [-1, 1]^2 (4x4 vertices, no stored normals: smooth
    // normals computed from the positions), facing +z like the rectangle.
    std::string obj;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            const float x = -1.f + 2.f * float(i) / 3.f, y = -1.f + 2.f * float(j) / 3.f;
            obj += "v " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(0.1f * (x * x + y * y)) + "\n";
        }
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            const int a = 4 * j + i + 1;
            obj += "f " + std::to_string(a) + " " + std::to_string(a + 1) + " " + std::to_string(a + 5) + "\n";
            obj += "f " + std::to_string(a) + " " + std::to_string(a + 5) + " " + std::to_string(a + 4) + "\n";
        }
    std::string optics = mirror;
    const std::string rectangle = R"(<shape type="rectangle" id="mirror">)";
    optics.replace(optics.find(rectangle), rectangle.size(),
                   R"(<shape type="obj" id="mirror"><string name="filename" value=")" + dir.write("bowl.obj", obj) + R"("/>)");
    auto scene = load_scene_string(scene_xml(optics, above));
    Parameters params(*scene);
    std::vector<float> d(size_t(params.find("mirror.vertex_positions").size));
    PCG32 rng(3);
    for (float& x : d) x = 0.2f * (rng.next_float() - 0.5f);
    params.enable({{"mirror.vertex_positions", d}});
    ASSERT_GT(params.tape_dimension(), params.dimension()) << "the bowl's normals should be tape leaves";
    expect_reverse_equals_forward(*scene, params);
}

TEST(DpmC, SameResultWhateverTheThreadCount) {
    auto scene = load_scene_string(scene_xml(glass, low));
    Parameters params(*scene);
    params.enable({parse_param_selection("block.rotate=0,0,1")});
    DpmOptions o;
    o.spp = 2;
    o.pixel_fraction = 0.25;
    o.threads = 1;
    const DerivativeImage one = dpm_derivative(*scene, params, o);
    o.threads = 2;
    const DerivativeImage two = dpm_derivative(*scene, params, o);
    double sum = 0;
    for (size_t i = 0; i < one.derivative.pixels.size(); ++i) {
        EXPECT_EQ(one.derivative.pixels[i], two.derivative.pixels[i]);
        sum += std::abs(one.derivative.pixels[i].x);
    }
    EXPECT_GT(sum, 0.0);
}

TEST(DpmC, RefusesMediaAndBadOptions) {
    auto scene = load_scene_string(scene_xml(mirror, above));
    Parameters params(*scene);
    params.enable({parse_param_selection("mirror.rotate=0,0,1")});
    DpmOptions o;
    o.pixel_fraction = 0.0;
    EXPECT_THROW(dpm_derivative(*scene, params, o), Error);
    MethodOptions m;
    m.set("pixel-fraction", "2");
    EXPECT_THROW(make_method("dpm-c", m), Error);
    auto media = load_scene_string(R"(<scene version="3.0.0">
        <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
        <emitter type="point"><point name="position" value="0, 0, 2"/></emitter>
        <shape type="sphere" id="ball"><bsdf type="null"/><medium type="homogeneous" name="interior"/></shape>
    </scene>)");
    Parameters mp(*media);
    mp.enable({parse_param_selection("ball.translate=1,0,0")});
    EXPECT_THROW(dpm_derivative(*media, mp, DpmOptions{}), Error);
}

// The scene's sppm settings the estimate cannot follow are warnings in its result: the constant kernel (its
// edge is not differentiated) and alpha < 1 (render and fd shrink the radius, dpm keeps it fixed).
TEST(DpmC, WarnsAboutAConstantKernelAndAShrinkingRadius) {
    auto warnings = [](const std::string& from, const std::string& to) {
        std::string xml = scene_xml(mirror, above);
        xml.replace(xml.find(from), from.size(), to);
        auto scene = load_scene_string(xml);
        Parameters params(*scene);
        params.enable({parse_param_selection("mirror.rotate=0,0,1")});
        DpmOptions o;
        o.spp = 1;
        o.paths = 1;
        o.pixel_fraction = 0.1;
        return dpm_derivative(*scene, params, o).warnings;
    };
    EXPECT_TRUE(warnings("", "").empty());
    const auto constant = warnings("value=\"smooth\"", "value=\"constant\"");
    ASSERT_EQ(constant.size(), 1u);
    EXPECT_NE(constant[0].find("constant kernel"), std::string::npos) << constant[0];
    const auto shrinking = warnings("name=\"alpha\" value=\"1\"", "name=\"alpha\" value=\"0.7\"");
    ASSERT_EQ(shrinking.size(), 1u);
    EXPECT_NE(shrinking[0].find("alpha"), std::string::npos) << shrinking[0];
}
