// volpath (camera paths with NEE) against ptracer (light paths connected to the camera) on small scenes with
// homogeneous media: two different estimators of the same images. Each compares image means and 4x4-pixel
// block means over 16 independent renders per estimator (tests/volpath_test_util.h: |z| < 4 on the image
// mean, at most one block channel beyond 4). Also volpathmis against volpath on a strongly chromatic medium,
// with the ratio of their pixel variances.
#include "scene/medium.h"
#include "volpath_test_util.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

constexpr int kRes = 24;

// Medium boundaries never coincide with other surfaces (the boxes and the sphere float 0.02 above the floor):
// a ray leaving coincident surfaces crosses one of them only, and the medium it tracks is then wrong.

const std::string kFloor =
    "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><rotate x=\"1\" "
    "angle=\"-90\"/>"
    "</transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6, 0.5, 0.4\"/></bsdf></shape>";

std::string camera(const std::string& extra = "") {
    return vp_sensor("<lookat origin=\"0,1.6,3.5\" target=\"0,0.4,0\" up=\"0,1,0\"/>", kRes,
                     "<float name=\"fov\" value=\"50\"/>" + extra);
}

std::string haze(const std::string& id, const std::string& sigma_t, const std::string& albedo, float g) {
    return "<medium type=\"homogeneous\" id=\"" + id + "\"><rgb name=\"sigma_t\" value=\"" + sigma_t +
           "\"/><rgb name=\"albedo\" value=\"" + albedo +
           "\"/><phase type=\"hg\"><float name=\"g\" value=\"" + std::to_string(g) + "\"/></phase></medium>";
}

const std::string kAreaLight = "<shape type=\"rectangle\"><transform name=\"to_world\"><scale "
                               "value=\"0.6\"/><rotate x=\"1\" angle=\"90\"/>"
                               "<translate value=\"0.4,2.2,0.2\"/></transform><emitter type=\"area\"><rgb "
                               "name=\"radiance\" value=\"8\"/>"
                               "</emitter></shape>";

// A box of scattering medium behind a null boundary on the floor, lit by an area light; camera in vacuum.
std::string medium_box(const std::string& integrator, int max_depth = -1) {
    return "<scene version=\"3.0.0\">" +
           vp_integrator(integrator,
                         "<integer name=\"max_depth\" value=\"" + std::to_string(max_depth) + "\"/>") +
           haze("fog", "2", "0.8", 0.3f) + camera() + kFloor + kAreaLight +
           "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.5\"/><translate "
           "value=\"0,0.52,0\"/>"
           "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape></scene>";
}

// A delta light in a large box of haze (null boundary) around the floor, itself in a small vacuum bubble (a
// null sphere declaring only its exterior, radius 0.25), above the field of view; the camera outside, in
// vacuum. This keeps the variance finite: next-event estimation from medium points arbitrarily close to a
// point light, and light tracing from medium points around a camera inside the medium, have infinite variance
// (the 1/d² of the connection, squared, is not integrable in 3D). The light's medium comes from the walk from
// the sensor through the box and the bubble (render/light_medium.h).
std::string hazy_delta_light(const std::string& integrator, const std::string& light) {
    return "<scene version=\"3.0.0\">" + vp_integrator(integrator) + haze("haze", "0.4", "0.9", 0.5f) +
           camera() + kFloor + light +
           "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"2, 1.75, 2\"/><translate "
           "value=\"0,1.25,0\"/>"
           "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"haze\"/></shape>"
           "<shape type=\"sphere\"><point name=\"center\" value=\"-0.1,2.6,-0.9\"/><float name=\"radius\" "
           "value=\"0.25\"/><bsdf type=\"null\"/><ref name=\"exterior\" id=\"haze\"/></shape></scene>";
}

const std::string kPoint = "<emitter type=\"point\"><point name=\"position\" value=\"-0.1,2.6,-0.9\"/>"
                           "<rgb name=\"intensity\" value=\"6\"/></emitter>";
const std::string kSpot =
    "<emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"-0.1,2.6,-0.9\" "
    "target=\"0.2,0,0\" up=\"0,1,0\"/></transform><rgb name=\"intensity\" value=\"8\"/>"
    "<float name=\"cutoff_angle\" value=\"35\"/></emitter>";

// A medium box under a constant environment (emitters hidden: ptracer cannot see an infinite emitter
// directly).
std::string environment(const std::string& integrator) {
    return "<scene version=\"3.0.0\">" +
           vp_integrator(integrator, "<boolean name=\"hide_emitters\" value=\"true\"/>") +
           haze("fog", "1.5", "0.9", -0.3f) + camera() + kFloor +
           "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.8, 1, 1.2\"/></emitter>"
           "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.5\"/><translate "
           "value=\"0,0.52,0\"/>"
           "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape></scene>";
}

