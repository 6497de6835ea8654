// The thinlens sensor (Mitsuba's conventions: uniform concentric-disk aperture, plane in focus at
// focus_distance along local +z, ray weight 1) and the principal point offset: analytic checks of its image
// (the plane in focus renders as with a pinhole; a point out of focus spreads over the thin-lens circle of
// confusion), light tracing against path tracing with a finite aperture, the interior derivative against
// finite differences, and the boundary terms' refusal of a finite aperture.
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "render_stats.h"
#include "scene/factory.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string film(int w, int h, const std::string& filter = "gaussian") {
    return R"(<film type="hdrfilm"><integer name="width" value=")" + std::to_string(w) +
           R"("/><integer name="height" value=")" + std::to_string(h) + R"("/><rfilter type=")" + filter +
           R"("/></film>)";
}

// A checkered diffuse plane facing the camera at distance 3, under a constant environment (radiance
// independent of the direction), so that the plane's radiance toward any lens point is the same.
std::string checker_plane(const std::string& sensor) {
    return R"(<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type=)" +
           sensor + R"(<float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>)" +
           film(24, 24) + R"(</sensor>
      <shape type="rectangle"><transform name="to_world"><scale value="3"/></transform>
        <bsdf type="diffuse"><texture type="checkerboard" name="reflectance"><rgb name="color0" value="0.1"/>
          <rgb name="color1" value="0.8,0.6,0.4"/><transform name="to_uv"><scale value="4"/></transform></texture></bsdf></shape>
      <emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>)";
}

} // namespace

TEST(CamThinLens, ParsesMitsubaParametersAndRejectsBadOnes) {
    auto scene = load_scene_string(checker_plane(
        R"("thinlens"><float name="aperture_radius" value="0.2"/><float name="focus_distance" value="3"/>)"));
    EXPECT_FALSE(scene->sensor->projects_points());
    for (
        const char* bad :
        {R"("thinlens">)",                                           // aperture_radius required
         R"("thinlens"><float name="aperture_radius" value="-1"/>)", // negative
         R"("thinlens"><float name="aperture_radius" value="1"/><float name="focus_distance" value="0"/>)"}) {
        try {
            load_scene_string(checker_plane(bad));
            FAIL() << bad;
        } catch (const LoadError& e) {
            const std::string what = e.what();
            EXPECT_TRUE(what.find("aperture_radius") != std::string::npos ||
                        what.find("focus_distance") != std::string::npos)
                << what;
        }
    }
}

// Rays from every lens point through a film position meet on the plane in focus, where the pinhole's ray
// through that film position meets it too.
TEST(CamThinLens, RaysConvergeOnThePlaneInFocus) {
    auto lens = load_scene_string(checker_plane(
        R"("thinlens"><float name="aperture_radius" value="0.5"/><float name="focus_distance" value="2.5"/>)"));
    auto pinhole = load_scene_string(checker_plane(R"("perspective">)"));
    const Sensor &l = *lens->sensor, &p = *pinhole->sensor;
    const Vec3f eye(0, 0, 3), axis(0, 0, -1);
    for (const Vec2f s : {Vec2f(12.f, 12.f), Vec2f(1.5f, 20.f), Vec2f(23.f, 0.5f)}) {
        const Ray chief = p.sample_ray(s, Vec2f(0.5f)).first;
        const Vec3f focus = chief.o + chief.d * (2.5f / dot(chief.d, axis));
        float spread = 0.f;
        for (const Vec2f u : {Vec2f(0.1f, 0.2f), Vec2f(0.9f, 0.5f), Vec2f(0.4f, 0.99f)}) {
            const Ray r = l.sample_ray(s, u).first;
            const Vec3f hit = r.o + r.d * ((2.5f - dot(r.o - eye, axis)) / dot(r.d, axis));
            EXPECT_NEAR(norm(hit - focus), 0.f, 1e-5f); // float roundoff at distance 2.5
            spread = std::max(spread, norm(r.o - eye));
        }
        EXPECT_GT(spread, 0.1f); // the lens points differ
    }
}

