// Crop windows of hdrfilm (crop_offset_x/y, crop_width/height): the image is the crop and shows the region of
// the full frame at the offset, for the sensors' ray geometry, the renderer, the light tracer and the
// derivative terms.
#include "core/rng.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "render_stats.h"
#include "scene/factory.h"

#include <gtest/gtest.h>

using namespace penumbra;
using namespace penumbra::test;

namespace {

constexpr int FullW = 32, FullH = 24, CropX = 5, CropY = 9, CropW = 14, CropH = 12;

// sample_border: the crop's edge pixels integrate the band beyond the crop that their filter reaches, as the
// full frame's pixels there do (without it each image cuts its filters at its own edges, so the crop's edge
// pixels would differ from the full render's by design).
std::string crop_film(bool crop, const std::string& filter = "gaussian") {
    std::string s = R"(<film type="hdrfilm"><integer name="width" value=")" + std::to_string(FullW) +
                    R"("/><integer name="height" value=")" + std::to_string(FullH) +
                    R"("/><boolean name="sample_border" value="true"/>)";
    if (crop)
        s += R"(<integer name="crop_offset_x" value=")" + std::to_string(CropX) +
             R"("/><integer name="crop_offset_y" value=")" + std::to_string(CropY) +
             R"("/><integer name="crop_width" value=")" + std::to_string(CropW) +
             R"("/><integer name="crop_height" value=")" + std::to_string(CropH) + R"("/>)";
    return s + R"(<rfilter type=")" + filter + R"("/></film>)";
}

// A lit cube in front of a wall, seen by `sensor` (its parameters) through a film with or without the crop.
std::string scene_xml(const std::string& sensor, bool crop, const std::string& integrator = "path",
                      const std::string& filter = "gaussian") {
    return R"(<scene version="3.0.0">
      <integrator type=")" +
           integrator + R"("><integer name="max_depth" value="3"/></integrator>
      <sensor type=)" +
           sensor +
           R"(<transform name="to_world"><lookat origin="0.3,0.2,4" target="0,0,0" up="0,1,0"/></transform>)" +
           crop_film(crop, filter) + R"(</sensor>
      <shape type="rectangle" id="wall"><transform name="to_world"><scale value="4"/><translate value="0,0,-1"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7,0.6,0.5"/></bsdf></shape>
      <shape type="cube" id="box"><transform name="to_world"><scale value="0.35"/><rotate y="1" angle="30"/>
        <rotate x="1" angle="20"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0.3,0.4,0.8"/></bsdf></shape>
      <shape type="sphere"><point name="center" value="-1,2,2"/><float name="radius" value="0.5"/>
        <emitter type="area"><rgb name="radiance" value="6"/></emitter></shape>
    </scene>)";
}

const char* Perspective = R"("perspective" id="cam"><float name="fov" value="35"/>)";

Image region(const Image& full) {
    Image out(CropW, CropH);
    for (int y = 0; y < CropH; ++y)
        for (int x = 0; x < CropW; ++x)
            out.at(x, y) = full.at(x + CropX, y + CropY);
    return out;
}

// Cropped and full renders are independent estimates of the same pixels: the batch standard errors of both.
void expect_same_region(const BatchStats& crop, const BatchStats& full, const char* what) {
    const DiffCheck c = check_against(crop.mean, crop.stderr_img, region(full.mean), region(full.stderr_img));
    std::printf("  %s: %s\n", what, describe(c).c_str());
    EXPECT_TRUE(c.passes()) << what << ": " << describe(c);
}

} // namespace

TEST(CamCrop, FilmParsesTheCropWindow) {
    auto scene = load_scene_string(scene_xml(Perspective, true));
    const Film& film = *scene->sensor->film;
    EXPECT_EQ(film.width, CropW);
    EXPECT_EQ(film.height, CropH);
    EXPECT_EQ(film.full_size.x, FullW);
    EXPECT_EQ(film.crop_offset.y, CropY);
    // The window must lie inside the frame; the error names the parameter's line.
    const std::string bad = R"(<scene version="3.0.0"><sensor type="perspective">
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/>
        <integer name="crop_offset_y" value="20"/>
        <integer name="crop_height" value="8"/></film></sensor></scene>)";
    try {
        load_scene_string(bad);
        FAIL() << "a crop window beyond the frame was accepted";
    } catch (const LoadError& e) {
        EXPECT_NE(std::string(e.what()).find(":4"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("crop_height"), std::string::npos) << e.what();
    }
}

