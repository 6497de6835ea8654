// Integrators against analytic answers and against each other. Tolerances are multiples of standard errors
// estimated from 16 independent renders (tests/render_stats.h): with 15 degrees of freedom P(|t| > 4) ~ 1e-3,
// so a per-pixel outlier fraction above 2% or an image-mean |z| > 4 means bias, not bad luck.
#include "render_stats.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string sensor_xml(const std::string& type, const std::string& transform, int res, const std::string& extra = "") {
    return "<sensor type=\"" + type + "\">" + extra + "<transform name=\"to_world\">" + transform +
           "</transform><sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(res) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
           "\"/><rfilter type=\"box\"/></film></sensor>";
}

// A closed box seen from inside, every point emitting Le and reflecting diffusely with albedo rho:
// L = Le / (1 - rho) everywhere (all bounces), Le (1 + rho) with direct lighting only.
std::unique_ptr<Scene> furnace(const std::string& integrator, int max_depth) {
    return load_scene_string(
        "<scene version=\"3.0.0\"><integrator type=\"" + integrator + "\"><integer name=\"max_depth\" value=\"" +
        std::to_string(max_depth) + "\"/></integrator>" +
        sensor_xml("perspective", "<lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/>", 12,
                   "<float name=\"fov\" value=\"70\"/>") +
        "<shape type=\"cube\"><boolean name=\"flip_normals\" value=\"true\"/>"
        "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"0.5\"/></emitter></shape></scene>");
}

void expect_image_mean(const BatchStats& s, double expected, const char* what) {
    const double z = (s.image_mean - expected) / s.image_mean_stderr;
    EXPECT_LT(std::abs(z), 4.0) << what << ": image mean " << s.image_mean << " expected " << expected
                                << " (stderr " << s.image_mean_stderr << ")";
}

// Fraction of pixel channels whose |z| exceeds 4 against a reference image (expected ~6e-5 if unbiased).
double outlier_fraction(const BatchStats& s, const Image& ref, double abs_tol = 0.0) {
    int bad = 0, n = 0;
    for (size_t i = 0; i < ref.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(double(s.mean.pixels[i][c]) - ref.pixels[i][c]);
            const double se = s.stderr_img.pixels[i][c];
            if (d > 4.0 * se + abs_tol) ++bad;
            ++n;
        }
    return double(bad) / n;
}

} // namespace

TEST(Integrators, PathFurnaceConvergesToGeometricSeries) {
    auto scene = furnace("path", -1);
    const BatchStats s = render_batches(*scene, 16, 64);
    expect_image_mean(s, 1.0, "path, closed furnace");
    EXPECT_LT(outlier_fraction(s, Image(12, 12, Color3f(1.f))), 0.02);
}

TEST(Integrators, PtracerFurnaceConvergesToGeometricSeries) {
    auto scene = furnace("ptracer", -1);
    const BatchStats s = render_batches(*scene, 16, 8);
    expect_image_mean(s, 1.0, "ptracer, closed furnace");
}

TEST(Integrators, DirectOnlyFurnace) {
    for (const char* integrator : {"path", "ptracer"}) {
        auto scene = furnace(integrator, 2);
        expect_image_mean(render_batches(*scene, 16, 4), 0.75, integrator);
    }
    auto scene = load_scene_string(
        "<scene version=\"3.0.0\"><integrator type=\"direct\"/>" +
        sensor_xml("perspective", "<lookat origin=\"0,0,0\" target=\"0,0,1\" up=\"0,1,0\"/>", 12) +
        "<shape type=\"cube\"><boolean name=\"flip_normals\" value=\"true\"/><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"0.5\"/></emitter></shape></scene>");
    expect_image_mean(render_batches(*scene, 16, 4), 0.75, "direct");
}

TEST(Integrators, MaxDepthOneShowsOnlyEmitters) {
    auto scene = furnace("path", 1);
    RenderOptions opt;
    opt.spp = 2;
    const Image im = render(*scene, opt);
    for (const auto& p : im.pixels) EXPECT_NEAR(p.x, 0.5f, 1e-5f);
}

// Point light of intensity I at height h above a diffuse plane (albedo rho), orthographic view from above:
// L(x) = rho/pi * I * h / d^3 with d the distance to the light. Pixels average L over their footprint (box filter).
class PointLightPlane : public ::testing::TestWithParam<const char*> {};

TEST_P(PointLightPlane, MatchesAnalyticRadiance) {
    const float I = 5.f, h = 1.f, rho = 0.6f, half = 1.5f;
    const int res = 16;
    auto scene = load_scene_string(
        std::string("<scene version=\"3.0.0\"><integrator type=\"") + GetParam() + "\"/>" +
        sensor_xml("orthographic",
                   "<scale value=\"1.5\"/><lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/>", res) +
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/></transform>"
        "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.6\"/></bsdf></shape>"
        "<emitter type=\"point\"><point name=\"position\" value=\"0,0,1\"/><rgb name=\"intensity\" value=\"5\"/>"
        "</emitter></scene>");
    Image ref(res, res);
    const int q = 8; // midpoint quadrature per pixel; the radial symmetry makes the axis orientation irrelevant
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            double sum = 0;
            for (int j = 0; j < q; ++j)
                for (int i = 0; i < q; ++i) {
                    const double wx = ((x + (i + 0.5) / q) / res * 2 - 1) * half;
                    const double wy = ((y + (j + 0.5) / q) / res * 2 - 1) * half;
                    const double d = std::sqrt(wx * wx + wy * wy + h * h);
                    sum += rho / M_PI * I * h / (d * d * d);
                }
            ref.at(x, y) = Color3f(float(sum / (q * q)));
        }
    const bool ptracer = std::string(GetParam()) == "ptracer";
    const BatchStats s = render_batches(*scene, 16, ptracer ? 24 : 8);
    double ref_mean = 0;
    for (const auto& p : ref.pixels) ref_mean += p.x;
    ref_mean /= ref.pixels.size();
    expect_image_mean(s, ref_mean, GetParam());
    // 8x8 midpoint quadrature of this smooth profile is accurate to ~1e-3 relative: allow that on top of 4 sigma.
    EXPECT_LT(outlier_fraction(s, ref, 2e-3 * ref_mean), 0.02);
}

