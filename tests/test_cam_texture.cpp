// Textures: bitmap lookups (uv convention, filters, wrap modes, sRGB), checkerboard pattern, constant.
#include "core/image.h"
#include "diff/parameters.h"
#include "diff_check.h"
#include "scene/factory.h"
#include "scene/scene.h"
#include "scene/shape.h"
#include "scene/texture.h"
#include "xml_test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

struct TextureFixture : ::testing::Test {
    fs::path dir = fs::temp_directory_path() / ("penumbra_cam_texture_" + std::to_string(::getpid()));
    LoadContext ctx;
    Image img{4, 2};

    void SetUp() override {
        fs::create_directories(dir);
        ctx.search_paths = {dir.string()};
        // Pixel (x, y) holds (x, y, 10 + x + 4 y): every texel is distinct and identifies its position.
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 4; ++x)
                img.at(x, y) = Color3f(float(x), float(y), 10.f + x + 4.f * y);
        write_image((dir / "grid.exr").string(), img);
    }
    void TearDown() override { fs::remove_all(dir); }

    std::shared_ptr<Texture> bitmap(const std::string& file, const std::string& filter = "",
                                    const std::string& wrap = "", bool raw = false,
                                    const Transform* to_uv = nullptr) {
        const SourceLocation loc{"scene.xml", 7};
        Properties props("bitmap", loc);
        props.set("filename", file, loc);
        if (!filter.empty()) props.set("filter_type", filter, loc);
        if (!wrap.empty()) props.set("wrap_mode", wrap, loc);
        if (raw) props.set("raw", true, loc);
        if (to_uv) props.set("to_uv", *to_uv, loc);
        auto obj = make_texture(props, ctx);
        EXPECT_TRUE(props.unqueried().empty());
        return std::static_pointer_cast<Texture>(obj);
    }
};

Color3f at_uv(const Texture& tex, float u, float v) {
    SurfaceInteraction3f si;
    si.uv = Vec2f(u, v);
    return tex.eval(si);
}

void expect_near(const Color3f& a, const Color3f& b, float tol) {
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(a[i], b[i], tol) << a << " vs " << b;
}

// Interpolation of exactly stored float texels: only single-precision roundoff (values <= 20, ~1e-6
// relative).
constexpr float Tol = 1e-5f;

} // namespace

TEST_F(TextureFixture, NearestUsesTopLeftOrigin) {
    auto tex = bitmap("grid.exr", "nearest");
    // uv (0,0) is the top-left corner; v grows downward through the image rows (Mitsuba's convention).
    EXPECT_EQ(at_uv(*tex, 0.1f, 0.1f), img.at(0, 0));
    EXPECT_EQ(at_uv(*tex, 0.9f, 0.9f), img.at(3, 1));
    EXPECT_EQ(at_uv(*tex, 0.3f, 0.7f), img.at(1, 1));
}

// Mitsuba's bitmap eval_1 (roughness, blend weights, opacity, bump heights) is the luminance of the texel color
// (0.212671 R + 0.715160 G + 0.072169 B), not the channel mean; its uv gradient is the gradient of that.
TEST_F(TextureFixture, SingleChannelValueIsTheLuminance) {
    auto tex = bitmap("grid.exr", "nearest");
    SurfaceInteraction3f si;
    si.uv = Vec2f(0.3f, 0.7f); // texel (1, 1) = (1, 1, 15)
    EXPECT_NEAR(tex->eval_1(si), 0.212671f + 0.715160f + 0.072169f * 15.f, Tol);
    auto bilinear = bitmap("grid.exr");
    si.uv = Vec2f(1.5f / 4.f, 0.5f / 2.f); // texel (1, 0) = (1, 0, 11): d/du = W (f(2,0) - f(1,0)) = 4 (R + B)
    const Vec2f grad = bilinear->eval_1_grad(si);
    EXPECT_NEAR(grad.x, 4.f * (0.212671f + 0.072169f), 1e-4f);
}

