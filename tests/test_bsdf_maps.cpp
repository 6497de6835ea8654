// normalmap and bumpmap: identities (an identity normal map, a constant height field), the analytic diffuse
// shading of a tilted normal, and derivatives of the image with respect to the map texels against finite
// differences.
#include "diff_check.h"
#include "render/render.h"
#include "scene/bsdfs/bsdfs.h"
#include "scene/scene.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A square image whose texel (x, y) is f(x, y), written as a (linear) EXR.
template <typename F> std::string write_map(const TempDir& dir, const std::string& name, int size, F f) {
    Image im;
    im.width = im.height = size;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            im.pixels.push_back(f(x, y));
    const std::string path = dir.str() + "/" + name;
    write_image(path, im);
    return path;
}

Vec3f random_direction(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const float z = u(rng), phi = 2.f * Pi * u(rng), r = std::sqrt(1.f - z * z);
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// The largest |a - b| relative to max(|b|, floor) over the image channels.
double max_relative_difference(const Image& a, const Image& b, double floor) {
    double worst = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k)
            worst = std::max(worst, std::abs(double(a.pixels[i][k]) - b.pixels[i][k]) /
                                        std::max(floor, std::abs(double(b.pixels[i][k]))));
    return worst;
}

// A sphere (curved: vertex normals, dp/du with a normal component) and a plane under a point light and a dim
// area light, seen by a camera; `bsdf` is the sphere's material.
std::string sphere_scene(const std::string& bsdf) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="3"/></integrator>
      <sensor type="perspective"><float name="fov" value="35"/>
        <transform name="to_world"><lookat origin="0,-4,1.5" target="0,0,0" up="0,0,1"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film></sensor>
      <shape type="sphere">)" +
           bsdf + R"(</shape>
      <shape type="rectangle"><transform name="to_world"><scale value="4"/><translate value="0,0,-1"/></transform>
        <bsdf type="diffuse"/></shape>
      <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="180"/>
        <translate value="0,0,4"/></transform><emitter type="area"><rgb name="radiance" value="0.5"/></emitter></shape>
      <emitter type="point"><point name="position" value="1.5,-2,2"/><rgb name="intensity" value="8"/></emitter>
    </scene>)";
}

Image render_at(const Scene& scene, int spp) {
    RenderOptions o;
    o.spp = spp;
    o.seed = 5;
    return render(scene, o);
}

} // namespace

// (0.5, 0.5, 1) encodes the unperturbed normal: eval, pdf and sampling equal the nested BSDF's.
TEST(NormalMap, IdentityMapEqualsTheNestedBSDF) {
    RoughnessParams rough;
    rough.type = MicrofacetType::GGX;
    rough.alpha_u = make_constant_texture(Color3f(0.2f));
    rough.alpha_v = make_constant_texture(Color3f(0.35f));
    const BSDFPtr nested = make_roughconductor(rough, make_constant_texture(Color3f(0.2f, 0.9f, 1.1f)),
                                               make_constant_texture(Color3f(3.9f, 2.4f, 2.1f)),
                                               make_constant_texture(Color3f(1.f)));
    const BSDFPtr mapped = make_normalmap(make_constant_texture(Color3f(0.5f, 0.5f, 1.f)), nested);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    SurfaceInteraction3f si;
    BSDFContext ctx;
    for (int i = 0; i < 200; ++i) {
        si.wi = random_direction(rng);
        const Vec3f wo = random_direction(rng);
        const Color3f a = mapped->eval(ctx, si, wo), b = nested->eval(ctx, si, wo);
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(a[k], b[k], 1e-5f * std::max(1.f, b[k]));
        EXPECT_NEAR(mapped->pdf(ctx, si, wo), nested->pdf(ctx, si, wo),
                    1e-5f * std::max(1.f, nested->pdf(ctx, si, wo)));
        const float u1 = u(rng);
        const Vec2f u2(u(rng), u(rng));
        const auto [bs_a, w_a] = mapped->sample(ctx, si, u1, u2);
        const auto [bs_b, w_b] = nested->sample(ctx, si, u1, u2);
        EXPECT_NEAR(norm(bs_a.wo - bs_b.wo), 0.f, 1e-5f);
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(w_a[k], w_b[k], 1e-4f * std::max(1.f, w_b[k]));
    }
}

