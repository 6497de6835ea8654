// hdrfilm options (pixel_format, component_format, sample_border, banner) and the `moment` integrator.
#include "core/image.h"
#include "diff/parameters.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "render/film_output.h"
#include "render/integrator.h"
#include "scene/factory.h"
#include "scene/film.h"
#include "scene/scene.h"
#include "xml_test_util.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::shared_ptr<Film> film_from(const std::map<std::string, std::string>& strings) {
    Properties props("hdrfilm", {"scene.xml", 4});
    int line = 5;
    for (const auto& [name, value] : strings)
        props.set(name, value, {"scene.xml", line++});
    auto film = std::static_pointer_cast<Film>(make_film(props, LoadContext{}));
    EXPECT_TRUE(props.unqueried().empty());
    return film;
}

// An orthographic camera looking down -z at the rectangle [-1, 1]^2 (radiance 1), which fills its view
// exactly; nothing lies beyond the film's edges. `film_extra` goes inside <film>, `scale` shrinks the
// rectangle.
std::string emitter_scene(const std::string& film_extra, const std::string& integrator = "",
                          float scale = 1.f) {
    return scene(
        (integrator.empty() ? std::string("<integrator type=\"path\"><integer name=\"max_depth\" "
                                          "value=\"1\"/></integrator>")
                            : integrator) +
        R"(<sensor type="orthographic"><transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="1024"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>)" +
        film_extra + R"(</film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value=")" +
        std::to_string(scale) + R"("/></transform>
    <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>)");
}

// ∫_a^b f / ∫ f for the filter's 1D profile (midpoint rule, 20000 points): independent of the film's table.
double profile_mass(const ReconstructionFilter& f, double a, double b) {
    const int n = 20000;
    const double r = f.radius();
    auto integrate = [&](double lo, double hi) {
        lo = std::max(lo, -r), hi = std::min(hi, r);
        double sum = 0.0;
        const double h = (hi - lo) / n;
        for (int i = 0; i < n && hi > lo; ++i)
            sum += f.eval(float(lo + (i + 0.5) * h)) * h;
        return sum;
    };
    return integrate(a, b) / integrate(-r, r);
}

struct ExrFile {
    std::map<std::string, Imf::PixelType> types;
    std::map<std::string, std::vector<float>> values;
};

ExrFile read_exr_channels(const std::string& path) {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    ExrFile out;
    Imf::FrameBuffer fb;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
        out.types[it.name()] = it.channel().type;
        out.values[it.name()].resize(size_t(w) * h);
    }
    for (auto& [name, v] : out.values)
        fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(v.data()), sizeof(float),
                                   sizeof(float) * w));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return out;
}

} // namespace

TEST(FilmOptions, ParsesMitsubaFormats) {
    EXPECT_EQ(film_from({})->pixel_format, Film::PixelFormat::RGB);
    EXPECT_EQ(film_from({})->component_format, ComponentFormat::Float16);
    EXPECT_FALSE(film_from({})->sample_border);
    EXPECT_EQ(film_from({{"pixel_format", "luminance_alpha"}})->pixel_format,
              Film::PixelFormat::LuminanceAlpha);
    EXPECT_EQ(film_from({{"pixel_format", "XYZA"}})->pixel_format,
              Film::PixelFormat::XYZA); // Mitsuba lowercases
    EXPECT_EQ(film_from({{"component_format", "uint32"}})->component_format, ComponentFormat::UInt32);

    Properties border("hdrfilm", {"scene.xml", 4});
    border.set("sample_border", true, {"scene.xml", 5});
    border.set("banner", false, {"scene.xml", 6});
    auto film = std::static_pointer_cast<Film>(make_film(border, LoadContext{}));
    EXPECT_TRUE(film->sample_border);
    EXPECT_TRUE(border.unqueried().empty());

    Properties bad("hdrfilm", {"scene.xml", 4});
    bad.set("pixel_format", std::string("rgbw"), {"scene.xml", 9});
    try {
        make_film(bad, LoadContext{});
        FAIL();
    } catch (const LoadError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("scene.xml:9"), std::string::npos) << msg;
        EXPECT_NE(msg.find("luminance_alpha"), std::string::npos) << msg;
    }
}