TEST_F(TextureFixture, BilinearInterpolatesBetweenTexelCenters) {
    auto tex = bitmap("grid.exr");
    // At a texel center the value is the texel itself.
    expect_near(at_uv(*tex, 2.5f / 4.f, 0.5f / 2.f), img.at(2, 0), Tol);
    // Half way between the centers of (1,0), (2,0), (1,1), (2,1): the average of the four.
    const Color3f avg = (img.at(1, 0) + img.at(2, 0) + img.at(1, 1) + img.at(2, 1)) * 0.25f;
    expect_near(at_uv(*tex, 0.5f, 0.5f), avg, Tol);
    // A quarter of the way from center (0,0) to center (1,0).
    expect_near(at_uv(*tex, 0.75f / 4.f, 0.25f), img.at(0, 0) * 0.75f + img.at(1, 0) * 0.25f, Tol);
}

TEST_F(TextureFixture, WrapModes) {
    auto repeat = bitmap("grid.exr", "nearest", "repeat");
    auto mirror = bitmap("grid.exr", "nearest", "mirror");
    auto clamp = bitmap("grid.exr", "nearest", "clamp");
    // u = -0.3 -> texel column floor(-1.2) = -2: repeat -> 2, mirror -> 1, clamp -> 0.
    EXPECT_EQ(at_uv(*repeat, -0.3f, 0.25f), img.at(2, 0));
    EXPECT_EQ(at_uv(*mirror, -0.3f, 0.25f), img.at(1, 0));
    EXPECT_EQ(at_uv(*clamp, -0.3f, 0.25f), img.at(0, 0));
    // v = 1.3 -> row floor(2.6) = 2: repeat -> 0, mirror -> 1, clamp -> 1.
    EXPECT_EQ(at_uv(*repeat, 0.1f, 1.3f), img.at(0, 0));
    EXPECT_EQ(at_uv(*mirror, 0.1f, 1.3f), img.at(0, 1));
    EXPECT_EQ(at_uv(*clamp, 0.1f, 1.3f), img.at(0, 1));
    // Bilinear at the left edge (u = 0) blends column 0 with column -1: 3 under repeat, 0 under clamp/mirror.
    auto bil_repeat = bitmap("grid.exr", "bilinear", "repeat");
    auto bil_clamp = bitmap("grid.exr", "bilinear", "clamp");
    expect_near(at_uv(*bil_repeat, 0.f, 0.25f), (img.at(0, 0) + img.at(3, 0)) * 0.5f, Tol);
    expect_near(at_uv(*bil_clamp, 0.f, 0.25f), img.at(0, 0), Tol);
}

TEST_F(TextureFixture, ToUvAndMean) {
    const Transform to_uv =
        Transform::translate(Vec3f(0.25f, 0.f, 0.f)) * Transform::scale(Vec3f(0.5f, 1.f, 1.f));
    auto tex = bitmap("grid.exr", "nearest", "", false, &to_uv);
    // u' = 0.5 u + 0.25: u = 0.9 -> 0.7 -> column 2.
    EXPECT_EQ(at_uv(*tex, 0.9f, 0.25f), img.at(2, 0));
    expect_near(tex->mean(), Color3f(1.5f, 0.5f, 13.5f), Tol);
    EXPECT_FALSE(tex->is_constant());
}

TEST_F(TextureFixture, EightBitFilesAreSrgbDecodedUnlessRaw) {
    Image png(2, 1);
    png.at(0, 0) = Color3f(srgb_to_linear(128.f / 255.f));
    png.at(1, 0) = Color3f(1.f);
    write_image((dir / "gray.png").string(), png);
    auto decoded = bitmap("gray.png", "nearest");
    auto raw = bitmap("gray.png", "nearest", "", true);
    // Code 128 decodes to 0.2158605 (IEC 61966-2-1); float pow roundoff ~1e-7.
    EXPECT_NEAR(at_uv(*decoded, 0.25f, 0.5f).x, 0.2158605f, 1e-6f);
    EXPECT_NEAR(at_uv(*raw, 0.25f, 0.5f).x, 128.f / 255.f, 1e-6f);
    // EXR data is linear whatever `raw` says.
    auto exr_raw = bitmap("grid.exr", "nearest", "", true);
    EXPECT_EQ(at_uv(*exr_raw, 0.9f, 0.9f), img.at(3, 1));
}

