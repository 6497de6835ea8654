// volpath / volpathmis / ptracer against analytic answers in media, against `path` without media,
// determinism, and Mitsuba's homogeneous-medium documentation scene. Tolerances are multiples of standard
// errors estimated from independent renders (16 batches: 15 degrees of freedom, P(|t| > 4) ~ 1.2e-3).
#include "render/render.h"
#include "render_stats.h"
#include "scene/scene.h"
#include "volpath_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

const char* const kVolumetric[] = {"volpath", "volpathmis", "ptracer"};

// Every pixel channel against a constant per channel: image-mean |z| < 4 and at most 2% of pixel channels
// beyond |z| = 4 (unbiased: ~0.1%; a per-pixel bias of one standard error already gives ~2%).
void expect_constant_image(const Scene& scene, int batches, int spp, const Color3f& expected,
                           const std::string& what) {
    const int w = scene.sensor->film->width, h = scene.sensor->film->height;
    std::vector<double> sum(size_t(w) * h * 3, 0.0), sum2(sum.size(), 0.0), means(3 * batches, 0.0);
    for (int b = 0; b < batches; ++b) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = 11 + uint64_t(b) * 7919;
        const Image im = render(scene, opt);
        for (size_t i = 0; i < im.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const double v = im.pixels[i][c];
                sum[i * 3 + c] += v;
                sum2[i * 3 + c] += v * v;
                means[size_t(b) * 3 + c] += v / im.pixels.size();
            }
    }
    int bad = 0;
    for (size_t i = 0; i < sum.size(); ++i) {
        const double m = sum[i] / batches;
        const double se = std::sqrt(std::max(0.0, (sum2[i] / batches - m * m) / (batches - 1)));
        const double d = std::abs(m - expected[int(i % 3)]);
        if (se > 0 ? d > 4.0 * se : d > 1e-5 * expected[int(i % 3)]) ++bad;
    }
    EXPECT_LE(double(bad) / sum.size(), 0.02) << what << ": pixel channels beyond 4 standard errors";
    for (int c = 0; c < 3; ++c) {
        double m = 0, m2 = 0;
        for (int b = 0; b < batches; ++b) {
            m += means[size_t(b) * 3 + c];
            m2 += means[size_t(b) * 3 + c] * means[size_t(b) * 3 + c];
        }
        m /= batches;
        const double se = std::sqrt(std::max(0.0, (m2 / batches - m * m) / (batches - 1)));
        const double z =
            se > 0 ? (m - expected[c]) / se : (std::abs(m - expected[c]) < 1e-5 ? 0.0 : INFINITY);
        EXPECT_LT(std::abs(z), 4.0) << what << " channel " << c << ": mean " << m << " expected "
                                    << expected[c];
        std::printf("[ %s ] channel %d: mean %.5f expected %.5f z = %+.2f, %d/%zu pixel outliers\n",
                    what.c_str(), c, m, expected[c], z, bad, sum.size());
    }
}

// A closed sphere (radius 1) emitting L inward over a black surface; inside it a null-boundary sphere filled
// with a conservative (albedo 1), forward-scattering medium in which the camera sits. Radiance is L
// everywhere inside (the equilibrium of a non-absorbing medium in a uniformly glowing cavity). The extinction
// is grey: with a chromatic one the per-segment channel weights make the estimate heavy-tailed (unbiased, but
// 16 batches then underestimate its standard error).
std::unique_ptr<Scene> medium_furnace(const std::string& integrator) {
    return load_scene_string(
        "<scene version=\"3.0.0\">" + vp_integrator(integrator) +
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_t\" value=\"2\"/>"
        "<float name=\"albedo\" value=\"1\"/><phase type=\"hg\"><float name=\"g\" "
        "value=\"0.5\"/></phase></medium>" +
        vp_sensor("<lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/>", 8,
                  "<float name=\"fov\" value=\"90\"/><ref id=\"fog\"/>") +
        "<shape type=\"sphere\"><boolean name=\"flip_normals\" value=\"true\"/>"
        "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"0.4, 0.6, 0.8\"/></emitter></shape>"
        "<shape type=\"sphere\"><float name=\"radius\" value=\"0.8\"/><bsdf type=\"null\"/>"
        "<ref name=\"interior\" id=\"fog\"/></shape></scene>");
}

} // namespace

