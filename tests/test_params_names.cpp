// Differentiable parameters under Mitsuba 3's traverse() keys (the table below is the spec, read from the
// plugins' traverse() in mitsuba3/src/{bsdfs,emitters,shapes,textures}), the newly differentiable ones
// against finite differences, and motions about a given center.
#include "core/image.h"
#include "diff_check.h"
#include "scene/scene.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A camera looking down at a large diffuse floor at y = -1 that fills the view, lit by `light`.
std::string floor_scene(const std::string& light) {
    return scene(R"(<integrator type="path"><integer name="max_depth" value="2"/></integrator>
<sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 2, 0.5" target="0, -1, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
</sensor>
<shape type="rectangle" id="floor">
    <transform name="to_world"><scale value="20"/><rotate x="1" angle="-90"/><translate value="0.3, -1, 0.2"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf>
</shape>
)" + light);
}

DiffCheck fd_check(Scene& s, const std::string& selection, int spp = 4) {
    Parameters params(s);
    params.enable({parse_param_selection(selection)});
    const DerivativePair r = derivative_and_fd(s, params, spp, spp, 1e-2);
    const DiffCheck c = check_against(r.derivative, r.fd);
    std::printf("  %s: %s\n", selection.c_str(), describe(c).c_str());
    return c;
}

} // namespace