// A rough dielectric sphere filled with a chromatic medium (sigma_t differs 8x between channels).
std::string dielectric_sphere(const std::string& integrator) {
    return "<scene version=\"3.0.0\">" + vp_integrator(integrator) +
           haze("jelly", "0.5, 1.5, 4", "0.95", 0.0f) + camera() + kFloor + kAreaLight +
           "<shape type=\"sphere\"><point name=\"center\" value=\"0,0.52,0\"/><float name=\"radius\" "
           "value=\"0.5\"/>"
           "<bsdf type=\"roughdielectric\"><float name=\"alpha\" value=\"0.3\"/></bsdf>"
           "<ref name=\"interior\" id=\"jelly\"/></shape></scene>";
}

// A nearly conservative chromatic medium in a null box under an area light.
std::string chromatic_box(const std::string& integrator, const std::string& sigma_t) {
    return "<scene version=\"3.0.0\">" + vp_integrator(integrator) + haze("fog", sigma_t, "0.97", 0.2f) +
           camera() + kFloor + kAreaLight +
           "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.6\"/><translate "
           "value=\"0,0.62,0\"/>"
           "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape></scene>";
}

// A heterogeneous medium for the tests (the loaders' heterogeneous media are another part of the work):
// chromatic extinction ramping linearly along x, sigma_t(p) = base (1 + 0.8 x) for |x| <= 0.5, and one grey
// majorant. It sends volpath and ptracer through weighted delta tracking and ratio tracking, volpathmis
// through its heterogeneous hero-channel tracking.
class RampMedium final : public MediumBase<RampMedium> {
  public:
    explicit RampMedium(const Color3f& base) : base_(base) {}
    bool is_homogeneous() const override { return false; }
    template <typename T> Color3<T> sigma_t_t(const Vec3<T>& p) const {
        return Color3<T>(base_) * (T(1) + T(0.8f) * p.x);
    }
    template <typename T> Color3<T> albedo_t(const Vec3<T>&) const { return Color3<T>(T(0.9f)); }
    void majorants(const Vec3f&, const Vec3f&, float tmin, float tmax,
                   const MajorantVisitor& f) const override {
        if (tmin < tmax) f(tmin, tmax, max_component(base_) * 1.45f); // 1 + 0.8 · 0.5 with margin
    }

  private:
    Color3f base_;
};

// The medium box with the ramp medium in place of its homogeneous one.
std::unique_ptr<Scene> ramp_box(const std::string& integrator, const Color3f& base) {
    auto scene = load_scene_string(medium_box(integrator));
    for (auto& shape : scene->shapes)
        if (shape->interior) {
            auto ramp = std::make_shared<RampMedium>(base);
            ramp->phase = shape->interior->phase;
            shape->interior = ramp;
        }
    return scene;
}

void compare(const std::string& what, const std::function<std::string(const std::string&)>& make,
             const std::string& a, int spp_a, const std::string& b, int spp_b) {
    auto sa = load_scene_string(make(a)), sb = load_scene_string(make(b));
    expect_agreement(block_stats(*sa, 16, spp_a, 1), block_stats(*sb, 16, spp_b, 100000),
                     what + ": " + a + " vs " + b);
}

} // namespace

TEST(VolPathAgreement, NullBoundedMediumBoxAreaLight) {
    compare(
        "medium box", [](const std::string& i) { return medium_box(i); }, "volpath", 16, "ptracer", 32);
}

// max_depth counts scattering vertices, surface and medium alike, never null crossings, in both estimators:
// direct lighting and single scattering only (2), and one more bounce (3).
TEST(VolPathAgreement, MaxDepthInMedia) {
    for (int depth : {2, 3})
        compare(
            "medium box, max_depth " + std::to_string(depth),
            [depth](const std::string& i) { return medium_box(i, depth); }, "volpath", 16, "ptracer", 32);
}

TEST(VolPathAgreement, PointLightInHaze) {
    compare(
        "point in haze", [](const std::string& i) { return hazy_delta_light(i, kPoint); }, "volpath", 32,
        "ptracer", 64);
}

TEST(VolPathAgreement, SpotLightInHaze) {
    compare(
        "spot in haze", [](const std::string& i) { return hazy_delta_light(i, kSpot); }, "volpath", 32,
        "ptracer", 64);
}

// The ramp medium: volpath against ptracer, and volpathmis channel by channel against volpath on the grey
// ramp of that channel's extinction (each channel of a chromatic medium is the grey medium of its own
// sigma_t; grey weighted delta tracking has weight 1, a light-tailed reference).
TEST(VolPathAgreement, HeterogeneousChromaticMedium) {
    const Color3f base(1.f, 2.f, 4.f);
    auto vp = ramp_box("volpath", base), pt = ramp_box("ptracer", base), mis = ramp_box("volpathmis", base);
    expect_agreement(block_stats(*vp, 16, 16, 1), block_stats(*pt, 16, 32, 100000),
                     "ramp medium: volpath vs ptracer");
    const BlockStats m = block_stats(*mis, 16, 16, 200000);
    for (int c = 0; c < 3; ++c) {
        auto grey = ramp_box("volpath", Color3f(base[c]));
        expect_agreement(m, block_stats(*grey, 16, 16, 300000 + 1000 * c),
                         "ramp medium: volpathmis vs grey volpath, channel " + std::to_string(c), c);
    }
}