// ptracer is not run here: light tracing from medium points around a pinhole inside the medium has infinite
// variance (the connection's 1/d² squared, integrated over the volume around the camera, diverges).
TEST(VolPath, MediumFurnaceIsUniform) {
    for (const char* integrator : {"volpath", "volpathmis"})
        expect_constant_image(*medium_furnace(integrator), 16, 8, Color3f(0.4f, 0.6f, 0.8f),
                              std::string("furnace ") + integrator);
}

// An orthographic camera (view [-1,1]²) looks through a purely absorbing slab (thickness 1, null boundary) at
// an area light that just covers the view: every pixel is L exp(-sigma_t,c · 1) per channel. ptracer needs
// more paths: only the fraction 4/5.76 of its emitted points lands in the view, one pixel each.
TEST(VolPath, AbsorbingSlabTransmittance) {
    const Color3f sigma(0.3f, 1.f, 2.5f), L(2.f, 3.f, 4.f);
    for (const char* integrator : kVolumetric) {
        auto scene = load_scene_string(
            "<scene version=\"3.0.0\">" + vp_integrator(integrator) +
            "<medium type=\"homogeneous\" id=\"ink\"><rgb name=\"sigma_t\" value=\"0.3, 1, 2.5\"/>"
            "<float name=\"albedo\" value=\"0\"/></medium>" +
            vp_sensor("<lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/>", 8, "", "orthographic") +
            "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"1.5, 1.5, 0.5\"/></transform>"
            "<bsdf type=\"null\"/><ref name=\"interior\" id=\"ink\"/></shape>"
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"1.2\"/><translate "
            "value=\"0,0,-2\"/>"
            "</transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"2, 3, "
            "4\"/></emitter></shape></scene>");
        const Color3f expected(L.x * std::exp(-sigma.x), L.y * std::exp(-sigma.y), L.z * std::exp(-sigma.z));
        const bool ptracer = std::string(integrator) == "ptracer";
        expect_constant_image(*scene, 16, ptracer ? 64 : 4, expected, std::string("slab ") + integrator);
    }
}

// Null boundaries are not bounces (Mitsuba's volpath): with max_depth 1 an emitter behind an empty null box
// is still seen, exactly.
TEST(VolPath, NullCrossingsDoNotCountAsBounces) {
    auto scene = load_scene_string(
        "<scene version=\"3.0.0\">" + vp_integrator("volpath", "<integer name=\"max_depth\" value=\"1\"/>") +
        vp_sensor("<lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/>", 4, "", "orthographic") +
        "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"3, 3, 0.5\"/></transform>"
        "<bsdf type=\"null\"/></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"4\"/><translate "
        "value=\"0,0,-2\"/>"
        "</transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"2\"/></emitter></shape></scene>");
    RenderOptions opt;
    opt.spp = 2;
    for (const Color3f& p : render(*scene, opt).pixels)
        EXPECT_NEAR(p.x, 2.f, 1e-5f);
}

// Without media the estimators follow path's sample stream and arithmetic: the same image up to rounding
// (differently ordered float products, ~1e-7 relative).
TEST(VolPath, MatchesPathWithoutMedia) {
    auto make = [](const std::string& integrator) {
        return load_scene_string(
            "<scene version=\"3.0.0\">" + vp_integrator(integrator) +
            vp_sensor("<lookat origin=\"0,2,4\" target=\"0,0,0\" up=\"0,1,0\"/>", 16,
                      "<float name=\"fov\" value=\"45\"/>") +
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><rotate x=\"1\" "
            "angle=\"-90\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7, 0.5, "
            "0.3\"/>"
            "</bsdf></shape>"
            "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.4\"/><translate "
            "value=\"0,0.4,0\"/>"
            "</transform><bsdf type=\"roughplastic\"/></shape>"
            "<shape type=\"sphere\"><point name=\"center\" value=\"0.9,0.4,0.5\"/><float name=\"radius\" "
            "value=\"0.4\"/><bsdf type=\"dielectric\"/></shape>"
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.5\"/><rotate x=\"1\" "
            "angle=\"90\"/><translate value=\"0.5,2,0\"/></transform>"
            "<emitter type=\"area\"><rgb name=\"radiance\" value=\"6\"/></emitter></shape>"
            "<emitter type=\"point\"><point name=\"position\" value=\"-1,1.5,1\"/><rgb name=\"intensity\" "
            "value=\"2\"/></emitter></scene>");
    };
    RenderOptions opt;
    opt.spp = 8;
    opt.seed = 5;
    const Image ref = render(*make("path"), opt);
    for (const char* integrator : {"volpath", "volpathmis"}) {
        const Image im = render(*make(integrator), opt);
        double max_rel = 0;
        for (size_t i = 0; i < ref.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c) {
                const double a = ref.pixels[i][c], b = im.pixels[i][c];
                max_rel = std::max(max_rel, std::abs(a - b) / std::max(std::abs(a), 1e-3));
            }
        EXPECT_LT(max_rel, 1e-4) << integrator;
        std::printf("[ %s vs path ] largest relative pixel difference %.2e\n", integrator, max_rel);
    }
}