// A constant height field has no gradient: on a curved mesh the image equals the one without the bump map
// (same random numbers; only rounding differs).
TEST(BumpMap, ConstantHeightEqualsTheNestedBSDF) {
    TempDir dir;
    write_map(dir, "flat.exr", 4, [](int, int) { return Color3f(0.3f); });
    const std::string nested = R"(<bsdf type="roughplastic"><float name="alpha" value="0.15"/>
        <rgb name="diffuse_reflectance" value="0.6,0.3,0.2"/></bsdf>)";
    const auto with = load_scene_string(sphere_scene(R"(<bsdf type="bumpmap"><float name="scale" value="5"/>
        <texture type="bitmap" name="height"><string name="filename" value="flat.exr"/></texture>)" +
                                                     nested + "</bsdf>"),
                                        dir.str());
    const auto without = load_scene_string(sphere_scene(nested), dir.str());
    const Image a = render_at(*with, 4), b = render_at(*without, 4);
    const double diff = max_relative_difference(a, b, 1e-2);
    std::printf("  constant bump map vs none: max relative difference %.2e\n", diff);
    EXPECT_LT(diff, 1e-3);
}

// A constant normal map tilted by 30 degrees toward +s (the rectangle's dp/du = +x) under a directional light
// from (1, 0, 1) / sqrt 2: a diffuse plane then reflects L = rho E cos(theta') / pi with cos(theta') = n' .
// l, n' = (sin 30, 0, cos 30): 0.9659 (0.7071 without the map, 0.2588 tilted the other way). Direct lighting
// from a delta light is deterministic: every pixel equals the closed form up to rounding.
TEST(NormalMap, TiltedMapGivesTheDiffuseShadingOfTheTiltedNormal) {
    for (const float sign : {1.f, -1.f}) {
        const float a = 30.f * Pi / 180.f;
        const Vec3f n(sign * std::sin(a), 0.f, std::cos(a));
        const Color3f c = (n + Vec3f(1.f)) * 0.5f;
        const std::string rgb = std::to_string(c.x) + "," + std::to_string(c.y) + "," + std::to_string(c.z);
        const auto scene = load_scene_string(R"(<scene version="3.0.0">
          <integrator type="path"><integer name="max_depth" value="2"/></integrator>
          <sensor type="perspective"><float name="fov" value="20"/>
            <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
          <shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
            <bsdf type="normalmap"><rgb name="normalmap" value=")" +
                                             rgb + R"("/>
              <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></bsdf></shape>
          <emitter type="directional"><vector name="direction" value="-1,0,-1"/><rgb name="irradiance" value="2"/></emitter>
        </scene>)");
        const Image im = render_at(*scene, 4);
        const double cos_theta = dot(n, normalize(Vec3f(1.f, 0.f, 1.f)));
        const double expected = 0.5 * 2.0 * cos_theta / Pi;
        for (const Color3f& p : im.pixels)
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(p[k], expected, 1e-4 * expected) << "tilt sign " << sign;
        std::printf("  tilt %+.0f deg: pixel %.6f, closed form %.6f\n", sign * 30.0, im.pixels[0].x,
                    expected);
    }
}

namespace {

// A plane filling the view under a point light and a large dim area light out of view (as in
// test_diff_interior.cpp). A plane seen from above keeps wi and the lights above every perturbed frame: where
// a perturbed frame sees wi from below (near a curved silhouette) the BSDF jumps to zero along a curve that
// moves with the map, a shading discontinuity whose boundary term the interior estimator does not include.
std::string plane_scene(const std::string& bsdf, bool area_light = true) {
    return R"(<scene version="3.0.0">
      <integrator type="path"><integer name="max_depth" value="3"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0.5,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="rectangle"><transform name="to_world"><scale value="5"/></transform>)" +
           bsdf + "</shape>" +
           (area_light
                ? R"(<shape type="rectangle"><transform name="to_world"><scale value="1.2"/><rotate x="1" angle="135"/>
          <translate value="-0.5,2.6,1.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="0.6, 0.45, 0.3"/></emitter></shape>)"
                : "") +
           R"(<emitter type="point"><point name="position" value="0.5,0.8,1.2"/><rgb name="intensity" value="3"/></emitter>
    </scene>)";
}