// Exact: the cropped sensor's ray through film position s is the full sensor's ray through s + crop_offset
// (same lens sample), and projections differ by the offset; the light tracer's importance is scaled by the
// ratio of frame to crop pixels (it integrates to 1 over the image).
TEST(CamCrop, SensorsMapTheCropIntoTheFrame) {
    for (const char* sensor :
         {Perspective, R"("orthographic">)",
          R"("thinlens"><float name="fov" value="35"/><float name="aperture_radius" value="0.1"/>
                                  <float name="focus_distance" value="3.5"/>)"}) {
        auto full = load_scene_string(scene_xml(sensor, false)),
             crop = load_scene_string(scene_xml(sensor, true));
        const Sensor &f = *full->sensor, &c = *crop->sensor;
        for (const Vec2f s : {Vec2f(0.5f, 0.5f), Vec2f(3.3f, 7.9f), Vec2f(13.5f, 11.5f)}) {
            const Vec2f u(0.3f, 0.8f);
            const Ray a = c.sample_ray(s, u).first,
                      b = f.sample_ray(s + Vec2f(float(CropX), float(CropY)), u).first;
            EXPECT_NEAR(norm(a.o - b.o), 0.f, 1e-6f) << sensor;
            EXPECT_NEAR(norm(a.d - b.d), 0.f, 1e-6f) << sensor;
            Vec2f pc, pf;
            const Vec3f p = a(3.7f);
            ASSERT_TRUE(c.project(p, pc)) << sensor;
            ASSERT_TRUE(f.project(p, pf)) << sensor;
            EXPECT_NEAR(pc.x + CropX, pf.x, 1e-3f) << sensor; // float roundoff of a projection at ~4 units
            EXPECT_NEAR(pc.y + CropY, pf.y, 1e-3f) << sensor;
            Interaction3f ref;
            ref.p = p;
            const auto [dc, wc] = c.sample_direction(ref, u);
            const auto [df, wf] = f.sample_direction(ref, u);
            EXPECT_NEAR(wc.x / wf.x, float(FullW * FullH) / (CropW * CropH), 1e-4f) << sensor;
            EXPECT_NEAR(dc.uv.x + CropX, df.uv.x, 1e-3f) << sensor;
        }
        // A point imaged outside the window is off the cropped film.
        Vec2f pos;
        const Ray outside = f.sample_ray(Vec2f(1.f, 1.f), Vec2f(0.5f)).first;
        EXPECT_FALSE(c.project(outside(3.f), pos)) << sensor;
    }
}

// The renderer: a cropped render equals the region of the full render (16 batches of 16 spp each).
TEST(CamCrop, PathRenderIsTheRegionOfTheFullRender) {
    auto full = load_scene_string(scene_xml(Perspective, false)),
         crop = load_scene_string(scene_xml(Perspective, true));
    expect_same_region(render_batches(*crop, 16, 16, 3), render_batches(*full, 16, 16, 5), "path");
}

// The light tracer splats through sample_direction, whose importance is normalized over the image. With the
// same seed and the same number of light paths (FullW·FullH·7 = CropW·CropH·32), the cropped render traces
// exactly the full render's paths, so it equals the full render's region up to float roundoff (weights scaled
// by the pixel-count ratio one way, the image by its inverse the other); the filter tails that reach the
// region's border pixels from outside the window are kept.
TEST(CamCrop, ParticleTracerRenderIsTheRegionOfTheFullRender) {
    static_assert(FullW * FullH * 7 == CropW * CropH * 32, "the same number of light paths");
    auto full = load_scene_string(scene_xml(Perspective, false, "ptracer"));
    auto crop = load_scene_string(scene_xml(Perspective, true, "ptracer"));
    RenderOptions o;
    o.seed = 11;
    o.spp = 7;
    const Image a = region(render(*full, o));
    o.spp = 32;
    const Image b = render(*crop, o);
    double sum = 0, diff = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            sum += std::abs(a.pixels[i][k]);
            diff += std::abs(a.pixels[i][k] - b.pixels[i][k]);
        }
    std::printf("  ptracer: crop vs region of the full render, relative L1 difference %.3g\n", diff / sum);
    EXPECT_GT(sum, 0.0);
    EXPECT_LT(diff / sum, 1e-5); // float roundoff of the differently scaled weights
}

