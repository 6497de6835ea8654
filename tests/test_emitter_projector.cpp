// Projector and textured spot emitters: Mitsuba's geometry and units against analytic answers, derivatives
// w.r.t. their parameters and an occluder in their light against finite differences, and the refusal of
// motions that the frustum's border crosses.
#include "core/image.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "render/render.h"
#include "scene/emitter.h"
#include "scene/scene.h"
#include "stored_reference.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const std::string validation = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/";

// A camera at the origin looking along +z (fov 60, box filter) at a white-ish diffuse wall at z = 2 facing
// it, lit by `light` (direct lighting only).
std::string wall_scene(const std::string& light, int res) {
    return scene(R"(<integrator type="path"><integer name="max_depth" value="2"/></integrator>
<sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value=")" +
                 std::to_string(res) + R"("/><integer name="height" value=")" + std::to_string(res) + R"("/>
        <rfilter type="box"/></film>
</sensor>
<shape type="rectangle" id="wall">
    <transform name="to_world"><scale value="10"/><rotate y="1" angle="180"/><translate value="0, 0, 2"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
</shape>
)" + light);
}

// Writes a W x H linear EXR with the given texels (row-major, top row first).
std::string write_texture(const TempDir& dir, const std::string& name, int w, int h,
                          const std::vector<Color3f>& texels) {
    Image image;
    image.width = w;
    image.height = h;
    image.pixels = texels;
    const std::string path = dir.str() + "/" + name;
    write_image(path, image);
    return path;
}

Image render_scene(const Scene& s, int spp) {
    RenderOptions o;
    o.spp = spp;
    o.seed = 3;
    o.stratified = true;
    return render(s, o);
}

// The wall point seen through the center of pixel (x, y) of the 60-degree camera (x grows to the left).
Vec2f wall_point(int x, int y, int res) {
    const float t = std::tan(radians(30.f));
    return {2.f * t * (1.f - 2.f * (x + 0.5f) / res), 2.f * t * (1.f - 2.f * (y + 0.5f) / res)};
}

} // namespace

// The lit region is the frustum's intersection with the wall: a square of side 2 z tan(fov / 2) centered on
// the projector's axis, here shifted to x = 0.5. Inside it, a diffuse wall of albedo rho perpendicular to the
// axis at distance z shows rho scale E / z² (irradiance pi scale E / z², Mitsuba's normalization).
TEST(EmitterProjector, FootprintAndIrradianceOnAPlaneFacingIt) {
    const int res = 96;
    auto s = load_scene_string(wall_scene(R"(<emitter type="projector">
    <float name="fov" value="30"/><float name="scale" value="4"/><rgb name="irradiance" value="1, 2, 3"/>
    <transform name="to_world"><lookat origin="0.5, 0, 0" target="0.5, 0, 1" up="0, 1, 0"/></transform>
</emitter>)",
                                          res));
    const Image img = render_scene(*s, 16);
    const Color3f expected = Color3f(1.f, 2.f, 3.f) * (0.5f * 4.f / 4.f);
    const float pixel_area = std::pow(4.f * std::tan(radians(30.f)) / res, 2.f);
    double area = 0, cx = 0, cy = 0;
    int interior = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            const float lit = img.at(x, y).z / expected.z; // fraction of the pixel inside the footprint
            const Vec2f p = wall_point(x, y, res);
            area += lit * pixel_area;
            cx += lit * pixel_area * p.x;
            cy += lit * pixel_area * p.y;
            const float half = 2.f * std::tan(radians(15.f));
            if (std::abs(p.x - 0.5f) < half - 0.05f && std::abs(p.y) < half - 0.05f) {
                ++interior;
                for (int k = 0; k < 3; ++k)
                    EXPECT_NEAR(img.at(x, y)[k], expected[k], 1e-4f * expected[k]) << x << "," << y;
            }
        }
    const double side = 2.0 * 2.0 * std::tan(radians(15.f));
    std::printf(
        "  lit area %.5f (analytic %.5f), centroid (%.5f, %.5f) (analytic (0.5, 0)), %d interior pixels\n",
        area, side * side, cx / area, cy / area, interior);
    EXPECT_GT(interior, 500);
    // Edge pixels are estimated from 16 stratified samples: their error averages out to well below 0.5%.
    EXPECT_NEAR(area, side * side, 5e-3 * side * side);
    EXPECT_NEAR(cx / area, 0.5, 5e-3);
    EXPECT_NEAR(cy / area, 0.0, 5e-3);
}

