// volpath, volpathmis, bdpt and ptracer estimate the same images on scenes with participating media:
// homogeneous and heterogeneous media behind null and dielectric boundaries, chromatic extinction, the
// sensor and the lights inside a medium, with area, point, spot and environment lights.
//
// Each integrator renders 16 independent batches; images are compared after 4x4 block averaging, block
// statistics taken per batch so that splatting integrators' correlated pixels are handled. With 15 degrees of
// freedom and ~100 block channels per scene, a block |z| above 5 (t-distribution tail ~2e-4 per block) or an
// image-mean |z| above 4 in any channel means bias, not bad luck.
#include "scene/scene.h"
#include "volpath_test_util.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

constexpr int kRes = 24, kBatches = 16;

// Block statistics of one integrator on the scene (tests/volpath_test_util.h: 4x4 pixel blocks per channel
// and the per-channel image means, statistics taken per batch).
BlockStats estimate(const std::string& xml, const std::string& integrator, int spp) {
    std::string s = xml;
    s.replace(s.find("$integrator"), 11, integrator);
    return block_stats(*load_scene_string(s), kBatches, spp, 17);
}

void expect_agree(const BlockStats& a, const BlockStats& b, const std::string& what) {
    const size_t n = a.mean.size();
    ASSERT_EQ(n, b.mean.size()) << what;
    double worst_mean = 0, worst = 0, image_mean = 0;
    for (size_t i = n - 3; i < n; ++i) { // the image mean, per channel
        const double z = (a.mean[i] - b.mean[i]) / std::hypot(a.stderr_[i], b.stderr_[i]);
        EXPECT_LT(std::abs(z), 4.0) << what << ": image mean (channel " << i - (n - 3) << ") " << a.mean[i]
                                    << " ± " << a.stderr_[i] << " vs " << b.mean[i] << " ± " << b.stderr_[i];
        if (std::abs(z) > std::abs(worst_mean)) worst_mean = z;
        image_mean += a.mean[i];
    }
    EXPECT_GT(image_mean, 0.0) << what << ": black image";
    for (size_t i = 0; i + 3 < n; ++i) {
        const double se = std::hypot(a.stderr_[i], b.stderr_[i]);
        const double d = a.mean[i] - b.mean[i];
        if (se > 0)
            worst = std::max(worst, std::abs(d) / se);
        else
            EXPECT_EQ(d, 0.0) << what << ": block channel " << i << " differs without noise";
    }
    EXPECT_LT(worst, 5.0) << what << ": largest block |z|";
    std::printf("[ agreement ] %-44s image mean z %+.2f (largest channel), worst block |z| %.2f\n",
                what.c_str(), worst_mean, worst);
}

std::string
camera(const std::string& medium_ref = "",
       const std::string& lookat = R"(<lookat origin="0, 0.3, 3" target="0, 0, 0" up="0, 1, 0"/>)") {
    return R"(<sensor type="perspective"><float name="fov" value="45"/><transform name="to_world">)" +
           lookat + "</transform>" + medium_ref + R"(<film type="hdrfilm"><integer name="width" value=")" +
           std::to_string(kRes) + R"("/><integer name="height" value=")" + std::to_string(kRes) +
           R"("/><rfilter type="box"/></film></sensor>)";
}

const char* kFloor =
    R"(<shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/>
    <translate value="0, -1, 0"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>)";

// A cube of chromatic haze behind a null boundary, on a floor, under an area light.
std::string null_box_scene(const std::string& medium) {
    return R"(<scene version="3.0.0"><integrator type="$integrator"><integer name="max_depth" value="6"/></integrator>)" +
           camera() + medium + kFloor + R"(
  <shape type="cube"><transform name="to_world"><scale value="0.8"/><rotate y="1" angle="30"/></transform>
    <bsdf type="null"/><ref name="interior" id="fog"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.6"/><rotate x="1" angle="90"/>
    <translate value="0.4, 2, 0.5"/></transform><emitter type="area"><rgb name="radiance" value="8"/></emitter></shape>
</scene>)";
}

const char* kChromaticFog = R"(<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="0.5, 1.5, 3"/>
    <rgb name="albedo" value="0.9, 0.7, 0.5"/><phase type="hg"><float name="g" value="0.5"/></phase></medium>)";

// Mitsuba's .vol format (version 3, float32): a 8x8x8 single-channel density bump.
std::string write_vol(const std::string& dir) {
    const std::string path = (std::filesystem::path(dir) / "bump.vol").string();
    std::ofstream out(path, std::ios::binary);
    out.write("VOL", 3);
    const uint8_t version = 3;
    out.write(reinterpret_cast<const char*>(&version), 1);
    const int32_t header[5] = {1, 8, 8, 8, 1};
    out.write(reinterpret_cast<const char*>(header), sizeof(header));
    const float bbox[6] = {0, 0, 0, 1, 1, 1};
    out.write(reinterpret_cast<const char*>(bbox), sizeof(bbox));
    for (int z = 0; z < 8; ++z)
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                const float dx = (x - 3.5f) / 4, dy = (y - 3.5f) / 4, dz = (z - 3.5f) / 4;
                const float d = 3.f * std::max(0.f, 1.f - (dx * dx + dy * dy + dz * dz));
                out.write(reinterpret_cast<const char*>(&d), sizeof(float));
            }
    return path;
}

} // namespace