TEST_F(TextureFixture, BadParametersAreLoadErrors) {
    EXPECT_THROW(bitmap("grid.exr", "trilinear"), LoadError);
    EXPECT_THROW(bitmap("grid.exr", "", "wrap"), LoadError);
    EXPECT_THROW(bitmap("missing.png"), LoadError);
    const std::string garbage = (dir / "garbage.jpg").string();
    {
        std::FILE* f = std::fopen(garbage.c_str(), "w");
        std::fputs("nope", f);
        std::fclose(f);
    }
    try {
        bitmap("garbage.jpg");
        FAIL();
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find("scene.xml:7"), std::string::npos) << e.what();
    }
}

TEST(CamTexture, CheckerboardPattern) {
    LoadContext ctx;
    Properties props("checkerboard", {"scene.xml", 3});
    auto tex = std::static_pointer_cast<Texture>(make_texture(props, ctx));
    // Mitsuba: color0 (0.4) where (frac(u) > .5) == (frac(v) > .5), else color1 (0.2).
    EXPECT_EQ(at_uv(*tex, 0.25f, 0.25f), Color3f(0.4f));
    EXPECT_EQ(at_uv(*tex, 0.75f, 0.25f), Color3f(0.2f));
    EXPECT_EQ(at_uv(*tex, 0.25f, 0.75f), Color3f(0.2f));
    EXPECT_EQ(at_uv(*tex, 0.75f, 0.75f), Color3f(0.4f));
    EXPECT_EQ(at_uv(*tex, 1.25f, -0.25f), Color3f(0.2f)); // frac(-0.25) = 0.75
    EXPECT_EQ(tex->mean(), Color3f(0.3f));

    Properties scaled("checkerboard", {"scene.xml", 4});
    scaled.set("color0", ColorValue{Color3f(1.f, 0.f, 0.f)}, {"scene.xml", 5});
    scaled.set("to_uv", Transform::scale(Vec3f(4.f, 4.f, 1.f)), {"scene.xml", 6});
    auto tex4 = std::static_pointer_cast<Texture>(make_texture(scaled, ctx));
    EXPECT_TRUE(scaled.unqueried().empty());
    EXPECT_EQ(at_uv(*tex4, 0.0625f, 0.0625f), Color3f(1.f, 0.f, 0.f)); // (0.25, 0.25) after scaling
    EXPECT_EQ(at_uv(*tex4, 0.1875f, 0.0625f), Color3f(0.2f));          // (0.75, 0.25)
}

TEST(CamTexture, ConstantAndUnsupported) {
    auto c = make_constant_texture(Color3f(0.1f, 0.2f, 0.3f));
    EXPECT_TRUE(c->is_constant());
    EXPECT_EQ(at_uv(*c, 5.f, -3.f), Color3f(0.1f, 0.2f, 0.3f));
    SurfaceInteraction3f si;
    EXPECT_NEAR(c->eval_1(si), 0.2f, 1e-7f); // mean of the channels, float roundoff
    LoadContext ctx;
    EXPECT_THROW(make_texture(Properties("wavelet", {"scene.xml", 9}), ctx), LoadError);
}