// Without sample_border each pixel's filter is cut to the film and renormalized: P_j integrates to 1 over the
// film, positions never leave it, and interior pixels are untouched. With it, the edge pixel's filter keeps
// the mass it has beyond the film (Mitsuba: samples are drawn in a border band the filter reaches into).
TEST(FilmOptions, SampleBorderFilterNormalization) {
    for (const char* filter : {"gaussian", "tent"}) {
        auto film = film_from({});
        film->width = film->height = 6;
        film->rfilter = std::static_pointer_cast<ReconstructionFilter>(
            make_rfilter(Properties(filter, {"scene.xml", 2}), LoadContext{}));
        const double mx = profile_mass(*film->rfilter, -0.5, 5.5); // pixel 0: centre 0.5 of [0, 6]
        EXPECT_NEAR(film->film_mass(0, 0), mx * mx, 2e-4) << filter;
        EXPECT_EQ(film->film_mass(3, 2), 1.f) << filter;

        // ∫_film P_0(s) ds = 1 (midpoint rule on a 600^2 grid over the film).
        const int n = 600;
        double sum = 0.0;
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j)
                sum += film->filter_weight(0, 0, Vec2f((i + 0.5f) * 6.f / n, (j + 0.5f) * 6.f / n));
        EXPECT_NEAR(sum * (6.0 / n) * (6.0 / n), 1.0, 2e-3) << filter;

        // Positions stay on the film; their mean offset from the centre is the truncated filter's mean,
        // ∫ t f(t) dt / ∫ f(t) dt over t in [-0.5, 5.5] (midpoint rule).
        double mean_x = 0.0, moment = 0.0, mass = 0.0;
        const int m = 20000;
        for (int k = 0; k < m; ++k) {
            const Vec2f p = film->sample_position(0, 0, Vec2f((k + 0.5f) / m, 0.5f));
            ASSERT_GE(p.x, 0.f);
            ASSERT_GE(p.y, 0.f);
            mean_x += (p.x - 0.5) / m;
        }
        for (int i = 0; i < n; ++i) {
            const double t = (i + 0.5) * 6.0 / n - 0.5;
            moment += t * film->rfilter->eval(float(t));
            mass += film->rfilter->eval(float(t));
        }
        EXPECT_NEAR(mean_x, moment / mass, 2e-3) << filter;
        // Interior pixels: the same positions as the untruncated filter.
        const Vec2f u(0.3f, 0.8f), off = film->rfilter->sample(u), p = film->sample_position(3, 2, u);
        EXPECT_EQ(p.x, 3.5f + off.x);
        EXPECT_EQ(p.y, 2.5f + off.y);
    }
}