INSTANTIATE_TEST_SUITE_P(Integrators, PointLightPlane, ::testing::Values("path", "direct", "ptracer"));

// The camera looks straight down through the light, whose black back side hides |x|,|y| < a (the light's edges
// fall on pixel boundaries, so no pixel is partly hidden).
// Form factor from a differential area at the origin (normal +z) to the parallel rectangle
// [x1,x2]x[y1,y2] at height h (corner formula, combined with signs).
static double form_factor_rect(double x1, double x2, double y1, double y2, double h) {
    auto f = [](double a, double b) {
        const double sa = std::sqrt(1 + a * a), sb = std::sqrt(1 + b * b);
        return (a / sa * std::atan(b / sa) + b / sb * std::atan(a / sb)) / (2 * M_PI);
    };
    return f(x2 / h, y2 / h) - f(x1 / h, y2 / h) - f(x2 / h, y1 / h) + f(x1 / h, y1 / h);
}

TEST(Integrators, SmallAreaLightOnPlaneMatchesFormFactor) {
    const double a = 0.25, h = 1.0, Le = 4.0, rho = 0.5, half = 1.5;
    const int res = 12;
    for (const char* integrator : {"path", "direct"}) {
        auto scene = load_scene_string(
            std::string("<scene version=\"3.0.0\"><integrator type=\"") + integrator + "\"/>" +
            sensor_xml("orthographic",
                       "<scale value=\"1.5\"/><lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/>", res) +
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/></transform>"
            "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf></shape>"
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.25\"/>"
            "<rotate x=\"1\" angle=\"180\"/><translate value=\"0,0,1\"/></transform>"
            "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf>"
            "<emitter type=\"area\"><rgb name=\"radiance\" value=\"4\"/></emitter></shape></scene>");
        Image ref(res, res);
        const int q = 8;
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                double sum = 0;
                for (int j = 0; j < q; ++j)
                    for (int i = 0; i < q; ++i) {
                        const double px = ((x + (i + 0.5) / q) / res * 2 - 1) * half;
                        const double py = ((y + (j + 0.5) / q) / res * 2 - 1) * half;
                        if (std::abs(px) < a && std::abs(py) < a) continue;
                        sum += rho * Le * form_factor_rect(-a - px, a - px, -a - py, a - py, h);
                    }
                ref.at(x, y) = Color3f(float(sum / (q * q)));
            }
        const BatchStats s = render_batches(*scene, 16, 8);
        double ref_mean = 0;
        for (const auto& p : ref.pixels) ref_mean += p.x;
        expect_image_mean(s, ref_mean / ref.pixels.size(), integrator);
        EXPECT_LT(outlier_fraction(s, ref, 2e-3 * ref_mean / ref.pixels.size()), 0.02) << integrator;
    }
}

// path (max_depth 2), direct and ptracer (max_depth 2) estimate the same direct-illumination image.
TEST(Integrators, PathDirectAndPtracerAgreeOnDirectLighting) {
    auto make = [](const std::string& integrator) {
        return load_scene_string(
            "<scene version=\"3.0.0\"><integrator type=\"" + integrator + "\">" +
            (integrator == "direct" ? "" : "<integer name=\"max_depth\" value=\"2\"/>") + "</integrator>" +
            sensor_xml("perspective", "<lookat origin=\"0,2,4\" target=\"0,0,0\" up=\"0,1,0\"/>", 16,
                       "<float name=\"fov\" value=\"45\"/>") +
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><rotate x=\"1\" "
            "angle=\"-90\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.7, 0.5, 0.3\"/>"
            "</bsdf></shape>"
            "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.4\"/><translate value=\"0,0.4,0\"/>"
            "</transform><bsdf type=\"roughplastic\"/></shape>"
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.5\"/><rotate x=\"1\" "
            "angle=\"90\"/><translate value=\"0.5,2,0\"/></transform>"
            "<emitter type=\"area\"><rgb name=\"radiance\" value=\"6\"/></emitter></shape></scene>");
    };
    auto path = make("path");
    const BatchStats sp = render_batches(*path, 16, 8);
    for (const char* other : {"direct", "ptracer"}) {
        auto scene = make(other);
        const BatchStats so = render_batches(*scene, 16, std::string(other) == "ptracer" ? 16 : 8, 1000);
        const double se = std::hypot(sp.image_mean_stderr, so.image_mean_stderr);
        EXPECT_LT(std::abs(sp.image_mean - so.image_mean) / se, 4.0)
            << other << " mean " << so.image_mean << " vs path " << sp.image_mean;
        int bad = 0, n = 0;
        for (size_t i = 0; i < sp.mean.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c, ++n) {
                const double d = std::abs(sp.mean.pixels[i][c] - so.mean.pixels[i][c]);
                if (d > 4.0 * std::hypot(sp.stderr_img.pixels[i][c], so.stderr_img.pixels[i][c]) + 1e-6) ++bad;
            }
        EXPECT_LT(double(bad) / n, 0.02) << other;
    }
}

TEST(Integrators, ImagesAreIdenticalWhateverTheThreadCount) {
    for (const char* integrator : {"path", "ptracer"})
        expect_same_image_whatever_the_thread_count(*furnace(integrator, -1), integrator);
}