// Mitsuba's projector is a camera in reverse: seen from a camera at the projector with the same up vector,
// the image appears upright and unmirrored, texel (0, 0) at the top left.
TEST(EmitterProjector, ImageAppearsAsACameraAtTheProjectorSeesIt) {
    TempDir dir;
    const std::string tex = write_texture(
        dir, "quad.exr", 2, 2, {Color3f(1, 0, 0), Color3f(0, 1, 0), Color3f(0, 0, 1), Color3f(1, 1, 1)});
    const int res = 32;
    auto s = load_scene_string(wall_scene(R"(<emitter type="projector">
    <float name="fov" value="30"/>
    <texture type="bitmap" name="irradiance"><string name="filename" value=")" +
                                              tex +
                                              R"("/><string name="filter_type" value="nearest"/></texture>
</emitter>)",
                                          res));
    const Image img = render_scene(*s, 4);
    const int q = res / 4; // the lit square spans about the middle half of the image; sample its quadrants
    const int lo = res / 2 - q, hi = res / 2 + q - 1;
    EXPECT_GT(img.at(lo, lo).x, 0.f);
    EXPECT_EQ(img.at(lo, lo).y, 0.f); // top left: red
    EXPECT_GT(img.at(hi, lo).y, 0.f);
    EXPECT_EQ(img.at(hi, lo).x, 0.f); // top right: green
    EXPECT_GT(img.at(lo, hi).z, 0.f);
    EXPECT_EQ(img.at(lo, hi).x, 0.f);                                       // bottom left: blue
    EXPECT_GT(img.at(hi, hi).x * img.at(hi, hi).y * img.at(hi, hi).z, 0.f); // bottom right: white
}