// A rectangle emitter that fills the orthographic view exactly, with nothing beyond the film. Mitsuba's film
// averages filter-weighted samples: without sample_border every sample lies on the emitter, so every pixel is
// 1; with it the edge pixels also average the black border band, giving the filter's mass over the film.
TEST(FilmOptions, SampleBorderAtTheImageEdge) {
    RenderOptions options;
    options.seed = 3;
    const Image cut = render(*load_scene_string(emitter_scene("<rfilter type=\"gaussian\"/>")), options);
    for (const Color3f& c : cut.pixels)
        ASSERT_NEAR(c.x, 1.f, 1e-5f);

    auto scene = load_scene_string(
        emitter_scene("<rfilter type=\"gaussian\"/><boolean name=\"sample_border\" value=\"true\"/>"));
    const Image border = render(*scene, options);
    const ReconstructionFilter& f = *scene->sensor->film->rfilter;
    // Pixel centres 0.5 and 1.5 lie 0.5 and 1.5 from the edge; the gaussian (stddev 0.5) reaches 2.
    const double m0 = profile_mass(f, -0.5, 7.5), m1 = profile_mass(f, -1.5, 6.5);
    const int spp = 1024;
    auto expect_fraction = [&](int x, int y, double p) {
        // A hit fraction over spp independent samples: standard error sqrt(p (1 - p) / spp).
        const double se = std::sqrt(std::max(p * (1.0 - p), 1e-4) / spp);
        EXPECT_NEAR(border.at(x, y).x, p, 4.0 * se) << "pixel " << x << "," << y;
    };
    std::printf("  sample_border edge pixel: %.4f (expected %.4f), without it: %.4f\n", border.at(0, 0).x,
                m0 * m0, cut.at(0, 0).x);
    expect_fraction(0, 0, m0 * m0);
    expect_fraction(1, 0, m1 * m0);
    expect_fraction(7, 7, m0 * m0);
    expect_fraction(3, 0, m0);
    expect_fraction(4, 4, 1.0);
    EXPECT_LT(m0, 0.9); // the check can fail: the edge pixel is measurably darker
}

// Alpha: the fraction of the pixel's camera rays that hit a surface (Mitsuba's `valid_ray`); a half-size
// rectangle covers pixels 2..5 of 8 exactly with a box filter.
TEST(FilmOptions, AlphaIsCoverage) {
    auto scene = load_scene_string(
        emitter_scene("<rfilter type=\"box\"/><string name=\"pixel_format\" value=\"rgba\"/>", "", 0.5f));
    RenderOptions options;
    options.spp = 16;
    const std::vector<Layer> layers = render_layers(*scene, options);
    ASSERT_EQ(layers.size(), 2u);
    EXPECT_EQ(layers[1].channels, "A");
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            const bool inside = x >= 2 && x < 6 && y >= 2 && y < 6;
            EXPECT_EQ(layers[1].image.at(x, y).x, inside ? 1.f : 0.f) << x << "," << y;
            EXPECT_EQ(layers[0].image.at(x, y).x, inside ? 1.f : 0.f) << x << "," << y;
        }
}