// A plane in focus under a direction-independent illumination renders as with a pinhole (16 batches of 16
// spp).
TEST(CamThinLens, PlaneInFocusMatchesThePinholeImage) {
    auto lens = load_scene_string(checker_plane(
        R"("thinlens"><float name="aperture_radius" value="0.4"/><float name="focus_distance" value="3"/>)"));
    auto pinhole = load_scene_string(checker_plane(R"("perspective">)"));
    const BatchStats a = render_batches(*lens, 16, 16, 3), b = render_batches(*pinhole, 16, 16, 5);
    const DiffCheck c = check_against(a.mean, a.stderr_img, b.mean, b.stderr_img);
    std::printf("  in focus vs pinhole: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
    // Negative control: focused elsewhere, the checkers blur and the images differ.
    auto blurred = load_scene_string(checker_plane(
        R"("thinlens"><float name="aperture_radius" value="0.4"/><float name="focus_distance" value="1.5"/>)"));
    const BatchStats d = render_batches(*blurred, 16, 16, 3);
    const DiffCheck e = check_against(d.mean, d.stderr_img, b.mean, b.stderr_img);
    std::printf("  out of focus vs pinhole: %s\n", describe(e).c_str());
    EXPECT_FALSE(e.passes()) << describe(e);
}

// A small sphere light on the axis at depth z, focus F, aperture r: rays through the sphere's center from the
// lens disk reach the film on a uniform disk of radius R = r |1/F − 1/z| W / (2 tan(fov_x / 2)) pixels. The
// image's second moment about its centroid is R²/2 + ρ²/2 + 2 · 2/12: the sphere's own pinhole image (a disk
// of radius ρ) and the box filter (variance 1/12 per axis) add as variances of a convolution, and reading the
// moment off pixel centers adds another 1/12 per axis (Sheppard's correction for grouped data).
TEST(CamThinLens, PointOutOfFocusSpreadsOverTheCircleOfConfusion) {
    const int W = 48;
    const float r = 0.5f, F = 4.f, z = 2.f, sphere = 0.05f, tan_half = std::tan(radians(20.f));
    const std::string xml =
        R"(<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="1"/></integrator>
      <sensor type="thinlens"><float name="fov" value="40"/><float name="aperture_radius" value="0.5"/>
        <float name="focus_distance" value="4"/>)" +
        film(W, W, "box") + R"(</sensor>
      <shape type="sphere"><point name="center" value="0,0,2"/><float name="radius" value="0.05"/>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>)";
    auto scene = load_scene_string(xml);
    RenderOptions o;
    const char* env = std::getenv("PENUMBRA_TEST_SEED");
    o.spp = 2048;
    o.seed = 5 + (env ? std::strtoull(env, nullptr, 10) : 0);
    const Image image = render(*scene, o);
    double sum = 0, sx = 0, sy = 0;
    for (int y = 0; y < W; ++y)
        for (int x = 0; x < W; ++x) {
            const double v = image.at(x, y).x;
            sum += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
        }
    const double cx = sx / sum, cy = sy / sum;
    double m2 = 0;
    for (int y = 0; y < W; ++y)
        for (int x = 0; x < W; ++x)
            m2 += image.at(x, y).x * ((x + 0.5 - cx) * (x + 0.5 - cx) + (y + 0.5 - cy) * (y + 0.5 - cy));
    m2 /= sum;
    const double px_per_unit = W / (2.0 * tan_half);
    const double R = r * std::abs(1.0 / F - 1.0 / z) * px_per_unit;
    const double rho = std::tan(std::asin(sphere / z)) * px_per_unit;
    const double expected = R * R / 2 + rho * rho / 2 + 4.0 / 12.0;
    std::printf("  circle of confusion: R = %.3f px expected, measured %.3f px (second moment %.3f vs %.3f), "
                "centroid (%.3f, %.3f)\n",
                R, std::sqrt(2 * (m2 - rho * rho / 2 - 4.0 / 12.0)), m2, expected, cx, cy);
    // ~1.9e4 sphere hits: the second moment's relative standard error is ~0.58 / sqrt(N) ~ 0.4% (measured
    // 0.2-0.4% above with three seeds at 4096 spp); 2% is ~5σ, while a wrong convention (aperture diameter
    // for radius, or a blur scaled by 1/z instead of |1/F − 1/z|) is off by 10% or more.
    EXPECT_NEAR(m2 / expected, 1.0, 0.02);
    EXPECT_NEAR(cx, W / 2.0, 0.1);
    EXPECT_NEAR(cy, W / 2.0, 0.1);
}