// The incident term pi scale E / (d² cos³ θ) times the cosine at a plane perpendicular to the axis at
// distance z is pi scale E / z² wherever the plane is lit, for any projector pose; nothing outside the
// frustum or behind.
TEST(EmitterProjector, IrradianceOnAPerpendicularPlaneIsUniform) {
    auto s = load_scene_string(scene(R"(<emitter type="projector" id="p">
    <float name="fov" value="40"/><float name="scale" value="2"/><rgb name="irradiance" value="0.5, 1, 1.5"/>
    <transform name="to_world"><lookat origin="1, 2, 3" target="-1, 0, 4" up="0, 0, 1"/></transform>
</emitter>
<shape type="sphere"/>)"));
    const Emitter& e = *s->emitters[0];
    const Vec3f origin(1, 2, 3), axis = normalize(Vec3f(-2, -2, 1));
    const Vec3f right = normalize(cross(Vec3f(0, 0, 1), axis)), up = cross(axis, right);
    const float z = 3.f, half = z * std::tan(radians(20.f));
    for (float a : {-0.95f, -0.3f, 0.f, 0.6f, 0.95f})
        for (float b : {-0.9f, 0.f, 0.4f, 0.95f}) {
            const Vec3f p = origin + axis * z + right * (a * half) + up * (b * half);
            Interaction3f ref;
            ref.p = p;
            const auto [ds, w] = e.sample_direction(ref, Vec2f(0.5f));
            const float cos_plane = dot(ds.d, -axis);
            EXPECT_NEAR(w.y * cos_plane, Pi * 2.f * 1.f / (z * z), 1e-4f) << a << "," << b;
            EXPECT_NEAR(e.eval_delta(p).y, w.y, 1e-6f);
        }
    Interaction3f outside, behind;
    outside.p = origin + axis * z + right * (1.05f * half);
    behind.p = origin - axis * z;
    EXPECT_EQ(e.sample_direction(outside, Vec2f(0.5f)).second.y, 0.f);
    EXPECT_EQ(e.sample_direction(behind, Vec2f(0.5f)).second.y, 0.f);
}

// Mitsuba multiplies a spot's intensity by its texture at uv = 1/2 + (x, y) / (2 z tan(cutoff)) (local): a
// texture of ones changes nothing, and texel (0, 0) lies toward local -x, -y.
TEST(EmitterSpotTexture, OnesEqualNoTextureAndTexelZeroIsTowardMinusXY) {
    TempDir dir;
    const std::string ones = write_texture(dir, "ones.exr", 4, 4, std::vector<Color3f>(16, Color3f(1.f)));
    const std::string quad = write_texture(
        dir, "quad.exr", 2, 2, {Color3f(1, 0, 0), Color3f(0, 1, 0), Color3f(0, 0, 1), Color3f(1, 1, 1)});
    const auto spot = [](const std::string& texture) {
        return load_scene_string(scene(R"(<emitter type="spot"><rgb name="intensity" value="3"/>
    <float name="cutoff_angle" value="30"/>)" +
                                       texture + R"(</emitter><shape type="sphere"/>)"));
    };
    auto plain = spot("");
    auto with_ones = spot(R"(<texture type="bitmap" name="texture"><string name="filename" value=")" + ones +
                          R"("/></texture>)");
    auto with_quad = spot(R"(<texture type="bitmap" name="texture"><string name="filename" value=")" + quad +
                          R"("/><string name="filter_type" value="nearest"/></texture>)");
    for (const Vec3f& p :
         {Vec3f(0, 0, 2), Vec3f(0.3f, -0.2f, 2), Vec3f(-0.9f, 0.5f, 2), Vec3f(0.1f, 0.1f, 0.5f)}) {
        const Color3f a = plain->emitters[0]->eval_delta(p), b = with_ones->emitters[0]->eval_delta(p);
        EXPECT_GT(a.x, 0.f);
        EXPECT_NEAR(a.x, b.x, 1e-6f * a.x);
    }
    const Color3f minus_xy = with_quad->emitters[0]->eval_delta(Vec3f(-0.2f, -0.2f, 2));
    EXPECT_GT(minus_xy.x, 0.f);
    EXPECT_EQ(minus_xy.y + minus_xy.z, 0.f);
    const Color3f plus_x = with_quad->emitters[0]->eval_delta(Vec3f(0.2f, -0.2f, 2));
    EXPECT_GT(plus_x.y, 0.f);
    EXPECT_EQ(plus_x.x + plus_x.z, 0.f);
}

// Derivatives of the wall's image w.r.t. the projector's image value and scale, and a textured spot's
// intensity (interior term only: nothing moves), against central differences (diff_check.h tolerances).
TEST(EmitterProjector, DerivativesOfTheImageAndScaleMatchFiniteDifferences) {
    TempDir dir;
    std::vector<Color3f> texels;
    for (int i = 0; i < 16; ++i)
        texels.push_back(Color3f(0.2f + 0.05f * i, 1.f - 0.04f * i, 0.5f));
    const std::string tex = write_texture(dir, "grad.exr", 4, 4, texels);
    const std::string lights = R"(<emitter type="projector" id="proj">
    <float name="fov" value="30"/><float name="scale" value="3"/><rgb name="irradiance" value="1, 0.5, 0.25"/>
</emitter>
<emitter type="spot" id="spot"><rgb name="intensity" value="4"/><float name="cutoff_angle" value="25"/>
    <transform name="to_world"><lookat origin="0.5, 0.3, 0" target="0.5, 0.3, 1" up="0, 1, 0"/></transform>
    <texture type="bitmap" name="texture"><string name="filename" value=")" +
                               tex + R"("/></texture></emitter>)";
    auto s = load_scene_string(wall_scene(lights, 16));
    for (const std::string name : {"proj.irradiance.value", "proj.scale", "spot.intensity.value"}) {
        Parameters params(*s);
        params.enable({parse_param_selection(name)});
        const DerivativePair r = derivative_and_fd(*s, params, 4, 4, 1e-2);
        const DiffCheck c = check_against(r.derivative, r.fd);
        std::printf("  %s: %s\n", name.c_str(), describe(c).c_str());
        EXPECT_TRUE(c.passes()) << name << ": " << describe(c);
        EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-3) << name;
    }
}

