// A point light translating inside a homogeneous fog above a diffuse floor, just above the view (paper 001
// §6.1): VolumeMotion carries the medium near the light with it (its shell reaches into the view), so that
// the connections from medium vertices near the light keep their length and the derivative of I/ℓ² has
// finite variance. psdr's derivative (interior + direct and pixel boundary terms; material-form first vertex,
// so that the medium vertices the camera sees follow X too) matches central finite differences.
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "render/render.h"

#include <gtest/gtest.h>

#include <string>

using namespace penumbra;
using namespace penumbra::test;

TEST(LightInMedium, TranslatingPointLightMatchesFiniteDifferences) {
    const std::string xml = R"(<scene version="3.0.0">
      <integrator type="volpath"><integer name="max_depth" value="2"/></integrator>
      <medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/><rgb name="albedo" value="0.9"/>
        </medium>
      <sensor type="perspective" id="cam"><float name="fov" value="45"/><transform name="to_world">
        <lookat origin="0, 2.6, 3.4" target="0, 0.6, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
      </sensor>
      <shape type="cube" id="box"><transform name="to_world"><scale value="2.5"/><translate value="0, 1, 0"/>
        </transform><bsdf type="null"/><ref name="interior" id="fog"/></shape>
      <shape type="rectangle" id="floor"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/>
        </transform><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.7, 0.6"/></bsdf></shape>
      <emitter type="point" id="bulb"><point name="position" value="0.2, 2.4, 0"/>
        <rgb name="intensity" value="10"/></emitter></scene>)";
    auto scene = load_scene_string(xml, ".");
    Parameters params(*scene);
    params.enable({parse_param_selection("bulb.translate=0.5,1,0")});
    PsdrOptions o;
    o.interior.spp = 64;
    o.interior.batches = 16;
    o.interior.seed = 5;
    o.interior.first_vertex = FirstVertex::Material;
    o.interior.path.max_depth = 2;
    o.primary_spp = o.indirect_spp = 0;
    o.pixel_spp = 32; // the material-form first vertex moves across pixel edges with X
    o.direct_spp = 16;
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 1024;
    ro.seed = 99;
    const FiniteDifference fd = finite_difference(*scene, params, 0.02, ro, 16);
    const DiffCheck c = check_against(d, fd);
    std::printf("  psdr vs fd: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}