// Light tracing connects through sample_direction's aperture sample: with a finite aperture and an
// out-of-focus scene it must agree with path tracing (16 batches each).
TEST(CamThinLens, ParticleTracerMatchesPathTracer) {
    auto xml = [](const char* integrator) {
        return std::string(R"(<scene version="3.0.0"><integrator type=")") + integrator +
               R"("><integer name="max_depth" value="3"/></integrator>
          <sensor type="thinlens"><float name="fov" value="45"/><float name="aperture_radius" value="0.3"/>
            <float name="focus_distance" value="2"/>
            <transform name="to_world"><lookat origin="0,1,3" target="0,0,0" up="0,1,0"/></transform>)" +
               film(20, 20) + R"(</sensor>
          <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.6,0.5,0.4"/></bsdf></shape>
          <shape type="cube"><transform name="to_world"><scale value="0.3"/><translate value="0.2,0.3,0"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.2,0.5,0.7"/></bsdf></shape>
          <shape type="sphere"><point name="center" value="-1,2.5,1"/><float name="radius" value="0.4"/>
            <emitter type="area"><rgb name="radiance" value="8"/></emitter></shape></scene>)";
    };
    auto path = load_scene_string(xml("path")), light = load_scene_string(xml("ptracer"));
    const BatchStats a = render_batches(*light, 16, 32, 3), b = render_batches(*path, 16, 16, 5);
    const DiffCheck c = check_against(a.mean, a.stderr_img, b.mean, b.stderr_img);
    std::printf("  ptracer vs path, thin lens: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
}

// The principal point offset (Mitsuba: a fraction of the film size added to the sample position) moves the
// image of a fixed point by −offset × size pixels, for perspective and thinlens (through the lens center).
TEST(CamThinLens, PrincipalPointOffsetShiftsTheProjection) {
    for (const char* type : {"perspective", "thinlens"}) {
        auto make = [&](float ox, float oy) {
            const std::string lens =
                std::string(type) == "thinlens" ? R"(<float name="aperture_radius" value="0.2"/>)" : "";
            return load_scene_string(checker_plane(
                "\"" + std::string(type) + "\">" + lens +
                R"(<float name="principal_point_offset_x" value=")" + std::to_string(ox) +
                R"("/><float name="principal_point_offset_y" value=")" + std::to_string(oy) + R"("/>)"));
        };
        auto base = make(0.f, 0.f), shifted = make(0.125f, -0.25f);
        const Vec3f p(0.3f, -0.2f, 0.5f);
        Vec2f a, b;
        ASSERT_TRUE(base->sensor->project(p, a));
        ASSERT_TRUE(shifted->sensor->project(p, b));
        EXPECT_NEAR(b.x - a.x, -0.125f * 24, 1e-4f) << type; // float roundoff
        EXPECT_NEAR(b.y - a.y, 0.25f * 24, 1e-4f) << type;
        // And the ray through the shifted position sees the point.
        const Ray ray = shifted->sensor->sample_ray(b, Vec2f(0.5f)).first;
        EXPECT_NEAR(norm(cross(ray.d, normalize(p - ray.o))), 0.f, 1e-5f) << type;
    }
}