// Every derivative term on a cropped film: a translating cube with a box filter and the material-form first
// vertex exercises the interior term (filter gradient), the primary boundary term (silhouettes crossing the
// window) and the pixel-boundary term; the cropped derivative must equal the region of the full film's.
TEST(CamCrop, DerivativeIsTheRegionOfTheFullDerivative) {
    DerivativeImage d[2];
    for (int k = 0; k < 2; ++k) {
        auto scene = load_scene_string(scene_xml(Perspective, k == 1, "path", "box"));
        Parameters params(*scene);
        params.enable({parse_param_selection("box.translate=1,0.5,0")});
        PsdrOptions o;
        o.interior.spp = 8;
        o.interior.batches = 16;
        o.interior.seed = 21 + 100 * k;
        o.interior.path = path_settings(*scene);
        o.interior.first_vertex = FirstVertex::Material;
        o.primary_spp = 8;
        o.direct_spp = 8;
        o.indirect_spp = 0;
        o.pixel_spp = 8;
        d[k] = psdr_derivative(*scene, params, o);
    }
    double primary = 0, pixel = 0;
    const Image &primary_term = d[1].term("primary").derivative, &pixel_term = d[1].term("pixel").derivative;
    for (size_t i = 0; i < primary_term.pixels.size(); ++i) {
        primary += std::abs(primary_term.pixels[i].x);
        pixel += std::abs(pixel_term.pixels[i].x);
    }
    EXPECT_GT(primary, 0.0) << "the window must contain a silhouette";
    EXPECT_GT(pixel, 0.0) << "the pixel-boundary term must contribute";
    const DiffCheck c =
        check_against(d[1].derivative, d[1].stderr_img, region(d[0].derivative), region(d[0].stderr_img));
    std::printf("  cropped vs full derivative: %s\n", describe(c).c_str());
    EXPECT_TRUE(c.passes()) << describe(c);
    EXPECT_GT(std::abs(c.comparison.mean_ref), 1e-3) << "a weak test: the reference derivative is ~0";
}

// Reverse mode on a cropped film: the adjoint has the crop's size, and ⟨a, Jv⟩ (forward, every term) equals
// ⟨Jᵀa, v⟩ on the same samples (psdr_gradient uses the seeds of psdr_derivative's single batch).
TEST(CamCrop, ReverseModeMatchesForwardMode) {
    auto scene = load_scene_string(scene_xml(Perspective, true, "path", "box"));
    Parameters params(*scene);
    params.enable({parse_param_selection("box.translate=1,0.5,0")});
    PsdrOptions o;
    o.interior.spp = 4;
    o.interior.seed = 5;
    o.interior.path = path_settings(*scene);
    o.interior.first_vertex = FirstVertex::Material;
    o.primary_spp = o.direct_spp = o.pixel_spp = 4;
    o.indirect_spp = 0;
    const DerivativeImage forward = psdr_derivative(*scene, params, o);
    Image adjoint(CropW, CropH);
    PCG32 rng(3);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    const Gradient reverse = psdr_gradient(*scene, params, adjoint, o);
    double lhs = 0, scale = 0;
    for (size_t i = 0; i < adjoint.pixels.size(); ++i) {
        const Vec3d a(adjoint.pixels[i]);
        lhs += dot(a, Vec3d(forward.derivative.pixels[i]));
        scale += std::abs(dot(a, Vec3d(forward.derivative.pixels[i])));
    }
    EXPECT_GT(scale, 0.0);
    // Float roundoff of sums accumulated in different orders.
    EXPECT_NEAR(lhs, reverse.values[0], 1e-4 * scale + 1e-6)
        << "⟨a, Jv⟩ = " << lhs << ", ⟨Jᵀa, v⟩ = " << reverse.values[0];
    std::printf("  cropped film: <a, Jv> = %.6g, <J^T a, v> = %.6g (scale %.3g)\n", lhs, reverse.values[0],
                scale);
}
