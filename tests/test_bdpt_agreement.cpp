// bdpt against the unidirectional path tracer on small scenes covering every emitter type, a specular
// (dielectric) object and a finite-aperture camera. Both estimate the same image: the image mean and the 16
// block means of 4x4 blocks must agree within the standard errors estimated from 12 independent renders of
// each integrator. With ~22 degrees of freedom P(|z| > 4) ~ 6e-4 for the image mean, and P(max of 16 block
// |z| > 4.5) ~ 3e-3: larger values mean bias, not bad luck (the seeds are fixed, so a pass is reproducible).
#include "test_bdpt_util.h"

#include "core/image.h"

#include <filesystem>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string kInsideBox = "<lookat origin=\"0,0,-0.95\" target=\"0,0,1\" up=\"0,1,0\"/>";

// A closed diffuse box (coloured side walls) seen from inside, with a diffuse sphere; `extra` adds lights
// and objects.
std::string box_scene(const std::string& integrator, const std::string& extra,
                      const std::string& sensor = "") {
    return "<scene version=\"3.0.0\">" + integrator +
           (sensor.empty() ? bdpt_sensor("perspective", kInsideBox, 70.f, 24) : sensor) +
           "<shape type=\"cube\"><boolean name=\"flip_normals\" value=\"true\"/>"
           "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6,0.5,0.4\"/></bsdf></shape>"
           "<shape type=\"sphere\"><point name=\"center\" value=\"0.35,-0.6,0.3\"/><float name=\"radius\" "
           "value=\"0.35\"/><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
           "value=\"0.3,0.6,0.3\"/></bsdf></shape>" +
           extra + "</scene>";
}

const std::string kCeilingLight =
    "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.3\"/><rotate x=\"1\" "
    "angle=\"90\"/>"
    "<translate value=\"0,0.95,0\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"8\"/>"
    "</emitter></shape>";

// An open scene: a diffuse floor and a sphere seen from above.
std::string open_scene(const std::string& integrator, const std::string& extra) {
    return "<scene version=\"3.0.0\">" + integrator +
           bdpt_sensor("perspective", "<lookat origin=\"0,3,-3\" target=\"0,0,0\" up=\"0,1,0\"/>", 45.f, 24) +
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><rotate x=\"1\" "
           "angle=\"-90\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
           "value=\"0.5\"/></bsdf>"
           "</shape><shape type=\"sphere\"><point name=\"center\" value=\"0,0.5,0\"/><float name=\"radius\" "
           "value=\"0.5\"/><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
           "value=\"0.7,0.4,0.3\"/></bsdf></shape>" +
           extra + "</scene>";
}

// Samples per pixel of each render: the projector's frustum edge is a jump in the lighting whose pixels have
// heavy-tailed estimates, so it needs more samples for the spread of 12 renders to estimate the standard
// error.
struct Case {
    const char* name;
    std::string (*scene)(const std::string& integrator);
    int spp_path, spp_bdpt;
    std::string params = ""; // integrator parameters shared by path and bdpt
};

std::string cbox(const std::string& i) { return box_scene(i, kCeilingLight); }
std::string point_light(const std::string& i) {
    return box_scene(i, "<emitter type=\"point\"><point name=\"position\" value=\"-0.3,0.6,0.2\"/>"
                        "<rgb name=\"intensity\" value=\"2\"/></emitter>");
}
std::string spot_light(const std::string& i) {
    return box_scene(
        i, "<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"40\"/><rgb name=\"intensity\" "
           "value=\"6\"/><transform name=\"to_world\"><lookat origin=\"0,0.9,0\" target=\"0.2,-1,0.3\" "
           "up=\"0,0,1\"/></transform></emitter>");
}
std::string projector(const std::string& i) {
    return box_scene(
        i, "<emitter type=\"projector\"><rgb name=\"irradiance\" value=\"0.5\"/><float name=\"fov\" "
           "value=\"50\"/><transform name=\"to_world\"><lookat origin=\"-0.5,0.8,-0.5\" "
           "target=\"0.3,-1,0.5\" up=\"0,1,0\"/></transform></emitter>");
}
std::string directional_light(const std::string& i) {
    return open_scene(i, "<emitter type=\"directional\"><vector name=\"direction\" value=\"0.4,-1,0.3\"/>"
                         "<rgb name=\"irradiance\" value=\"2\"/></emitter>");
}
std::string environment(const std::string& i) {
    return open_scene(i, "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.8,0.9,1\"/></emitter>");
}
std::string glass_sphere(const std::string& i) {
    return box_scene(i, kCeilingLight +
                            "<shape type=\"sphere\"><point name=\"center\" value=\"-0.35,-0.55,0.1\"/>"
                            "<float name=\"radius\" value=\"0.3\"/><bsdf type=\"dielectric\"/></shape>");
}
std::string thinlens(const std::string& i) {
    return box_scene(
        i, kCeilingLight,
        bdpt_sensor("thinlens", kInsideBox, 70.f, 24,
                    "<float name=\"aperture_radius\" value=\"0.08\"/><float name=\"focus_distance\" "
                    "value=\"1.2\"/>",
                    "gaussian"));
}

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

std::string orthographic(const std::string& i) {
    return box_scene(i, kCeilingLight,
                     "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale value=\"0.8\"/>" +
                         kInsideBox +
                         "</transform><sampler type=\"independent\"/><film type=\"hdrfilm\"><integer "
                         "name=\"width\" value=\"24\"/><integer name=\"height\" value=\"24\"/><rfilter "
                         "type=\"box\"/></film></sensor>");
}

class BDPTvsPath : public ::testing::TestWithParam<Case> {};