// Area lights inside haze: a small glowing sphere that declares the haze as its exterior (ptracer starts its
// rays in the exterior) and a rectangle declaring no medium (its medium comes from the walk from the sensor).
TEST(VolPathAgreement, AreaLightsInsideHaze) {
    compare(
        "area lights in haze",
        [](const std::string& integrator) {
            return "<scene version=\"3.0.0\">" + vp_integrator(integrator) +
                   haze("haze", "0.5", "0.8", 0.3f) + camera() + kFloor +
                   "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"2, 1.75, 2\"/>"
                   "<translate value=\"0,1.25,0\"/></transform><bsdf type=\"null\"/><ref name=\"interior\" "
                   "id=\"haze\"/>"
                   "</shape><shape type=\"sphere\"><point name=\"center\" value=\"-0.6,0.8,-0.4\"/><float "
                   "name=\"radius\" "
                   "value=\"0.2\"/><emitter type=\"area\"><rgb name=\"radiance\" value=\"4, 2, "
                   "1\"/></emitter>"
                   "<ref name=\"exterior\" id=\"haze\"/></shape>"
                   "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.4\"/><rotate "
                   "x=\"1\" angle=\"90\"/>"
                   "<translate value=\"0.5,1.5,0\"/></transform><emitter type=\"area\"><rgb "
                   "name=\"radiance\" value=\"3\"/>"
                   "</emitter></shape></scene>";
        },
        "volpath", 16, "ptracer", 32);
}

TEST(VolPathAgreement, ConstantEnvironment) {
    compare("environment", environment, "volpath", 16, "ptracer", 32);
}

TEST(VolPathAgreement, RoughDielectricSphereWithChromaticMedium) {
    compare("dielectric sphere", dielectric_sphere, "volpath", 16, "ptracer", 32);
    compare("dielectric sphere", dielectric_sphere, "volpathmis", 16, "ptracer", 32);
}

// volpathmis against volpath on a moderately chromatic medium (sigma_t 0.5 / 1 / 2): the same image.
TEST(VolPathAgreement, SpectralMISOverPathsAgainstPerSegment) {
    auto seg = load_scene_string(chromatic_box("volpath", "0.5, 1, 2"));
    auto mis = load_scene_string(chromatic_box("volpathmis", "0.5, 1, 2"));
    const BlockStats a = block_stats(*seg, 16, 16, 1), b = block_stats(*mis, 16, 16, 100000);
    expect_agreement(a, b, "chromatic medium: volpath vs volpathmis");
    std::printf(
        "[ moderately chromatic ] pixel variance volpath %.4g, volpathmis %.4g, ratio %.3f (per channel "
        "%.3f %.3f %.3f)\n",
        a.pixel_variance, b.pixel_variance, a.pixel_variance / b.pixel_variance,
        a.channel_variance[0] / b.channel_variance[0], a.channel_variance[1] / b.channel_variance[1],
        a.channel_variance[2] / b.channel_variance[2]);
}

// The variance of the two on a strongly chromatic medium (sigma_t 0.3 / 3 / 12, optical depth up to 14): the
// per-segment weights of volpath multiply up to 3 per segment along the many scattering events of the dense
// channel, so its estimate is heavy-tailed there (unbiased, but 16 renders underestimate its variance and can
// miss its mean: it is not z-tested here). volpathmis bounds each path's weight by 3. Reports the ratio of
// mean per-pixel variances (a lower bound of the true ratio) and checks that whole-path MIS is the better
// one.
TEST(VolPathAgreement, SpectralMISVarianceOnStronglyChromaticMedium) {
    auto seg = load_scene_string(chromatic_box("volpath", "0.3, 3, 12"));
    auto mis = load_scene_string(chromatic_box("volpathmis", "0.3, 3, 12"));
    const BlockStats a = block_stats(*seg, 16, 16, 1), b = block_stats(*mis, 16, 16, 100000);
    const double ratio = a.pixel_variance / b.pixel_variance;
    std::printf(
        "[ strongly chromatic ] pixel variance volpath %.4g, volpathmis %.4g, ratio volpath/volpathmis %.3f "
        "(per channel %.3f %.3f %.3f)\n",
        a.pixel_variance, b.pixel_variance, ratio, a.channel_variance[0] / b.channel_variance[0],
        a.channel_variance[1] / b.channel_variance[1], a.channel_variance[2] / b.channel_variance[2]);
    EXPECT_GT(ratio, 1.0);
}