// Forward-mode derivative of the image against central finite differences (tests/diff_check.h).
void expect_matches_fd(const std::string& xml, const std::string& base_dir,
                       const std::pair<std::string, std::vector<float>>& selection, double h) {
    auto scene = load_scene_string(xml, base_dir);
    Parameters params(*scene);
    params.enable({selection});
    const DerivativePair r = derivative_and_fd(*scene, params, 16, 32, h);
    const DiffCheck c = check_against(r.derivative, r.fd);
    EXPECT_TRUE(c.passes()) << selection.first << ": " << describe(c);
    std::printf("  %s: %s\n", selection.first.c_str(), describe(c).c_str());
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-4) << "the reference derivative is ~0, a weak test";
}

// An 8 x 8 map of smoothly varying normals tilted by up to ~25 degrees.
Color3f wavy_normal(int x, int y) {
    const Vec3f n = normalize(Vec3f(0.4f * std::sin(0.8f * x), 0.3f * std::cos(0.9f * y), 1.f));
    return (n + Vec3f(1.f)) * 0.5f;
}

} // namespace

// All texels' red channel (the normals' s component) moves: the shading of the whole plane changes. The image
// is curved in the texel values (with a constant map over a diffuse plane, the central difference at h = 1e-2
// was 0.6% above its h -> 0 limit, at h = 1e-3 within 1e-4 of it): h = 1e-3.
TEST(NormalMap, DerivativeWrtTheMapDataMatchesFiniteDifferences) {
    TempDir dir;
    write_map(dir, "normals.exr", 8, wavy_normal);
    const std::string xml = plane_scene(R"(<bsdf type="normalmap" id="mat">
        <texture type="bitmap" name="normalmap"><string name="filename" value="normals.exr"/></texture>
        <bsdf type="roughplastic"><float name="alpha" value="0.2"/><rgb name="diffuse_reflectance" value="0.6,0.4,0.3"/></bsdf>
      </bsdf>)",
                                        false);
    expect_matches_fd(xml, dir.str(), {"mat.normalmap.data", {1.f, 0.f, 0.f}}, 1e-3);
}

// The height field's texels move in a checkered pattern (a uniform offset would change nothing), and,
// separately, the gradient multiplier `scale`.
TEST(BumpMap, DerivativeWrtTheHeightDataAndScaleMatchesFiniteDifferences) {
    TempDir dir;
    constexpr int n = 8;
    write_map(dir, "height.exr", n,
              [](int x, int y) { return Color3f(0.05f * std::sin(0.7f * x + 0.4f * y)); });
    const std::string xml = plane_scene(R"(<bsdf type="bumpmap" id="mat"><float name="scale" value="10"/>
        <texture type="bitmap" name="height"><string name="filename" value="height.exr"/></texture>
        <bsdf type="roughplastic"><float name="alpha" value="0.2"/><rgb name="diffuse_reflectance" value="0.6,0.4,0.3"/></bsdf>
      </bsdf>)",
                                        false);
    std::vector<float> direction;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            for (int k = 0; k < 3; ++k)
                direction.push_back((x + y) % 2 == 0 ? 0.01f : -0.01f);
    expect_matches_fd(xml, dir.str(), {"mat.nested_texture.data", direction}, 1e-1);
    expect_matches_fd(xml, dir.str(), {"mat.scale", {}}, 0.05);
}

// Bad input: a one-line LoadError naming the plugin and what is missing.
TEST(BumpMap, MissingOrExtraChildrenAreLoadErrors) {
    auto expect_error = [](const std::string& bsdf, const std::string& fragment) {
        try {
            load_scene_string(scene(R"(<shape type="sphere">)" + bsdf + "</shape>"));
            ADD_FAILURE() << "no error for " << bsdf;
        } catch (const LoadError& e) {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        }
    };
    expect_error(R"(<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>)",
                 "bumpmap: expected exactly one nested height-map texture, got 0");
    expect_error(
        R"(<bsdf type="bumpmap"><texture type="checkerboard"/><texture type="checkerboard"/><bsdf type="diffuse"/></bsdf>)",
        "got 2");
    expect_error(R"(<bsdf type="bumpmap"><texture type="checkerboard"/></bsdf>)",
                 "bumpmap: expected exactly one nested BSDF, got 0");
    expect_error(R"(<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>)", "normalmap");
    expect_error(R"(<bsdf type="normalmap"><rgb name="normalmap" value="0.5,0.5,1"/></bsdf>)",
                 "normalmap: expected exactly one nested BSDF, got 0");
    expect_error(
        R"(<bsdf type="bumpmap"><float name="scal" value="2"/><texture type="checkerboard"/><bsdf type="diffuse"/></bsdf>)",
        "scal");
}