TEST(VolPath, ImagesAreIdenticalWhateverTheThreadCount) {
    for (const char* integrator : kVolumetric)
        expect_same_image_whatever_the_thread_count(*medium_furnace(integrator), integrator);
}

// A point light nesting its medium (Mitsuba's `medium` child of emitters) in a haze box: ptracer starts its
// light paths in the declared medium, the same one the walk from the sensor finds without it
// (render/light_medium.h), so the image is the same bit for bit; nesting another medium changes it; a second
// nested medium is a load error.
TEST(VolPath, PointLightNestsItsMedium) {
    auto make = [](const std::string& nested) {
        return load_scene_string(
            "<scene version=\"3.0.0\">" + vp_integrator("ptracer") +
            "<medium type=\"homogeneous\" id=\"haze\"><float name=\"sigma_t\" value=\"0.5\"/></medium>"
            "<medium type=\"homogeneous\" id=\"smoke\"><float name=\"sigma_t\" value=\"3\"/></medium>" +
            vp_sensor("<lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/>", 8) +
            "<shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"haze\"/></shape>"
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><translate "
            "value=\"0,0,-1.5\"/>"
            "</transform></shape><emitter type=\"point\"><point name=\"position\" value=\"0.2,0.3,0\"/>" +
            nested + "</emitter></scene>");
    };
    RenderOptions opt;
    opt.spp = 4;
    const Image walked = render(*make(""), opt), nested = render(*make("<ref id=\"haze\"/>"), opt);
    EXPECT_EQ(walked.pixels, nested.pixels);
    EXPECT_NE(render(*make("<ref id=\"smoke\"/>"), opt).pixels, walked.pixels);
    double sum = 0;
    for (const Color3f& p : walked.pixels)
        sum += p.x;
    EXPECT_GT(sum, 0.0);
    EXPECT_THROW(make("<ref id=\"haze\"/><ref id=\"haze\"/>"), LoadError);
}

// Mitsuba's documentation scene for the homogeneous medium (a bunny of dense, forward-scattering medium
// behind a rough dielectric, sample_emitters off) renders with volpath: a 16x12 crop of the frame's centre at
// 2 spp.
TEST(VolPath, MitsubaHomogeneousSSSDocScene) {
    const std::filesystem::path file = "/work/shared/mitsuba-data/docs/scenes/medium_homogeneous_sss.xml";
    if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is not available";
    auto scene = load_scene(file.string());
    Film& film = *scene->sensor->film;
    film.crop_offset = Vec2i(film.full_size.x / 2 - 8, film.full_size.y / 2 - 6);
    film.width = 16;
    film.height = 12;
    scene->sensor->set_transform(scene->sensor->to_world); // recompute what the sensor derives from its film
    RenderOptions opt;
    opt.spp = 2;
    RenderStats stats;
    const Image im = render(*scene, opt, &stats);
    double sum = 0;
    for (const Color3f& p : im.pixels) {
        ASSERT_TRUE(is_finite(p));
        sum += p.x + p.y + p.z;
    }
    EXPECT_GT(sum, 0.0);
    EXPECT_EQ(stats.dropped_samples, 0u);
}