TEST_P(BDPTvsPath, SameImage) {
    const Case& c = GetParam();
    const auto path = load_scene_string(c.scene(integrator_xml("path", c.params)));
    const auto bdpt = load_scene_string(c.scene(integrator_xml("bdpt", c.params)));
    const BlockStats a = block_stats(*bdpt, 12, c.spp_bdpt, 1);
    const BlockStats b = block_stats(*path, 12, c.spp_path, 100001);
    const std::vector<double> z = z_scores(a, b);
    std::printf("[bdpt vs path] %s: image mean %.5f vs %.5f, z = %.2f, max block |z| = %.2f\n", c.name,
                a.mean[0], b.mean[0], z[0], max_abs(z, 1));
    EXPECT_GT(a.mean[0], 0.0);
    EXPECT_LT(std::abs(z[0]), 4.0) << c.name;
    EXPECT_LT(max_abs(z, 1), 4.5) << c.name;
}

INSTANTIATE_TEST_SUITE_P(
    BDPT, BDPTvsPath,
    ::testing::Values(Case{"cbox", cbox, 16, 8}, Case{"point", point_light, 16, 8},
                      Case{"spot", spot_light, 16, 8}, Case{"projector", projector, 32, 16},
                      Case{"directional", directional_light, 16, 8}, Case{"environment", environment, 16, 8},
                      Case{"glass", glass_sphere, 32, 16}, Case{"thinlens", thinlens, 16, 8},
                      Case{"orthographic", orthographic, 16, 8},
                      Case{"hide_emitters", environment, 16, 8,
                           "<boolean name=\"hide_emitters\" value=\"true\"/>"},
                      Case{"max_depth_3", cbox, 16, 8, "<integer name=\"max_depth\" value=\"3\"/>"}),
    [](const auto& info) { return std::string(info.param.name); });

// An importance-sampled environment map (a bright sun over a sky gradient): the light subpaths' direction
// density and the emitter's sampling density enter the MIS weights.
TEST(BDPTvsPathEnvmap, SameImage) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "penumbra_test_bdpt_envmap";
    std::filesystem::create_directories(dir);
    Image sky(16, 8);
    for (int y = 0; y < sky.height; ++y)
        for (int x = 0; x < sky.width; ++x)
            sky.at(x, y) = Color3f(0.2f + 0.1f * float(y), 0.3f, 0.5f - 0.05f * float(y));
    sky.at(5, 2) = Color3f(60.f, 55.f, 40.f);
    write_image((dir / "sky.exr").string(), sky);
    const std::string env =
        "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/></emitter>";
    const auto path = load_scene_string(open_scene(integrator_xml("path"), env), dir.string());
    const auto bdpt = load_scene_string(open_scene(integrator_xml("bdpt"), env), dir.string());
    std::filesystem::remove_all(dir);
    const BlockStats a = block_stats(*bdpt, 12, 8, 1);
    const BlockStats b = block_stats(*path, 12, 16, 100001);
    const std::vector<double> z = z_scores(a, b);
    std::printf("[bdpt vs path] envmap: image mean %.5f vs %.5f, z = %.2f, max block |z| = %.2f\n", a.mean[0],
                b.mean[0], z[0], max_abs(z, 1));
    EXPECT_LT(std::abs(z[0]), 4.0);
    EXPECT_LT(max_abs(z, 1), 4.5);
}

// A radiance meter cannot be reached by light tracing: the other strategies must carry the whole weight.
TEST(BDPTvsPathMeter, SameRadiance) {
    const std::string meter =
        "<sensor type=\"radiancemeter\"><point name=\"origin\" value=\"0,0,-0.9\"/><vector "
        "name=\"direction\" value=\"0.2,-0.3,1\"/><sampler type=\"independent\"/><film "
        "type=\"hdrfilm\"><integer name=\"width\" value=\"1\"/><integer name=\"height\" "
        "value=\"1\"/><rfilter type=\"box\"/></film></sensor>";
    const auto path = load_scene_string(box_scene(integrator_xml("path"), kCeilingLight, meter));
    const auto bdpt = load_scene_string(box_scene(integrator_xml("bdpt"), kCeilingLight, meter));
    const BlockStats a = block_stats(*bdpt, 12, 256, 1);
    const BlockStats b = block_stats(*path, 12, 512, 100001);
    const std::vector<double> z = z_scores(a, b);
    std::printf("[bdpt vs path] radiancemeter: %.5f vs %.5f, z = %.2f\n", a.mean[0], b.mean[0], z[0]);
    EXPECT_GT(a.mean[0], 0.0);
    EXPECT_LT(std::abs(z[0]), 4.0);
}

// Light tracing on both sides: bdpt's splats (t = 1) and ptracer's normalize alike through a wide filter.
TEST(BDPTvsParticleTracer, SameImageWithGaussianFilter) {
    const std::string sensor = bdpt_sensor("perspective", kInsideBox, 70.f, 24, "", "gaussian");
    const auto ptracer = load_scene_string(box_scene(integrator_xml("ptracer"), kCeilingLight, sensor));
    const auto bdpt = load_scene_string(box_scene(integrator_xml("bdpt"), kCeilingLight, sensor));
    const BlockStats a = block_stats(*bdpt, 12, 8, 1);
    const BlockStats b = block_stats(*ptracer, 12, 16, 200001);
    const std::vector<double> z = z_scores(a, b);
    std::printf(
        "[bdpt vs ptracer] cbox, gaussian filter: image mean %.5f vs %.5f, z = %.2f, max block |z| = %.2f\n",
        a.mean[0], b.mean[0], z[0], max_abs(z, 1));
    EXPECT_LT(std::abs(z[0]), 4.0);
    EXPECT_LT(max_abs(z, 1), 4.5);
}

} // namespace