// rawconstant: the value as given (negative or above 1 too: no color conversion), float broadcast to 3
// channels; traverse() names it `value` as Mitsuba does.
TEST(CamTexture, RawConstant) {
    LoadContext ctx;
    Properties vec("rawconstant", {"scene.xml", 3});
    vec.set("value", Vec3f(0.5f, -2.f, 3.f), {"scene.xml", 4});
    auto v = std::static_pointer_cast<Texture>(make_texture(vec, ctx));
    EXPECT_EQ(at_uv(*v, 0.3f, 0.7f), Color3f(0.5f, -2.f, 3.f));
    Properties one("rawconstant", {"scene.xml", 3});
    one.set("value", 0.25, {"scene.xml", 4});
    EXPECT_EQ(at_uv(*std::static_pointer_cast<Texture>(make_texture(one, ctx)), 0.f, 0.f), Color3f(0.25f));
    struct Names final : ParamVisitor {
        std::vector<std::string> names;
        void put(const std::string& name, float*, int, int*, bool) override { names.push_back(name); }
        void put_object(const std::string&, Object*) override {}
    } names;
    v->traverse(names);
    EXPECT_EQ(names.names, std::vector<std::string>{"value"});
    Properties bad("rawconstant", {"scene.xml", 3});
    bad.set("value", std::string("red"), {"scene.xml", 5});
    EXPECT_THROW(make_texture(bad, ctx), LoadError);
}

TEST_F(TextureFixture, FormatAndAccel) {
    Image tenth(2, 2, Color3f(0.1f));
    write_image((dir / "tenth.exr").string(), tenth);
    auto load = [&](const std::string& format) {
        const SourceLocation loc{"scene.xml", 7};
        Properties props("bitmap", loc);
        props.set("filename", std::string("tenth.exr"), loc);
        props.set("format", format, {"scene.xml", 8});
        props.set("accel", false, {"scene.xml", 9});
        auto obj = make_texture(props, ctx);
        EXPECT_TRUE(props.unqueried().empty());
        return std::static_pointer_cast<Texture>(obj);
    };
    EXPECT_EQ(at_uv(*load("variant"), 0.3f, 0.3f).x, 0.1f);
    EXPECT_EQ(at_uv(*load("auto"), 0.3f, 0.3f).x, 0.1f);
    EXPECT_EQ(at_uv(*load("fp16"), 0.3f, 0.3f).x, 0.0999755859375f); // the nearest half to 0.1
    EXPECT_THROW(load("fp8"), LoadError);
}

// mesh_attribute on a PLY written here: a quad (fan-split into triangles (0,1,2), (0,2,3)) with float vertex
// colors color_r/g/b -> vertex_color, a float `weight` -> vertex_weight (1D, broadcast), and 8-bit face
// colors red/green/blue -> face_color (normalized and sRGB-decoded, as Mitsuba's PLY loader flags them).
TEST(CamTexture, MeshAttributesFromPly) {
    test::TempDir dir;
    dir.write("quad.ply", R"(ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
property float color_r
property float color_g
property float color_b
property float weight
element face 1
property list uchar int vertex_indices
property uchar red
property uchar green
property uchar blue
end_header
0 0 0 1 0 0 0.5
1 0 0 0 1 0 1.5
1 1 0 0 0 1 2.5
0 1 0 1 1 1 3.5
4 0 1 2 3 255 128 0
)");
    auto scene = load_scene_string(
        test::scene(R"(<shape type="ply"><string name="filename" value="quad.ply"/></shape>)"), dir.str());
    const Shape& shape = *scene->shapes.at(0);
    ASSERT_EQ(shape.mesh.face_count(), 2u);
    ASSERT_TRUE(shape.mesh.attribute("vertex_color"));
    EXPECT_EQ(shape.mesh.attribute("vertex_color")->dim, 3);
    ASSERT_TRUE(shape.mesh.attribute("face_color"));

    auto texture = [](const std::string& name, float scale) {
        Properties props("mesh_attribute", {"scene.xml", 3});
        props.set("name", name, {"scene.xml", 4});
        if (scale != 1.f) props.set("scale", double(scale), {"scene.xml", 5});
        LoadContext ctx;
        return std::static_pointer_cast<Texture>(make_texture(props, ctx));
    };
    SurfaceInteraction3f si;
    si.shape = &shape;
    si.prim_index = 1; // triangle (0, 2, 3)
    si.bary = Vec2f(0.25f, 0.5f);
    const uint32_t* tri = &shape.mesh.indices[3];
    ASSERT_EQ(tri[0], 0u);
    ASSERT_EQ(tri[1], 2u);
    ASSERT_EQ(tri[2], 3u);
    // 0.25 (1,0,0) + 0.25 (0,0,1) + 0.5 (1,1,1), times the scale 2.
    const Color3f color = texture("vertex_color", 2.f)->eval(si);
    EXPECT_NEAR(color.x, 2.f * 0.75f, 1e-6f);
    EXPECT_NEAR(color.y, 2.f * 0.5f, 1e-6f);
    EXPECT_NEAR(color.z, 2.f * 0.75f, 1e-6f);
    EXPECT_NEAR(texture("vertex_weight", 1.f)->eval(si).y, 0.25f * 0.5f + 0.25f * 2.5f + 0.5f * 3.5f, 1e-6f);
    for (uint32_t face : {0u, 1u}) {
        si.prim_index = face;
        const Color3f c = texture("face_color", 1.f)->eval(si);
        EXPECT_EQ(c, Color3f(1.f, srgb_to_linear(128.f / 255.f), 0.f)) << face;
    }
    EXPECT_THROW(texture("vertex_normal_thing", 1.f)->eval(si), Error);
    Properties bad("mesh_attribute", {"scene.xml", 3});
    bad.set("name", std::string("color"), {"scene.xml", 4});
    LoadContext ctx;
    EXPECT_THROW(make_texture(bad, ctx), LoadError);
}