// EXR channels and storage types as Mitsuba's hdrfilm writes them, and the PNG fallbacks.
TEST(FilmOptions, PixelAndComponentFormatsInFiles) {
    TempDir dir;
    std::vector<Layer> layers{{"", Image(2, 1), "RGB"}, {"dd", Image(2, 1), "RGB"}, {"", Image(2, 1), "A"}};
    layers[0].image.at(0, 0) = Color3f(0.25f, 0.5f, 1.f);
    layers[0].image.at(1, 0) = Color3f(2.f, 1.f, 0.5f);
    layers[1].image.at(1, 0) = Color3f(7.f, 8.f, 9.f);
    layers[2].image.at(0, 0) = Color3f(0.5f);
    layers[2].image.at(1, 0) = Color3f(1.f);
    auto film = film_from({});
    const Color3f c0 = layers[0].image.at(0, 0);

    struct Case {
        Film::PixelFormat format;
        ComponentFormat component;
        std::vector<std::string> channels;
        Imf::PixelType type;
    };
    using PF = Film::PixelFormat;
    const Case cases[] = {
        {PF::RGB, ComponentFormat::Float16, {"B", "G", "R", "dd.B", "dd.G", "dd.R"}, Imf::HALF},
        {PF::RGBA, ComponentFormat::Float32, {"A", "B", "G", "R", "dd.B", "dd.G", "dd.R"}, Imf::FLOAT},
        {PF::Luminance, ComponentFormat::Float32, {"Y", "dd.B", "dd.G", "dd.R"}, Imf::FLOAT},
        {PF::LuminanceAlpha, ComponentFormat::Float16, {"A", "Y", "dd.B", "dd.G", "dd.R"}, Imf::HALF},
        {PF::XYZ, ComponentFormat::Float32, {"X", "Y", "Z", "dd.B", "dd.G", "dd.R"}, Imf::FLOAT},
        {PF::XYZA, ComponentFormat::UInt32, {"A", "X", "Y", "Z", "dd.B", "dd.G", "dd.R"}, Imf::UINT}};
    for (const Case& c : cases) {
        film->pixel_format = c.format;
        film->component_format = c.component;
        const std::string path = dir.str() + "/out.exr";
        write_film(path, *film, layers);
        const ExrFile exr = read_exr_channels(path);
        std::vector<std::string> names;
        for (const auto& [name, type] : exr.types) {
            names.push_back(name);
            EXPECT_EQ(type, c.type) << name;
        }
        EXPECT_EQ(names, c.channels);
        const float tol = c.component == ComponentFormat::Float16 ? 2e-3f : 1e-6f;
        if (c.component == ComponentFormat::UInt32) {
            // Normalized integers: [0, 1] maps to [0, 2^32 - 1]; 1.27 (X of (2, 1, 0.5)) clamps to 1.
            EXPECT_NEAR(exr.values.at("A")[0], 0.5f * 4294967295.f, 512.f);
            EXPECT_EQ(exr.values.at("X")[1], 4294967295.f);
            continue;
        }
        if (c.format == PF::Luminance || c.format == PF::LuminanceAlpha) {
            EXPECT_NEAR(exr.values.at("Y")[0], 0.212671f * c0.x + 0.715160f * c0.y + 0.072169f * c0.z, tol);
        }
        if (c.format == PF::XYZ) {
            EXPECT_NEAR(exr.values.at("X")[0], 0.412453f * c0.x + 0.357580f * c0.y + 0.180423f * c0.z, tol);
            EXPECT_NEAR(exr.values.at("Z")[0], 0.019334f * c0.x + 0.119193f * c0.y + 0.950227f * c0.z, tol);
        }
        if (c.format == PF::RGBA) {
            EXPECT_EQ(exr.values.at("A")[0], 0.5f);
        }
        EXPECT_NEAR(exr.values.at("dd.R")[1], 7.f, 8 * tol);
    }

    // PNG: gray + alpha for luminance_alpha, read back as 8-bit sRGB with a linear alpha.
    film->pixel_format = PF::LuminanceAlpha;
    const std::string png = dir.str() + "/out.png";
    write_film(png, *film, layers);
    const Image back = read_image(png, true);
    EXPECT_NEAR(back.at(0, 0).x, luminance(c0), 0.01f);
    EXPECT_EQ(back.at(0, 0).x, back.at(0, 0).z); // gray

    film->pixel_format = PF::RGBA;
    layers.pop_back();
    EXPECT_THROW(write_film(png, *film, layers), Error); // alpha requested but not rendered
}

