// Motions of lights (<emitter>.translate / <emitter>.rotate, diff/parameters.h) against finite differences:
// the interior term's next-event segments see the moving light (its position, direction, cone or
// environment), the direct boundary term the shadows it moves.
#include "core/rng.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "stored_reference.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string validation = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

// A hard shadow moved by the light (shadow.xml): interior + direct boundary must match the finite differences
// (with the reference's truncation error and detection limit, as in test_diff_boundary.cpp), the interior
// term alone must miss the moving shadow. The references at h = 1e-2 and 2e-2 are stored (tests/data/fd,
// scripts/make_test_references.sh; `reference` and `reference`_2h) at twice the samples this test used to
// render.
void expect_moving_light_shadow_matches(const std::string& light, const std::string& param,
                                        const std::string& reference) {
    auto scene = load_scene(validation + "shadow.xml", {{"res", "32"}, {"light", light}});
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    PsdrOptions o;
    o.interior.spp = 16;
    o.interior.batches = 16;
    const char* seed = std::getenv("PENUMBRA_TEST_SEED");
    const uint64_t run = seed ? std::strtoull(seed, nullptr, 10) : 0;
    o.interior.seed = 11 + 1000 * run;
    o.interior.path = path_settings(*scene);
    o.primary_spp = 0;
    o.direct_spp = 512;
    o.indirect_spp = 0;
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    const StoredReference fd = stored_reference({reference, {"light=" + light}}, 1e-2);
    const StoredReference fd2 = stored_reference({reference + "_2h", {"light=" + light}}, 2e-2);
    expect_only_the_total_matches("shadow.xml " + param, *scene, d, fd.fd, fd2.fd, fd.h, fd.samples);
}

// The interior derivative alone against finite differences (no visibility edge moves). The reference's
// truncation error is estimated too (diff_check.h): where the derivative is nearly noiseless (the environment
// seen directly) the O(h²) error of the central difference, and the kinks of bilinear texel interpolation,
// exceed the reference's own noise.
void expect_interior_matches(Scene& scene, const std::string& param, int spp, int fd_spp, double h) {
    Parameters params(scene);
    params.enable({parse_param_selection(param)});
    const DerivativePair r = derivative_and_fd(scene, params, spp, fd_spp, h);
    RenderOptions ro;
    ro.spp = fd_spp;
    const char* seed = std::getenv("PENUMBRA_TEST_SEED"); // the seed derivative_and_fd's reference uses
    ro.seed = 1234 + 1000 * (seed ? std::strtoull(seed, nullptr, 10) : 0);
    const FiniteDifference fd2 = finite_difference(scene, params, 2 * h, ro, 16);
    const Image reference_error = with_truncation_error(r.fd.stderr_img, r.fd, fd2);
    const DiffCheck c =
        check_against(r.derivative.derivative, r.derivative.stderr_img, r.fd.derivative, reference_error);
    double magnitude = 0;
    for (const Color3f& v : r.fd.derivative.pixels)
        magnitude += std::abs(v.x) + std::abs(v.y) + std::abs(v.z);
    std::printf("  %s: %s\n", param.c_str(), describe(c).c_str());
    EXPECT_GT(magnitude, 0.0) << "the motion must change the image";
    EXPECT_TRUE(c.passes()) << describe(c);
}

const std::string camera_and_floor = R"(
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 3, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.7, 0.6"/></bsdf>
    </shape>)";

} // namespace

// (1) A point light translating above an occluder: shading (1/r², cosines) and the shadow edge move.
TEST(EmitterMotion, TranslatingPointLightMovesShadingAndShadow) {
    expect_moving_light_shadow_matches("point", "bulb.translate=1,0,0.5", "bulb_translate");
}

// (3) A directional light turning: its shadow slides across the floor and the cosine changes.
TEST(EmitterMotion, RotatingDirectionalLightMovesItsShadow) {
    expect_moving_light_shadow_matches("directional", "sun.rotate=0,0,1", "sun_rotate");
}

