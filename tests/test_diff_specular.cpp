// Delta lobes (issue 35, item 4; docs/design.md, "Delta lobes"): a smooth mirror turning and a smooth glass
// ball moving. A delta lobe fixes the outgoing direction given the incident one, so the vertex after it is
// where that direction, turning with the geometry, meets its surface (no area integral there), and the lobe's
// smooth factor (Fresnel, reflectance) follows the angles. Before, with the vertex after a delta lobe at its
// material point and the lobe's weight constant, every estimator missed what the mirror reflects (psdr's
// image mean 0.215 against central differences 0.884 on the 32² mirror, the mirror's own silhouette only; the
// bidirectional interior 0.216, war-bdpt 0.165) and the path sampling methods read the mirror's reflectance
// as 0 (against 0.146).
#include "diff_cases.h"
#include "diff_check.h"
#include "stored_reference.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

LoadedCase load_specular(const std::string& file, const std::string& param,
                         const std::vector<std::string>& defines) {
    std::map<std::string, std::string> values{{"res", "16"}};
    for (const std::string& d : defines)
        values[d.substr(0, d.find('='))] = d.substr(d.find('=') + 1);
    LoadedCase l;
    l.scene = load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/specular/" + file, values);
    l.params = std::make_unique<Parameters>(*l.scene);
    l.params->enable({parse_param_selection(param)});
    return l;
}

// `method` with `options` at `spp` (in `batches`) against the stored central differences of `key` at step h
// (tests/data/fd, scripts/make_test_references.sh), with their truncation error from the step 2h where the
// derivative is not linear in the parameter.
void expect_matches_fd(const std::string& method, const std::map<std::string, std::string>& options,
                       const std::string& file, const std::string& param, const StoredKey& key, double h,
                       bool truncation, int spp, int batches = 8) {
    const LoadedCase l = load_specular(file, param, key.defines);
    const DerivativeImage d = method_derivative(method, options, l, spp, 11 + 1000 * test_seed(), batches);
    const StoredReference fd = stored_reference(key, h);
    const Image error =
        truncation ? with_truncation_error(fd.fd.stderr_img, fd.fd,
                                           stored_reference({key.name + "_2h", key.defines}, 2 * h).fd)
                   : fd.fd.stderr_img;
    const DiffCheck c = check_against(d.derivative, d.stderr_img, fd.fd.derivative, error);
    std::printf("  %s on %s, %s, %d spp in %.1f s: %s\n", method.c_str(), key.name.c_str(), param.c_str(),
                spp, d.seconds, describe(c).c_str());
    EXPECT_TRUE(c.passes()) << method << " " << param << ": " << describe(c);
}

// The reflection without the mirror's own edges (whose silhouettes carry was's known bias at N' = 32,
// docs/warped-area-sampling.md): the methods that warp vertices are checked on the delta lobe there.
const StoredKey mirror_inner{"mirror_turn_inner", {"crop_x=4", "crop_y=6", "crop_width=8", "crop_height=6"}};

struct MirrorCase {
    std::string label, method;
    std::map<std::string, std::string> options;
    int spp;
    bool inner = false; // on the crop without the mirror's edges
};

const std::vector<MirrorCase> mirror_cases = {
    {"psdr", "psdr", {}, 256},
    {"psdr_material", "psdr", {{"first-vertex", "material"}}, 256},
    {"bidirectional", "psdr", {{"interior-estimator", "bidirectional"}}, 128},
    {"war", "war", {{"war-aux", "16"}}, 256, true},
    {"was", "was", {}, 256, true},
    {"war_bdpt", "war-bdpt", {{"war-aux", "16"}}, 128, true},
};

class MirrorTurning : public testing::TestWithParam<MirrorCase> {};

} // namespace

// Every reflected ray turns with the mirror: the derivative of the wall's image in it.
TEST_P(MirrorTurning, MatchesFiniteDifferences) {
    const MirrorCase& c = GetParam();
    expect_matches_fd(c.method, c.options, "mirror.xml", "mirror.rotate=1,0,0",
                      c.inner ? mirror_inner : StoredKey{"mirror_turn", {}}, 2e-3, true, c.spp);
}

INSTANTIATE_TEST_SUITE_P(Methods, MirrorTurning, testing::ValuesIn(mirror_cases),
                         [](const testing::TestParamInfo<MirrorCase>& info) { return info.param.label; });

// The conductor's reflectance scales its delta lobe: path replay differentiates the lobe's smooth factor. Its
// tails are heavier than psdr's here (at 2048 spp in 8 batches, one seed in six reads z 4.1): 16 batches.
TEST(Specular, MirrorReflectanceByPathSamplingMatchesFiniteDifferences) {
    expect_matches_fd("paths", {}, "mirror.xml", "mirror.bsdf.specular_reflectance.value=1,1,1",
                      {"mirror_reflectance", {}}, 1e-2, false, 4096, 16);
}

// Chains of refractions (and the Fresnel reflections inside), rays leaving the ball for the environment, and
// the ball's silhouette (the primary term).
TEST(Specular, GlassBallMovingMatchesFiniteDifferences) {
    expect_matches_fd("psdr", {}, "glass_ball.xml", "ball.translate=1,0,0", {"glass_ball_slide", {}}, 2e-3,
                      true, 1024);
}

// The same ball with a scattering medium inside (volpath, diff/psdr/interior_media.h): medium vertices after
// a refraction keep their free-flight distance along the refracted direction (8 × 8 crop of the ball).
TEST(Specular, MurkyGlassBallMovingMatchesFiniteDifferences) {
    expect_matches_fd("psdr", {}, "murky_ball.xml", "ball.translate=1,0,0",
                      {"murky_ball_slide", {"crop_x=4", "crop_y=4", "crop_width=8", "crop_height=8"}}, 2e-3,
                      true, 2048);
}

// A discontinuity seen only through a delta lobe — here a card's silhouette and shadow reflected in a mirror
// — has no boundary term yet (the boundary terms reach the camera by next-event connections): the methods
// that differentiate visibility refuse it in one line instead of returning the derivative without it
// (diff/specular_chains.h). Before, psdr returned such a derivative: a ball in front of a mirror read +0.0008
// against central differences −0.0016 (32², the reflected silhouette's pixels 0 against −6.4).
TEST(Specular, EdgesSeenOnlyInAMirrorAreRefused) {
    const std::string scene = R"(<scene version="3.0.0">
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 1, 3" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
      <shape type="rectangle" id="mirror"><bsdf type="conductor"/>
        <transform name="to_world"><scale value="1.5"/><translate value="0, 0.5, -1"/></transform></shape>
      <shape type="rectangle" id="plane"><bsdf type="diffuse"/>
        <transform name="to_world"><scale value="0.2"/><translate value="0.3, 0.5, 0"/></transform></shape>
      <emitter type="point"><point name="position" x="0" y="2" z="2"/><rgb name="intensity" value="5"/></emitter>
    </scene>)";
    for (const std::string method : {"psdr", "war", "was"}) {
        const std::string error = derivative_error(method, scene);
        EXPECT_NE(error.find("seen only through the delta lobes of 'mirror'"), std::string::npos)
            << method << ": " << error;
    }
}