TEST(MediaAgreement, ChromaticHomogeneousBehindNullBoundary) {
    const std::string xml = null_box_scene(kChromaticFog);
    const BlockStats ref = estimate(xml, "volpath", 32);
    expect_agree(ref, estimate(xml, "volpathmis", 32), "null box: volpathmis vs volpath");
    expect_agree(ref, estimate(xml, "bdpt", 8), "null box: bdpt vs volpath");
    expect_agree(ref, estimate(xml, "ptracer", 32), "null box: ptracer vs volpath");
}

TEST(MediaAgreement, HeterogeneousGridBehindNullBoundary) {
    TempDir dir;
    const std::string medium =
        R"(<medium type="heterogeneous" id="fog"><volume name="sigma_t" type="gridvolume">
        <string name="filename" value=")" +
        write_vol(dir.str()) + R"("/><transform name="to_world">
        <translate value="-0.5, -0.5, -0.5"/><scale value="1.6"/></transform></volume>
        <rgb name="albedo" value="0.8, 0.6, 0.9"/></medium>)";
    const std::string xml = null_box_scene(medium);
    const BlockStats ref = estimate(xml, "volpath", 32);
    expect_agree(ref, estimate(xml, "bdpt", 8), "grid: bdpt vs volpath");
    expect_agree(ref, estimate(xml, "ptracer", 32), "grid: ptracer vs volpath");
}

// The camera sits in haze that fills a closed room (the sensor's medium); a spot and a point light sit in
// small vacuum bubbles inside it, whose media the integrators find from the sensor (render/light_medium.h).
// The bubbles keep medium points away from the lights: next-event estimation from medium points arbitrarily
// close to a point light has infinite variance (∫ d⁻⁴ d² dd diverges), which would make the standard errors
// meaningless; for the same reason ptracer is not compared here (a pinhole camera inside a scattering medium
// receives W/d² from points arbitrarily close to it).
TEST(MediaAgreement, SpotAndPointLightsInHaze) {
    auto bubble = [](const std::string& center) {
        return R"(<shape type="sphere"><point name="center" value=")" + center +
               R"("/><float name="radius" value="0.2"/><bsdf type="null"/><ref name="exterior" id="haze"/></shape>)";
    };
    const std::string xml =
        R"(<scene version="3.0.0"><integrator type="$integrator"><integer name="max_depth" value="5"/></integrator>
  <medium type="homogeneous" id="haze"><rgb name="sigma_t" value="0.4"/><rgb name="albedo" value="0.8"/>
    <phase type="hg"><float name="g" value="0.3"/></phase></medium>)" +
        camera(R"(<ref name="medium" id="haze"/>)",
               R"(<lookat origin="0, 0, 1.5" target="0, -0.3, 0" up="0, 1, 0"/>)") +
        R"(
  <shape type="cube"><transform name="to_world"><scale value="2"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></bsdf>
    <ref name="interior" id="haze"/></shape>)" +
        bubble("0.5, 1.5, 0") + bubble("-1.2, -1.2, -1.2") + R"(
  <emitter type="spot"><transform name="to_world"><lookat origin="0.5, 1.5, 0" target="0, -2, 0" up="0, 0, 1"/></transform>
    <rgb name="intensity" value="10"/><float name="cutoff_angle" value="25"/></emitter>
  <emitter type="point"><point name="position" value="-1.2, -1.2, -1.2"/><rgb name="intensity" value="3, 2, 1"/></emitter>
</scene>)";
    const BlockStats ref = estimate(xml, "volpath", 32);
    expect_agree(ref, estimate(xml, "volpathmis", 32), "haze, spot + point: volpathmis vs volpath");
    expect_agree(ref, estimate(xml, "bdpt", 8), "haze, spot + point: bdpt vs volpath");
}

// A glass sphere filled with a scattering medium under a constant environment (dielectric boundary).
TEST(MediaAgreement, DielectricSphereFilledWithMediumUnderEnvironment) {
    const std::string xml =
        R"(<scene version="3.0.0"><integrator type="$integrator"><integer name="max_depth" value="12"/></integrator>)" +
        camera() + R"(
  <medium type="homogeneous" id="milk"><rgb name="sigma_t" value="2, 3, 4"/><rgb name="albedo" value="0.95, 0.9, 0.8"/></medium>
  <shape type="sphere"><float name="radius" value="0.8"/><bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf>
    <ref name="interior" id="milk"/></shape>)" +
        kFloor + R"(
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>)";
    const BlockStats ref = estimate(xml, "volpath", 32);
    expect_agree(ref, estimate(xml, "bdpt", 8), "milk sphere, env: bdpt vs volpath");
}