// (2) A spot light turning about its position, and translating: its falloff ring (beam_width < cutoff_angle,
// a continuous profile) sweeps the floor.
TEST(EmitterMotion, MovingSpotLightSweepsItsCone) {
    auto s = load_scene_string(scene(camera_and_floor + R"(
    <emitter type="spot" id="spot">
        <rgb name="intensity" value="20"/>
        <float name="cutoff_angle" value="35"/>
        <float name="beam_width" value="10"/>
        <transform name="to_world"><lookat origin="0.3, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    </emitter>)"));
    expect_interior_matches(*s, "spot.rotate=1,0,0.3", 16, 256, 1e-2);
    expect_interior_matches(*s, "spot.translate=0.5,-1,1", 16, 256, 1e-2);
}

// A spot light whose cone ends in a jump (beam_width = cutoff_angle) cannot move: the jump's motion is a
// boundary penumbra does not sample.
TEST(EmitterMotion, HardConeEdgeIsRefused) {
    auto s = load_scene_string(scene(camera_and_floor + R"(
    <emitter type="spot" id="spot">
        <float name="cutoff_angle" value="20"/>
        <float name="beam_width" value="20"/>
        <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    </emitter>)"));
    Parameters params(*s);
    params.enable({parse_param_selection("spot.rotate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 1;
    o.direct_spp = 1;
    try {
        psdr_derivative(*s, params, o);
        FAIL() << "a moving hard-edged spot must be refused";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("emitter 'spot'"), std::string::npos) << e.what();
    }
}

// (4) An environment map turning about the vertical: the sky seen directly, the light on the floor and the
// occlusion of a box (whose visibility edges do not move: the interior term is the whole derivative).
TEST(EmitterMotion, RotatingEnvmapLightsTheFloorDifferently) {
    TempDir dir;
    Image sky(32, 16);
    for (int y = 0; y < sky.height; ++y)
        for (int x = 0; x < sky.width; ++x) {
            const float u = (x + 0.5f) / sky.width, v = (y + 0.5f) / sky.height;
            sky.at(x, y) =
                Color3f(1.f + std::sin(2.f * Pi * u), 1.f + 0.8f * std::cos(2.f * Pi * u), 0.5f + v);
        }
    write_image(dir.str() + "/sky.exr", sky);
    auto s = load_scene_string(scene(R"(
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="60"/>
        <transform name="to_world"><lookat origin="0, 1.5, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.3"/><translate value="0, 0.3, 0"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    <emitter type="envmap" id="sky"><string name="filename" value="sky.exr"/></emitter>)"),
                               dir.str());
    expect_interior_matches(*s, "sky.rotate=0,1,0", 16, 256, 1e-2);
}

// The motions are listed under the lights' ids: translate and rotate for lights at a point, rotate only for
// directions; none for constant environments and area lights.
TEST(EmitterMotion, ParametersListTheLightsMotions) {
    auto s = load_scene_string(scene(camera_and_floor + R"(
    <emitter type="point" id="bulb"><point name="position" value="0, 2, 0"/></emitter>
    <emitter type="directional" id="sun"><vector name="direction" value="0, -1, 0"/></emitter>
    <emitter type="constant" id="ambient"/>)"));
    Parameters params(*s);
    EXPECT_NO_THROW(params.find("bulb.translate"));
    EXPECT_NO_THROW(params.find("bulb.rotate"));
    EXPECT_NO_THROW(params.find("sun.rotate"));
    EXPECT_THROW(params.find("sun.translate"), Error);
    EXPECT_THROW(params.find("ambient.rotate"), Error);
    EXPECT_THROW(params.enable({parse_param_selection("bulb.rotate@0,0,0")}), Error);
}

// Finite differences move the light itself: a displaced point light lights the floor below it more brightly.
TEST(EmitterMotion, DisplaceMovesTheLightAndRestoresIt) {
    auto s = load_scene_string(scene(camera_and_floor + R"(
    <emitter type="point" id="bulb"><point name="position" value="0, 2, 0"/></emitter>)"));
    Parameters params(*s);
    params.enable({parse_param_selection("bulb.translate=0,-1,0")});
    Interaction3f ref;
    ref.p = Vec3f(0.f);
    const auto before = s->emitters[0]->sample_direction(ref, Vec2f(0.5f));
    params.displace(*s, 0.5);
    const auto moved = s->emitters[0]->sample_direction(ref, Vec2f(0.5f));
    EXPECT_NEAR(moved.first.p.y, 1.5f, 1e-6f);
    EXPECT_NEAR(moved.second.x / before.second.x, (2.f * 2.f) / (1.5f * 1.5f), 1e-4f);
    params.displace(*s, 0.0);
    EXPECT_EQ(s->emitters[0]->sample_direction(ref, Vec2f(0.5f)).first.p.y, 2.f);
}

// A projector translating and turning above the floor, which lies wholly inside its frustum (the frustum's
// border, a jump, falls on nothing): the projected image's uv and the 1/d² fall-off move.
TEST(EmitterMotion, MovingProjectorSlidesItsImage) {
    TempDir dir;
    Image slide(16, 16);
    for (int y = 0; y < slide.height; ++y)
        for (int x = 0; x < slide.width; ++x)
            slide.at(x, y) = Color3f(1.f + float(x) / 4.f, 1.f + float(y) / 8.f, 2.f);
    write_image(dir.str() + "/slide.exr", slide);
    for (const std::string param : {"projector.translate=1,0,0.5", "projector.rotate=0,0.3,1"}) {
        auto s = load_scene_string(scene(camera_and_floor + R"(
    <emitter type="projector" id="projector">
        <float name="fov" value="130"/>
        <texture type="bitmap" name="irradiance"><string name="filename" value="slide.exr"/></texture>
        <transform name="to_world"><lookat origin="0.2, 3, 0" target="0.2, 0, 0" up="0, 0, -1"/></transform>
    </emitter>)"),
                                   dir.str());
        expect_interior_matches(*s, param, 16, 256, 1e-2);
    }
}

// Reverse mode (`penumbra gradient`) takes the light's motion too: ⟨a, (interior + direct) v⟩ = ⟨gradient, v⟩
// on the same samples, the direct term being a sizeable part.
TEST(EmitterMotion, ReverseModeMatchesForwardMode) {
    auto s = load_scene(validation + "shadow.xml", {{"res", "16"}, {"light", "point"}});
    Parameters params(*s);
    params.enable({parse_param_selection("bulb.translate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.seed = 5;
    o.interior.path = path_settings(*s);
    o.primary_spp = 0;
    o.direct_spp = 64;
    o.indirect_spp = 0;
    const DerivativeImage forward = psdr_derivative(*s, params, o);
    Image adjoint(16, 16);
    PCG32 rng(3);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    const Gradient reverse = psdr_gradient(*s, params, adjoint, o);
    double lhs = 0, scale = 0, direct = 0;
    const Image& direct_term = forward.term("direct").derivative;
    for (size_t i = 0; i < adjoint.pixels.size(); ++i) {
        const Vec3d a(adjoint.pixels[i]);
        lhs += dot(a, Vec3d(forward.derivative.pixels[i]));
        scale += std::abs(dot(a, Vec3d(forward.derivative.pixels[i])));
        direct += std::abs(dot(a, Vec3d(direct_term.pixels[i])));
    }
    EXPECT_GT(direct, 0.05 * scale);
    EXPECT_NEAR(lhs, reverse.values[0], 1e-4 * scale + 1e-6)
        << "⟨a, Jv⟩ = " << lhs << ", ⟨Jᵀa, v⟩ = " << reverse.values[0];
}