// One of each plugin penumbra differentiates; every name is Mitsuba's `<id>.<key>[.<nested key>]`.
TEST(ParamsNames, MatchMitsubaTraverseKeys) {
    TempDir dir;
    Image env;
    env.width = 4;
    env.height = 3;
    env.pixels.assign(12, Color3f(0.5f));
    const std::string env_file = dir.str() + "/env.exr";
    write_image(env_file, env);
    auto s = load_scene_string(scene(R"(
<bsdf type="diffuse" id="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
<bsdf type="conductor" id="conductor"/>
<bsdf type="roughconductor" id="roughconductor"/>
<bsdf type="dielectric" id="dielectric"/>
<bsdf type="roughdielectric" id="roughdielectric"/>
<bsdf type="thindielectric" id="thindielectric"/>
<bsdf type="plastic" id="plastic"/>
<bsdf type="twosided" id="twosided"><bsdf type="diffuse"/></bsdf>
<bsdf type="blendbsdf" id="blend"><float name="weight" value="0.3"/><bsdf type="diffuse"/><bsdf type="conductor"/></bsdf>
<bsdf type="mask" id="mask"><float name="opacity" value="0.5"/><bsdf type="diffuse"/></bsdf>
<shape type="rectangle" id="lamp"><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
<shape type="sphere" id="ball"><ref id="diffuse"/></shape>
<emitter type="point" id="point"/>
<emitter type="spot" id="spot"/>
<emitter type="directional" id="sun"/>
<emitter type="projector" id="projector"><rgb name="irradiance" value="1"/></emitter>
<emitter type="constant" id="sky"/>
<emitter type="envmap" id="envmap"><string name="filename" value=")" +
                                     env_file + R"("/></emitter>)"));
    Parameters params(*s);
    std::vector<std::string> names;
    for (const Parameter& p : params.all())
        names.push_back(p.name);
    const std::vector<std::string> expected = {
        "diffuse.reflectance.value",
        "conductor.eta.value",
        "conductor.k.value",
        "conductor.specular_reflectance.value",
        "roughconductor.alpha.value",
        "roughconductor.eta.value",
        "roughconductor.k.value",
        "roughconductor.specular_reflectance.value",
        "dielectric.specular_reflectance.value",
        "dielectric.specular_transmittance.value",
        "roughdielectric.eta",
        "roughdielectric.alpha.value",
        "roughdielectric.specular_reflectance.value",
        "roughdielectric.specular_transmittance.value",
        "thindielectric.specular_reflectance.value",
        "thindielectric.specular_transmittance.value",
        "plastic.diffuse_reflectance.value",
        "plastic.specular_reflectance.value",
        "twosided.brdf_0.reflectance.value",
        "blend.weight.value",
        "blend.bsdf_0.reflectance.value",
        "blend.bsdf_1.eta.value",
        "mask.opacity.value",
        "mask.nested_bsdf.reflectance.value",
        "lamp.vertex_positions",
        "lamp.emitter.radiance.value",
        "ball.vertex_positions",
        "point.intensity.value",
        "spot.intensity.value",
        "sun.irradiance.value",
        "projector.irradiance.value",
        "projector.scale",
        "sky.radiance.value",
        "envmap.scale",
        "envmap.data",
        "lamp.translate",
        "lamp.rotate",
        "lamp.scale",
        "sensor.translate",
        "sensor.rotate",
    };
    for (const std::string& name : expected)
        EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << "missing " << name;
    std::string listed;
    for (const std::string& name : names)
        listed += name + " ";
    SCOPED_TRACE(listed);
    // The shorter names without `.value` stay accepted (scripts, configs and docs use them).
    EXPECT_EQ(params.find("diffuse.reflectance").name, "diffuse.reflectance.value");
    EXPECT_EQ(params.find("point.intensity").name, "point.intensity.value");
    EXPECT_EQ(params.find("envmap.data").size, 3 * 12);
    EXPECT_THROW(params.enable({{"point.intensity", {}}, {"point.intensity.value", {}}}), Error);
}

// Newly differentiable emitter keys against central differences (interior term: nothing moves).
TEST(ParamsNames, ConstantRadianceIsDifferentiable) {
    auto s = load_scene_string(floor_scene(
        R"(<emitter type="constant" id="sky"><rgb name="radiance" value="0.5, 1, 2"/></emitter>)"));
    const DiffCheck c = fd_check(*s, "sky.radiance.value", 16);
    EXPECT_TRUE(c.passes()) << describe(c);
    EXPECT_GT(c.comparison.mean_ref, 0.1);
}

TEST(ParamsNames, EnvmapScaleAndDataAreDifferentiable) {
    TempDir dir;
    Image env;
    env.width = 8;
    env.height = 5;
    for (int i = 0; i < 40; ++i)
        env.pixels.push_back(Color3f(0.2f + 0.05f * (i % 8), 0.5f, 1.5f - 0.03f * i));
    const std::string env_file = dir.str() + "/env.exr";
    write_image(env_file, env);
    auto s =
        load_scene_string(floor_scene(R"(<emitter type="envmap" id="env"><string name="filename" value=")" +
                                      env_file + R"("/><float name="scale" value="1.5"/></emitter>)"));
    for (const std::string selection : {"env.scale", "env.data=1,0.5,0.25"}) {
        const DiffCheck c = fd_check(*s, selection, 16);
        EXPECT_TRUE(c.passes()) << selection << ": " << describe(c);
        EXPECT_GT(c.comparison.mean_ref, 0.01) << selection;
    }
}

// Scaling the floor about its own center only slides it within its plane (a uniform diffuse floor looks the
// same: derivative 0); about the origin it also lowers it away from the light: a different derivative, and
// both match finite differences.
TEST(ParamsNames, ScaleAboutAGivenCenter) {
    auto s =
        load_scene_string(floor_scene(R"(<emitter type="point"><point name="position" value="0.5, 1.5, 0"/>
    <rgb name="intensity" value="5"/></emitter>)"));
    const DiffCheck about_origin = fd_check(*s, "floor.scale@0,0,0");
    EXPECT_TRUE(about_origin.passes()) << describe(about_origin);
    EXPECT_LT(about_origin.comparison.mean_ref, -0.01); // lower, farther from the light: darker
    // About its center both the estimate and the finite difference vanish (the relative checks are 0 / 0).
    Parameters center(*s);
    center.enable({parse_param_selection("floor.scale")});
    const DerivativePair r = derivative_and_fd(*s, center, 4, 4, 1e-2);
    float largest = 0.f;
    for (const Image* img : {&r.derivative.derivative, &r.fd.derivative})
        for (const Color3f& c : img->pixels)
            largest = std::max(largest, max_component(abs(c)));
    std::printf("  floor.scale (about its center): largest |derivative| %g\n", largest);
    EXPECT_LT(largest, 1e-3 * std::abs(about_origin.comparison.mean_ref));

    Parameters params(*s);
    EXPECT_THROW(params.enable({parse_param_selection("floor.translate@0,0,0")}), Error);
    EXPECT_THROW(params.enable({parse_param_selection("floor.scale@0,0")}), Error);
    EXPECT_THROW(params.enable({parse_param_selection("sensor.rotate@0,0,0")}), Error);
    params.enable({parse_param_selection("floor.rotate@1,2,3=0,0,1")});
    ASSERT_EQ(params.motions(s->shapes[0].get()).size(), 1u);
    EXPECT_EQ(params.motions(s->shapes[0].get())[0].center.y, 2.f);
}
