// The radiancemeter sensor (Mitsuba: one ray from `origin` along `direction`, or from to_world's origin along
// its +z): analytic readings, its parameters and errors, and its interior derivative.
#include "diff/psdr/interior.h"
#include "diff/psdr/psdr.h"
#include "render/render.h"
#include "render_stats.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string meter_scene(const std::string& meter_params,
                        const std::string& film = "1\"/><integer name=\"height\" value=\"1") {
    return R"(<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type="radiancemeter" id="meter">)" +
           meter_params + R"(
        <film type="hdrfilm"><integer name="width" value=")" +
           film + R"("/><rfilter type="box"/></film></sensor>
      <shape type="rectangle" id="floor"><bsdf type="diffuse" id="mat"><rgb name="reflectance" value="0.5,0.25,0.75"/></bsdf></shape>
      <emitter type="constant" id="sky"><rgb name="radiance" value="0.3,0.5,0.7"/></emitter></scene>)";
}

Color3f measure(const Scene& scene) {
    RenderOptions o;
    o.spp = 4;
    return render(scene, o).at(0, 0);
}

} // namespace

// Looking away from everything, the meter reads the constant environment's radiance exactly (one ray, weight
// 1).
TEST(CamMeters, RadianceMeterReadsTheEnvironment) {
    auto scene = load_scene_string(
        meter_scene(R"(<point name="origin" value="0,0,1"/><vector name="direction" value="0.3,0.2,1"/>)"));
    const Color3f L = measure(*scene);
    EXPECT_FLOAT_EQ(L.x, 0.3f);
    EXPECT_FLOAT_EQ(L.y, 0.5f);
    EXPECT_FLOAT_EQ(L.z, 0.7f);
}

// Looking down at the diffuse floor under the constant environment (the upper hemisphere sees only the sky):
// L = ρ L_sky. origin/direction and the equivalent to_world give the same ray.
TEST(CamMeters, RadianceMeterReadsADiffuseFloor) {
    for (
        const std::string& params :
        {std::string(
             R"(<point name="origin" value="0.1,0.2,1"/><vector name="direction" value="0.1,-0.2,-1"/>)"),
         std::string(
             R"(<transform name="to_world"><lookat origin="0.1,0.2,1" target="0.2,0,0" up="0,1,0"/></transform>)")}) {
        auto scene = load_scene_string(meter_scene(params));
        const BatchStats s = render_batches(*scene, 16, 256);
        const Color3f expected(0.5f * 0.3f, 0.25f * 0.5f, 0.75f * 0.7f);
        for (int k = 0; k < 3; ++k) {
            // 4 standard errors of 16 batches; the estimate is MIS of sky and BSDF sampling (not noise-free).
            EXPECT_NEAR(s.mean.at(0, 0)[k], expected[k], 4 * s.stderr_img.at(0, 0)[k]) << params;
            EXPECT_LT(s.stderr_img.at(0, 0)[k], 0.01f * expected[k]) << "the test has power";
        }
        std::printf(
            "  floor: %s reads (%.5f, %.5f, %.5f) +- (%.5f, %.5f, %.5f), expected (%.5f, %.5f, %.5f)\n",
            params.substr(1, 5).c_str(), s.mean.at(0, 0).x, s.mean.at(0, 0).y, s.mean.at(0, 0).z,
            s.stderr_img.at(0, 0).x, s.stderr_img.at(0, 0).y, s.stderr_img.at(0, 0).z, expected.x, expected.y,
            expected.z);
    }
}

TEST(CamMeters, RadianceMeterRejectsBadParameters) {
    const std::string only_origin = meter_scene(R"(<point name="origin" value="0,0,1"/>)");
    EXPECT_THROW(load_scene_string(only_origin), LoadError);
    try {
        load_scene_string(meter_scene("", "4\"/><integer name=\"height\" value=\"3"));
        FAIL() << "a 4x3 film was accepted";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("radiancemeter"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(":3:"), std::string::npos) << e.what(); // the film's line
    }
    // A 1-pixel-high strip is accepted, as in Mitsuba: every pixel measures the same ray.
    auto strip = load_scene_string(
        meter_scene(R"(<point name="origin" value="0,0,1"/><vector name="direction" value="0,0,1"/>)",
                    "3\"/><integer name=\"height\" value=\"1"));
    RenderOptions o;
    o.spp = 1;
    const Image image = render(*strip, o);
    EXPECT_EQ(image.at(2, 0).y, 0.5f);
}