// The hard shadow of an occluder translating in a projector's light (validation scene (a) of the boundary
// tests with -D light=projector): the direct boundary term treats the projector like a point light. The
// reference's truncation error and detection limit are estimated as in test_diff_boundary.cpp, from
// references stored at twice the samples this test used to render (tests/data/fd,
// scripts/make_test_references.sh).
TEST(EmitterProjector, ShadowOfATranslatingOccluder) {
    auto s = load_scene(validation + "shadow.xml", {{"res", "32"}, {"light", "projector"}});
    Parameters params(*s);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 16;
    o.interior.batches = 16;
    o.interior.seed = 11;
    o.interior.path = path_settings(*s);
    o.direct_spp = 256;
    const DerivativeImage d = psdr_derivative(*s, params, o);
    const StoredReference fd = stored_reference({"shadow_projector", {"light=projector"}}, 1e-2);
    const StoredReference fd2 = stored_reference({"shadow_projector_2h", {"light=projector"}}, 2e-2);
    expect_only_the_total_matches("projector occluder.translate", *s, d, fd.fd, fd2.fd, fd.h, fd.samples);
}

// The frustum's border on a moving surface is a jump of the light that no boundary term samples: refused,
// with the emitter named; an occluder strictly inside the frustum is accepted (the test above).
TEST(EmitterProjector, MotionAcrossTheFrustumBorderIsRefused) {
    auto s = load_scene(validation + "shadow.xml", {{"res", "8"}, {"light", "projector"}});
    Parameters params(*s);
    params.enable({parse_param_selection("floor.translate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 1;
    o.interior.path = path_settings(*s);
    o.direct_spp = 1;
    try {
        psdr_derivative(*s, params, o);
        FAIL() << "a floor crossing the projector's frustum border must be refused";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("floor"), std::string::npos) << msg;
        EXPECT_NE(msg.find("projector"), std::string::npos) << msg;
    }
}

// A floor strictly inside a projector's frustum (so no jump of the light crosses it) moving toward it: the
// light it receives changes through the bilinear image lookup at uv(x) and the factor |q| / q.z³, all in the
// interior term (the floor fills the view and casts no shadow).
TEST(EmitterProjector, ReceiverMovingInsideTheFrustumMatchesFiniteDifferences) {
    TempDir dir;
    std::vector<Color3f> texels;
    for (int i = 0; i < 16; ++i)
        texels.push_back(Color3f(0.3f + 0.1f * (i % 4), 1.f - 0.05f * i, 0.2f + 0.04f * i));
    const std::string tex = write_texture(dir, "grad.exr", 4, 4, texels);
    auto s =
        load_scene_string(scene(R"(<integrator type="path"><integer name="max_depth" value="2"/></integrator>
<sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 1, 0.2" target="0, -1, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
</sensor>
<shape type="rectangle" id="floor">
    <transform name="to_world"><rotate x="1" angle="-90"/><translate value="0, -1, 0"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
</shape>
<emitter type="projector" id="proj">
    <float name="fov" value="100"/><float name="scale" value="2"/>
    <transform name="to_world"><lookat origin="0.2, 1.5, 0" target="0.2, -1, 0" up="0, 0, 1"/></transform>
    <texture type="bitmap" name="irradiance"><string name="filename" value=")" +
                                tex + R"("/></texture>
</emitter>)"));
    EXPECT_FALSE(s->emitters[0]->emission_jumps_on(s->shapes[0]->mesh));
    Parameters params(*s);
    params.enable({parse_param_selection("floor.translate=0,1,0")});
    const DerivativePair r = derivative_and_fd(*s, params, 4, 4, 1e-2);
    const DiffCheck c = check_against(r.derivative, r.fd);
    std::printf("  floor.translate=0,1,0 in the projector's light: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-2);
}

// Light tracing starts paths with sample_ray (image-plane points uniform by area, weight pi scale E A): the
// wall it lights must look as the path tracer's (sample_direction) does. The mean over the image of 16
// independent light-tracing renders is compared within 4 standard errors.
TEST(EmitterProjector, LightTracingAgreesWithPathTracing) {
    TempDir dir;
    std::vector<Color3f> texels;
    for (int i = 0; i < 16; ++i)
        texels.push_back(Color3f(0.3f + 0.1f * (i % 4), 1.f - 0.05f * i, 0.5f));
    const std::string tex = write_texture(dir, "grad.exr", 4, 4, texels);
    const std::string light =
        R"(<emitter type="projector"><float name="fov" value="30"/><float name="scale" value="2"/>
    <texture type="bitmap" name="irradiance"><string name="filename" value=")" +
        tex + R"("/></texture></emitter>)";
    std::string xml = wall_scene(light, 16);
    auto path = load_scene_string(xml);
    xml.replace(xml.find("\"path\""), 6, "\"ptracer\"");
    auto ptracer = load_scene_string(xml);
    const auto image_mean = [](const Image& img) {
        double m = 0;
        for (const Color3f& c : img.pixels)
            m += c.x + c.y + c.z;
        return m / (3.0 * img.pixels.size());
    };
    // Mean and standard error of the image mean over 16 independent renders.
    const auto batched_mean = [&](const Scene& sc) {
        double sum = 0, sum2 = 0;
        const int batches = 16;
        for (int b = 0; b < batches; ++b) {
            RenderOptions o;
            o.spp = 16;
            o.seed = 100 + b;
            const double m = image_mean(render(sc, o));
            sum += m;
            sum2 += m * m;
        }
        const double mean = sum / batches;
        return std::pair{mean, std::sqrt((sum2 / batches - mean * mean) / (batches - 1))};
    };
    const auto [light_mean, light_se] = batched_mean(*ptracer);
    const auto [path_mean, path_se] = batched_mean(*path);
    std::printf("  image mean: light tracing %.6f +- %.6f, path tracing %.6f +- %.6f\n", light_mean, light_se,
                path_mean, path_se);
    EXPECT_NEAR(light_mean, path_mean, 4 * std::hypot(light_se, path_se));
    const Emitter& e = *path->emitters[0];
    EXPECT_NEAR(e.power().y, Pi * 2.f * 4.f * std::pow(std::tan(radians(15.f)), 2.f) * (1.f - 0.05f * 7.5f),
                1e-4f);
}

// Mitsuba's field-of-view options (fov / fov_axis / focal_length, shared with the perspective camera), and
// one-line errors with file:line naming the parameter.
TEST(EmitterProjector, FieldOfViewOptionsAndErrors) {
    const auto load_error = [](const std::string& body) {
        try {
            load_scene_string(scene(body + "\n<shape type=\"sphere\"/>"));
        } catch (const LoadError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(load_error(R"(<emitter type="projector"><rgb name="irradiance" value="1"/></emitter>)"), "");
    EXPECT_EQ(load_error(R"(<emitter type="projector"><rgb name="irradiance" value="1"/>
        <string name="focal_length" value="35mm"/></emitter>)"),
              "");
    EXPECT_EQ(load_error(R"(<emitter type="projector"><rgb name="irradiance" value="1"/>
        <float name="fov" value="20"/><string name="fov_axis" value="diagonal"/></emitter>)"),
              "");
    const std::string missing = load_error(R"(<emitter type="projector"/>)");
    EXPECT_NE(missing.find("irradiance"), std::string::npos) << missing;
    const std::string fov = load_error(R"(<emitter type="projector"><rgb name="irradiance" value="1"/>
        <float name="fov" value="180"/></emitter>)");
    EXPECT_NE(fov.find(":3"), std::string::npos) << fov;
    EXPECT_NE(fov.find("field of view"), std::string::npos) << fov;
    const std::string scale = load_error(R"(<emitter type="projector"><rgb name="irradiance" value="1"/>
        <float name="scale" value="-1"/></emitter>)");
    EXPECT_NE(scale.find("scale"), std::string::npos) << scale;
    const std::string unknown = load_error(R"(<emitter type="projector"><rgb name="irradiance" value="1"/>
        <float name="cutoff_angle" value="3"/></emitter>)");
    EXPECT_NE(unknown.find("cutoff_angle"), std::string::npos) << unknown;
}
