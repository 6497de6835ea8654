// What the robustness tests share (test_nan_policy.cpp, test_degenerate_input.cpp): a small scene, and a check
// that rendering and differentiating it gives finite outputs.
#pragma once
#include "diff/method.h"
#include "render/render.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace penumbra::test {

// A box on a floor under an area light, 16x16; `box_bsdf` and `floor_bsdf` are BSDF elements, `sensor` the
// sensor's to_world.
inline std::string scene_xml(const std::string& box_bsdf, const std::string& floor_bsdf = R"(<bsdf type="diffuse"/>)",
                      const std::string& box_shape = R"(<shape type="cube" id="box">)",
                      const std::string& sensor = R"(<lookat origin="0,2,4" target="0,0.3,0" up="0,1,0"/>)") {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="4"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world">)" + sensor + R"(</transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
      )" + box_shape + R"(<transform name="to_world"><scale value="0.4"/><translate value="0,0.4,0"/></transform>
        )" + box_bsdf + R"(</shape>
      <shape type="rectangle" id="floor"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        )" + floor_bsdf + R"(</shape>
      <shape type="rectangle" id="light"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/>
        <translate value="0,2.5,0"/></transform><emitter type="area"><rgb name="radiance" value="8"/></emitter></shape>
    </scene>)";
}

inline bool finite(const Image& image) {
    for (const Color3f& c : image.pixels)
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) return false;
    return true;
}

struct Outputs {
    RenderStats render;
    DerivativeImage derivative;
    Gradient gradient;
};

// A render at `render_spp`, and the method's derivative and gradient of `param` at `spp`; every output must be
// finite.
inline Outputs render_and_differentiate(Scene& scene, const std::string& param, const std::string& method = "psdr",
                                        int render_spp = 4, int spp = 8) {
    Outputs out;
    RenderOptions ro;
    ro.spp = render_spp;
    const Image image = render(scene, ro, &out.render);
    EXPECT_TRUE(finite(image)) << "render";
    Parameters params(scene);
    params.enable({parse_param_selection(param)});
    MethodRun run;
    run.spp = spp;
    out.derivative = make_method(method, MethodOptions())->derivative(scene, params, run);
    EXPECT_TRUE(finite(out.derivative.derivative)) << method << " derivative of " << param;
    out.gradient = make_method(method, MethodOptions())
                       ->gradient(scene, params, Image(scene.sensor->film->width, scene.sensor->film->height, Color3f(1.f)), run);
    for (double g : out.gradient.values) EXPECT_TRUE(std::isfinite(g)) << method << " gradient of " << param;
    return out;
}

} // namespace penumbra::test