// dL/dρ = L_sky exactly for the meter on the floor (image-space first vertex: the ray is fixed); moving
// geometry needs boundary terms the single ray cannot connect to, and is refused.
TEST(CamMeters, RadianceMeterDerivativeOfReflectance) {
    auto scene = load_scene_string(meter_scene(
        R"(<point name="origin" value="0.1,0.2,1"/><vector name="direction" value="0.1,-0.2,-1"/>)"));
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.reflectance=1,1,1")});
    DiffOptions o;
    o.spp = 256;
    o.batches = 16;
    o.path = path_settings(*scene);
    const DerivativeImage d = render_derivative(*scene, params, o);
    for (int k = 0; k < 3; ++k) {
        // L = ρ L_sky: dL/dρ = L_sky, within 4 standard errors of 16 batches.
        const float sky = k == 0 ? 0.3f : k == 1 ? 0.5f : 0.7f;
        EXPECT_NEAR(d.derivative.at(0, 0)[k], sky, 4 * d.stderr_img.at(0, 0)[k]);
        EXPECT_LT(d.stderr_img.at(0, 0)[k], 0.01f * sky) << "the test has power";
    }
    std::printf("  dL/drho = (%.5f, %.5f, %.5f) +- (%.5f, %.5f, %.5f), expected (0.3, 0.5, 0.7)\n",
                d.derivative.at(0, 0).x, d.derivative.at(0, 0).y, d.derivative.at(0, 0).z,
                d.stderr_img.at(0, 0).x, d.stderr_img.at(0, 0).y, d.stderr_img.at(0, 0).z);
    params.enable({parse_param_selection("floor.translate=0,0,1")});
    PsdrOptions p;
    p.interior = o;
    EXPECT_THROW(psdr_derivative(*scene, params, p), Error);
}

namespace {

std::string irradiance_scene(const std::string& extra, const std::string& meter_film = "") {
    return R"(<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <shape type="disk" id="probe"><transform name="to_world"><scale value="0.01"/><translate value="0,0,1"/></transform>
        <sensor type="irradiancemeter">)" +
           meter_film + R"(</sensor></shape>)" + extra + "</scene>";
}

const char* OnePixel =
    R"(<film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film>)";

} // namespace

// Mitsuba's normalization: E = (1/A) ∫ ∫ L cos θ dω dA. Under a constant environment L: E = π L; a
// cosine-weighted direction and weight π make every sample read exactly π L (the default gaussian rfilter is
// replaced by the box that makes the film sample a uniform direction sample).
TEST(CamMeters, IrradianceMeterUnderAConstantEnvironmentReadsPiL) {
    auto scene = load_scene_string(irradiance_scene(
        R"(<emitter type="constant"><rgb name="radiance" value="0.3,0.5,0.7"/></emitter>)", OnePixel));
    EXPECT_EQ(scene->sensor->plugin, "irradiancemeter");
    EXPECT_EQ(scene->sensor->film->rfilter->plugin, "box");
    const BatchStats s = render_batches(*scene, 16, 64);
    for (int k = 0; k < 3; ++k) {
        const float L = k == 0 ? 0.3f : k == 1 ? 0.5f : 0.7f;
        // Every ray escapes to the environment and reads π L (standard error 0): float roundoff.
        EXPECT_NEAR(s.mean.at(0, 0)[k], Pi * L, 1e-5f * L);
    }
    std::printf("  irradiance under L = (0.3, 0.5, 0.7): (%.5f, %.5f, %.5f) +- (%.2g, %.2g, %.2g), pi L = "
                "(%.5f, %.5f, %.5f)\n",
                s.mean.at(0, 0).x, s.mean.at(0, 0).y, s.mean.at(0, 0).z, s.stderr_img.at(0, 0).x,
                s.stderr_img.at(0, 0).y, s.stderr_img.at(0, 0).z, Pi * 0.3f, Pi * 0.5f, Pi * 0.7f);
}

// A disk light of radius R and radiance L facing the probe from height h: E = π L R² / (R² + h²) (its
// projected solid angle). (A point light reads 0, as in Mitsuba: the meter's rays start at the probe and only
// surfaces they hit sample lights.)
TEST(CamMeters, IrradianceMeterUnderADiskLight) {
    auto scene = load_scene_string(
        irradiance_scene(R"(<shape type="disk"><transform name="to_world"><rotate x="1" angle="180"/>
        <translate value="0,0,2"/></transform><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>)",
                         OnePixel));
    const BatchStats s = render_batches(*scene, 16, 4096);
    const double expected = Pi * 2.0 * 1.0 / (1.0 + 1.0); // R = 1, h = 1
    // 4 standard errors of 16 batches; the disk light is a 256-triangle fan (its area is 0.01% below π R²).
    EXPECT_NEAR(s.mean.at(0, 0).x, expected, 4 * s.stderr_img.at(0, 0).x + 1e-3 * expected);
    EXPECT_LT(s.stderr_img.at(0, 0).x, 0.01 * expected) << "the test has power";
    std::printf("  irradiance under a disk light: %.5f +- %.5f, expected %.5f\n", s.mean.at(0, 0).x,
                s.stderr_img.at(0, 0).x, expected);
}

TEST(CamMeters, IrradianceMeterErrors) {
    // Its film must have one pixel; other sensors cannot be nested in a shape; another sensor may sit beside
    // it (several sensors per scene, as in Mitsuba).
    EXPECT_THROW(load_scene_string(irradiance_scene("")), LoadError); // the default 768x576 film
    const std::string nested_camera =
        R"(<scene version="3.0.0"><shape type="disk"><sensor type="perspective"/></shape></scene>)";
    try {
        load_scene_string(nested_camera);
        FAIL();
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("irradiancemeter"), std::string::npos) << e.what();
    }
    EXPECT_EQ(
        load_scene_string(irradiance_scene(R"(<sensor type="perspective"/>)", OnePixel))->sensors.size(), 2u);
}