// The bitmap's `data` (Mitsuba's traverse() key) against central finite differences: a diffuse plane textured
// by a 4x4 bitmap fills the view; the direction raises only the texels of the left half (x < 2), so an
// indexing error (a transposed or shifted texel) changes where the derivative lies. Tolerances:
// tests/diff_check.h.
TEST(CamTexture, BitmapDataDerivativeMatchesFiniteDifferences) {
    test::TempDir dir;
    Image texels(4, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            texels.at(x, y) = Color3f(0.2f + 0.1f * x, 0.3f + 0.1f * y, 0.5f);
    write_image(dir.str() + "/texels.exr", texels);
    auto scene = load_scene_string(
        test::scene(R"(<integrator type="path"><integer name="max_depth" value="2"/></integrator>
      <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
      <shape type="rectangle"><transform name="to_world"><scale value="1.5"/></transform>
        <bsdf type="diffuse" id="mat"><texture type="bitmap" name="reflectance"><string name="filename" value="texels.exr"/></texture></bsdf></shape>
      <emitter type="point"><point name="position" value="0.3,0.5,2"/><rgb name="intensity" value="4"/></emitter>
      <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>)"),
        dir.str());
    std::string direction;
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            for (int c = 0; c < 3; ++c)
                direction += std::string(direction.empty() ? "" : ",") + (x < 2 ? "1" : "0");
    Parameters params(*scene);
    params.enable({parse_param_selection("mat.reflectance.data=" + direction)});
    const test::DerivativePair r = test::derivative_and_fd(*scene, params, 16, 32, 1e-2);
    const test::DiffCheck c = test::check_against(r.derivative.derivative, r.derivative.stderr_img,
                                                  r.fd.derivative, r.fd.stderr_img);
    EXPECT_TRUE(c.passes()) << test::describe(c);
    std::printf("  mat.reflectance.data: %s\n", test::describe(c).c_str());
    // The derivative lives on one half of the plane: texels x < 2 reach u < 0.625 through the bilinear
    // interpolation, world x < 0.375; the outer 5 columns on each side see |world x| > 0.64. One side must be
    // ~0 and the other clearly not (which side is the image's left depends on the camera's handedness).
    double side[2] = {0, 0};
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 24; ++x)
            if (x < 5 || x >= 19) side[x < 5 ? 0 : 1] += std::abs(r.fd.derivative.at(x, y).x);
    EXPECT_GT(std::max(side[0], side[1]), 1e-3);
    EXPECT_LT(std::min(side[0], side[1]), 0.01 * std::max(side[0], side[1])) << side[0] << " vs " << side[1];
}