namespace {

// test_diff_interior's glossy plane filling the view (no visibility change under the tested parameters), seen
// through a thin lens focused in front of it.
std::string lens_plane_xml(const std::string& bsdf) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="3"/></integrator>
      <sensor type="thinlens" id="cam"><float name="fov" value="40"/><float name="aperture_radius" value="0.15"/>
        <float name="focus_distance" value="1.5"/>
        <transform name="to_world"><lookat origin="0,0.5,3" target="0,0,0" up="0,1,0"/></transform>)" +
           film(24, 24) + R"(</sensor>
      <shape type="rectangle" id="plane"><transform name="to_world"><scale value="5"/></transform>)" +
           bsdf + R"(</shape>
      <shape type="rectangle" id="light"><transform name="to_world"><scale value="1.2"/><rotate x="1" angle="135"/>
          <translate value="-0.5,2.6,1.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="0.6, 0.45, 0.3"/></emitter></shape>
      <emitter type="point" id="bulb"><point name="position" value="0.5,0.8,1.2"/><rgb name="intensity" value="3"/></emitter>
    </scene>)";
}

const char* Glossy =
    R"(<bsdf type="roughconductor" id="mat"><float name="alpha" value="0.3"/><string name="distribution" value="ggx"/></bsdf>)";
const char* Diffuse = R"(<bsdf type="diffuse" id="mat"><rgb name="reflectance" value="0.6,0.5,0.4"/></bsdf>)";

void expect_interior_matches_fd(const std::string& xml, const std::string& param, double h) {
    auto scene = load_scene_string(xml);
    Parameters params(*scene);
    params.enable({parse_param_selection(param)});
    const DerivativePair r = derivative_and_fd(*scene, params, 16, 32, h);
    const DiffCheck c = check_against(r.derivative, r.fd);
    std::printf("  thin lens, %s: %s\n", param.c_str(), describe(c).c_str());
    EXPECT_TRUE(c.passes()) << param << ": " << describe(c);
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-4)
        << param << ": the reference derivative is ~0, a weak test";
}

} // namespace

// With a finite aperture the first vertex is in image space (the ray is fixed by the film and lens samples):
// the interior term is the whole derivative where no visibility changes.
TEST(CamThinLens, InteriorDerivativeOfReflectance) {
    expect_interior_matches_fd(lens_plane_xml(Diffuse), "mat.reflectance=1,0.5,0", 1e-2);
}
TEST(CamThinLens, InteriorDerivativeOfEmitterRadiance) {
    expect_interior_matches_fd(lens_plane_xml(Glossy), "light.emitter.radiance", 1e-2);
}
TEST(CamThinLens, InteriorDerivativeOfAPlaneMovingAlongItsNormal) {
    expect_interior_matches_fd(lens_plane_xml(Glossy), "plane.translate=0,0,1", 1e-2);
}

// What a finite aperture does not support is refused with a clear Error, never silently wrong: the boundary
// terms that connect points to a single center of projection (for parameters that move geometry), the
// material-form first vertex, and a moving camera. Parameters that move nothing still run every term (their
// boundary terms are 0).
TEST(CamThinLens, UnsupportedDerivativesAreRefused) {
    auto scene = load_scene_string(lens_plane_xml(Glossy));
    Parameters params(*scene);
    PsdrOptions o;
    o.interior.spp = 1;
    o.interior.batches = 1;
    o.primary_spp = o.direct_spp = o.indirect_spp = o.pixel_spp = 1;
    params.enable({parse_param_selection("plane.translate=0,0,1")});
    for (const char* term : {"primary", "direct", "indirect"}) {
        PsdrOptions one = o;
        one.primary_spp = std::string(term) == "primary";
        one.direct_spp = std::string(term) == "direct";
        one.indirect_spp = std::string(term) == "indirect";
        try {
            psdr_derivative(*scene, params, one);
            FAIL() << term;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(term), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("thinlens"), std::string::npos) << e.what();
        }
        EXPECT_THROW(psdr_gradient(*scene, params, Image(24, 24), one), Error) << term;
    }
    DiffOptions material = o.interior;
    material.first_vertex = FirstVertex::Material;
    EXPECT_THROW(render_derivative(*scene, params, material), Error);
    params.enable({parse_param_selection("cam.translate=1,0,0")});
    EXPECT_THROW(render_derivative(*scene, params, o.interior), Error);
    params.enable({parse_param_selection("mat.alpha")});
    EXPECT_NO_THROW(psdr_derivative(*scene, params, o));
}