// moment: the main image is the nested integrator's (same samples), <name> holds its XYZ average and
// m2_<name> the average of the squared XYZ samples, so m2 - m1^2 >= 0 (a sample variance) and is > 0 where
// paths are noisy.
TEST(FilmOptions, MomentIntegrator) {
    const std::string lit =
        R"(<integrator type="moment"><integrator type="path" name="pt"><integer name="max_depth" value="3"/></integrator></integrator>)";
    auto body = [](const std::string& integrator) {
        return scene(
            integrator +
            R"(<sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
  <emitter type="constant"><rgb name="radiance" value="0.5, 1, 2"/></emitter>
  <shape type="sphere"><bsdf type="diffuse"/></shape>)");
    };
    auto moment = load_scene_string(body(lit));
    auto plain = load_scene_string(
        body(R"(<integrator type="path"><integer name="max_depth" value="3"/></integrator>)"));
    RenderOptions options;
    options.seed = 11;
    const std::vector<Layer> layers = render_layers(*moment, options);
    ASSERT_EQ(layers.size(), 3u);
    EXPECT_EQ(layers[1].name, "pt");
    EXPECT_EQ(layers[1].channels, "XYZ");
    EXPECT_EQ(layers[2].name, "m2_pt");
    const Image reference = render(*plain, options);
    double variance = 0.0;
    for (size_t i = 0; i < reference.pixels.size(); ++i) {
        ASSERT_EQ(layers[0].image.pixels[i], reference.pixels[i]) << i;
        const Color3f xyz = srgb_to_xyz(reference.pixels[i]), m1 = layers[1].image.pixels[i],
                      m2 = layers[2].image.pixels[i];
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(m1[k], xyz[k], 1e-5f * (1.f + std::abs(xyz[k])));
            EXPECT_GE(m2[k] - m1[k] * m1[k], -1e-5f * m2[k]);
            variance += m2[k] - m1[k] * m1[k];
        }
    }
    EXPECT_GT(variance, 0.01); // diffuse bounces under a coloured sky: the samples do vary

    // A nested aov integrator: its layers are prefixed with its name, then squared; it has no main image.
    auto with_aov = load_scene_string(body(
        R"(<integrator type="moment"><integrator type="aov" name="a"><string name="aovs" value="dd:depth"/></integrator></integrator>)"));
    options.spp = 2;
    const std::vector<Layer> aov_layers = render_layers(*with_aov, options);
    std::vector<std::string> names;
    for (const Layer& l : aov_layers)
        names.push_back(l.name);
    EXPECT_EQ(names, (std::vector<std::string>{"", "a.dd", "a", "m2_a.dd", "m2_a"}));
    EXPECT_EQ(aov_layers[1].channels, "T"); // Mitsuba's depth channel: a.dd.T
    EXPECT_EQ(aov_layers[3].channels, "T");
    TempDir dir;
    write_film(dir.str() + "/moment.exr", *with_aov->sensor->film, aov_layers);
    const ExrFile exr = read_exr_channels(dir.str() + "/moment.exr");
    for (const char* channel : {"R", "a.dd.T", "a.X", "a.Z", "m2_a.dd.T", "m2_a.Y"})
        EXPECT_TRUE(exr.types.count(channel)) << channel;
    EXPECT_EQ(exr.types.size(), 3u + 1u + 3u + 1u + 3u);
    EXPECT_THROW(load_scene_string(scene(R"(<integrator type="moment"/>)")), LoadError);
}

// Without sample_border a gaussian pixel filter is cut at the film's edge, so under camera motion the edge
// pixels gain and lose what crosses the film's edge: the pixel-boundary term runs along the film's edge
// (paper 001 §4.3 with P_j = Film::filter_weight). The total must match central differences and the interior
// term alone must not. Tolerances: tests/diff_check.h.
TEST(FilmOptions, FilmEdgeTermUnderCameraMotion) {
    auto scene = load_scene(std::string(PENUMBRA_SOURCE_DIR) + "/scenes/validation/pixel_edges.xml",
                            {{"res", "16"}, {"filter", "gaussian"}});
    ASSERT_FALSE(scene->sensor->film->sample_border);
    Parameters params(*scene);
    params.enable({parse_param_selection("cam.translate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 16;
    o.interior.batches = 16;
    o.interior.seed = 5;
    o.interior.path = path_settings(*scene);
    o.primary_spp = o.direct_spp = o.indirect_spp = 0;
    o.pixel_spp = 256;
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    RenderOptions ro;
    ro.spp = 512;
    ro.seed = 17;
    const FiniteDifference fd = finite_difference(*scene, params, 1e-2, ro, 16);
    const test::DiffCheck total = test::check_against(d, fd);
    const test::DiffCheck interior = test::check_against(
        d.term("interior").derivative, d.term("interior").stderr_img, fd.derivative, fd.stderr_img);
    std::printf("  film edge, cam.translate: interior+pixel %s\n  interior only %s\n",
                test::describe(total).c_str(), test::describe(interior).c_str());
    EXPECT_TRUE(total.passes()) << test::describe(total);
    EXPECT_FALSE(interior.passes()) << "the film-edge term should matter: " << test::describe(interior);
}
