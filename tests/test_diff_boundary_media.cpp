// Boundary terms through participating media (paper 001 §5.2, Algorithm 1; §4.3) against central finite
// differences: volumetric shadows (boundary segments ending on the shadow sheet inside a fog, homogeneous or
// heterogeneous, from a point or a directional light), silhouettes seen through the fog (the primary term),
// shadows seen through one more scattering (the indirect term), and a point light moving inside the medium.
// The occluders are black and everything else is static, so that moving an occluder changes the image only
// through visibility: the interior term is zero and the boundary terms alone must match the finite
// differences (run directly, 16 batches each), while the surface-only boundary segments
// (PsdrOptions::volume_boundary = false, the DTRT-like baseline) must visibly miss the shadow sheets. The
// moving light changes the shading too: there psdr's interior + direct terms must match and the interior term
// alone must miss. Tolerances are diff_check.h's, from the batches' standard errors.
#include "core/batch_stats.h"
#include "core/rng.h"
#include "diff/psdr/boundary_segment.h"
#include "diff/psdr/direct_boundary.h"
#include "diff/psdr/indirect_boundary.h"
#include "diff/psdr/primary_boundary.h"
#include "diff/psdr/psdr.h"
#include "diff_check.h"
#include "media_test_util.h"
#include "render/render.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

using namespace penumbra;
using namespace penumbra::test;

namespace {

std::string point_light(const std::string& position) {
    return "<emitter type=\"point\" id=\"bulb\"><point name=\"position\" value=\"" + position +
           "\"/><rgb name=\"intensity\" value=\"30\"/></emitter>";
}

// A floor under a black square occluder and a light (by default a point light in the fog), inside a fog cube
// behind an index-matched (null) boundary; the camera looks in from outside. `occluder_y`: the occluder's
// height (in view, or above it).
const std::string homogeneous_fog =
    "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_t\" value=\"0.35\"/>"
    "<rgb name=\"albedo\" value=\"0.9, 0.8, 0.7\"/><phase type=\"hg\"><float name=\"g\" "
    "value=\"0.3\"/></phase>"
    "</medium>";

std::unique_ptr<Scene> fog_scene(int res, float occluder_y,
                                 const std::string& light = point_light("0.2, 3.2, 0"), int max_depth = 2,
                                 const std::string& medium = homogeneous_fog, const std::string& dir = ".") {
    const std::string xml =
        "<scene version=\"3.0.0\">"
        "<integrator type=\"volpath\"><integer name=\"max_depth\" value=\"" +
        std::to_string(max_depth) + "\"/></integrator>" + medium +
        "<sensor type=\"perspective\" id=\"cam\"><float name=\"fov\" value=\"45\"/><transform "
        "name=\"to_world\">"
        "<lookat origin=\"0, 2.6, 3.4\" target=\"0, 0.6, 0\" up=\"0, 1, 0\"/></transform>"
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
        std::to_string(res) + "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
        "\"/></film></sensor>"
        "<shape type=\"cube\" id=\"box\"><transform name=\"to_world\"><scale value=\"2.5\"/>"
        "<translate value=\"0, 1, 0\"/></transform><bsdf type=\"null\"/><ref name=\"interior\" "
        "id=\"fog\"/></shape>"
        "<shape type=\"rectangle\" id=\"floor\"><transform name=\"to_world\"><scale value=\"2\"/>"
        "<rotate x=\"1\" angle=\"-90\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
        "value=\"0.8, 0.7, 0.6\"/></bsdf></shape>"
        "<shape type=\"rectangle\" id=\"occluder\"><transform name=\"to_world\"><scale value=\"0.35\"/>"
        "<rotate x=\"1\" angle=\"90\"/><rotate y=\"1\" angle=\"25\"/><translate value=\"0, " +
        std::to_string(occluder_y) +
        ", 0\"/></transform><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0\"/></bsdf></shape>" +
        light + "</scene>";
    return load_scene_string(xml, dir);
}

struct Estimate {
    Image mean, stderr_img;
};

// 16 batches of one boundary term (samples_per_pixel per batch), as psdr_derivative runs them.
Estimate batches(const Scene&, const Parameters& params, const BoundaryTerm& term, int spp, bool volume,
                 FirstVertex first_vertex = FirstVertex::Auto, int max_depth = 2) {
    ImageBatches b;
    for (int k = 0; k < 16; ++k) {
        BoundaryOptions o;
        o.samples_per_pixel = spp;
        o.seed = 17 + 0x9E3779B97F4A7C15ULL * uint64_t(k + 1);
        o.path.max_depth = max_depth; // the scene's volpath integrator's

        o.first_vertex = first_vertex;
        o.volume_endpoints = volume;
        b.add(term.derivative(params, o));
    }
    return {b.mean(), b.standard_error()};
}

// The interior term (16 batches): moving the occluder moves the fog around it too (diff/volume_motion.h: a
// shell of the surrounding medium follows the shape), so the interior term is not zero; the boundary terms'
// velocities are relative to that motion.
Estimate interior(const Scene& scene, const Parameters& params, int spp,
                  FirstVertex first_vertex = FirstVertex::Auto) {
    DiffOptions o;
    o.spp = spp;
    o.batches = 16;
    o.seed = 23;
    o.path = path_settings(scene);
    o.first_vertex = first_vertex;
    const DerivativeImage d = render_derivative(scene, params, o);
    return {d.derivative, d.stderr_img};
}

Estimate sum(const Estimate& a, const Estimate& b) {
    Estimate s = a;
    for (size_t i = 0; i < s.mean.pixels.size(); ++i) {
        s.mean.pixels[i] += b.mean.pixels[i];
        const Color3f x = a.stderr_img.pixels[i], y = b.stderr_img.pixels[i];
        s.stderr_img.pixels[i] = Color3f(std::hypot(x.x, y.x), std::hypot(x.y, y.y), std::hypot(x.z, y.z));
    }
    return s;
}

struct Reference {
    FiniteDifference fd;
    Image error;
};

// Central differences (16 batches) with their truncation error estimated from the step 2h (diff_check.h);
// `detection_limit`: where no sample switched, the reference's detection limit as its error (hard shadows).
Reference reference(Scene& scene, Parameters& params, double h, int spp, bool detection_limit = false) {
    RenderOptions ro;
    ro.spp = spp;
    ro.seed = 99;
    Reference r{finite_difference(scene, params, h, ro, 16), {}};
    Image error = r.fd.stderr_img;
    if (detection_limit)
        error =
            with_detection_limit(r.fd, render(scene, ro), h, spp * 16, scene.sensor->film->rfilter->radius());
    r.error = with_truncation_error(error, r.fd, finite_difference(scene, params, 2 * h, ro, 16));
    return r;
}

DiffCheck report(const char* label, const Estimate& e, const Reference& r) {
    const DiffCheck c = check_against(e.mean, e.stderr_img, r.fd.derivative, r.error);
    std::printf("  %s: %s\n", label, describe(c).c_str());
    return c;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

// (1) A volumetric shadow: the occluder hangs above the view, lit by a point light in the fog; translating it
// moves its shadow on the floor (curve endpoints) and the shadow sheet through the fog (medium endpoints).
// The direct term with volume endpoints matches the finite differences; restricted to surface endpoints it
// misses the sheet (the fog's light shafts).
TEST(BoundaryMedia, VolumetricShadowOfATranslatingOccluder) {
    auto scene = fog_scene(16, 2.3f);
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const SceneEdges edges(*scene);
    const DirectBoundary direct(*scene, edges);
    auto start = std::chrono::steady_clock::now();
    const Estimate in = interior(*scene, params, 16);
    const Estimate with_sheets = sum(in, batches(*scene, params, direct, 64, true));
    const double t_direct = seconds_since(start);
    const Estimate surfaces_only = sum(in, batches(*scene, params, direct, 64, false));
    start = std::chrono::steady_clock::now();
    const Reference r = reference(*scene, params, 2e-2, 64);
    std::printf("  direct term %.2f s, finite differences %.2f s\n", t_direct, seconds_since(start));
    const DiffCheck total = report("interior + direct (volume endpoints)", with_sheets, r);
    const DiffCheck surface = report("interior + direct (surface endpoints only)", surfaces_only, r);
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(surface.passes()) << "surface endpoints alone must miss the shadow sheet: "
                                   << describe(surface);
}

// (1') The same in a heterogeneous fog (a density grid): transmittances by ratio tracking, the flights beyond
// the edge by delta tracking.
TEST(BoundaryMedia, VolumetricShadowInAHeterogeneousFog) {
    const TempDir dir;
    write_bytes(dir.str() + "/density.vol",
                vol_bytes({8, 8, 8}, 1, Vec3f(0.f), Vec3f(1.f), [](int x, int y, int z, int) {
                    return 0.1f + 0.08f * float(x) + 0.03f * float((y * z) % 7);
                }));
    auto scene =
        fog_scene(16, 2.3f, point_light("0.2, 3.2, 0"), 2,
                  "<medium type=\"heterogeneous\" id=\"fog\"><volume type=\"gridvolume\" name=\"sigma_t\">"
                  "<string name=\"filename\" value=\"density.vol\"/><transform name=\"to_world\"><scale "
                  "value=\"5\"/><translate x=\"-2.5\" y=\"-1.5\" z=\"-2.5\"/></transform></volume>"
                  "<float name=\"albedo\" value=\"0.9\"/></medium>",
                  dir.str());
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const SceneEdges edges(*scene);
    const DirectBoundary direct(*scene, edges);
    const Reference r = reference(*scene, params, 2e-2, 256);
    const Estimate in = interior(*scene, params, 16);
    const DiffCheck total = report("interior + direct (volume endpoints)",
                                   sum(in, batches(*scene, params, direct, 256, true)), r);
    const DiffCheck surface = report("interior + direct (surface endpoints only)",
                                     sum(in, batches(*scene, params, direct, 64, false)), r);
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(surface.passes()) << "surface endpoints alone must miss the shadow sheet: "
                                   << describe(surface);
}

// (2) The occluder in view, seen through the fog: its silhouette (the primary term: the transmittance to the
// edge, the fog and floor behind it) plus its shadow (direct term); with the image-space first vertex (the
// jump L_occluder − L_beyond) and in material form (−L_beyond, the far side's medium and floor points moving
// relative to the edge). The black occluder and the static rest make the interior term zero in both.
TEST(BoundaryMedia, SilhouetteSeenThroughFog) {
    auto scene = fog_scene(16, 1.0f);
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const SceneEdges edges(*scene);
    const PrimaryBoundary primary(*scene, edges);
    const DirectBoundary direct(*scene, edges);
    const Reference r = reference(*scene, params, 2e-2, 64);
    for (const FirstVertex first_vertex : {FirstVertex::ImageSpace, FirstVertex::Material}) {
        const char* name = first_vertex == FirstVertex::ImageSpace ? "image-space" : "material form";
        const Estimate in = interior(*scene, params, 16, first_vertex);
        const Estimate p = batches(*scene, params, primary, 16, true, first_vertex),
                       d = sum(in, batches(*scene, params, direct, 64, true, first_vertex));
        const DiffCheck total =
            report((std::string(name) + ": interior + primary + direct").c_str(), sum(p, d), r);
        const DiffCheck direct_only = report((std::string(name) + ": interior + direct only").c_str(), d, r);
        EXPECT_TRUE(total.passes()) << name << ": " << describe(total);
        EXPECT_FALSE(direct_only.passes())
            << name << ": the silhouette's jump must matter: " << describe(direct_only);
    }
}

// (4) Multiple scattering (max_depth 3): shadows of the occluder above the view seen through one more bounce
// in the fog or on the floor. The indirect term's emitter technique walks the detector subpath through the
// fog (free flights, phase sampling, camera connections with transmittance); its multi-directional technique
// draws both endpoints by sampleInteraction (surface or medium sources and receivers, Eqs. 40–43) and
// estimates the source subpath volumetrically.
TEST(BoundaryMedia, MultipleScatteringShadows) {
    auto scene = fog_scene(16, 2.3f, point_light("0.2, 3.2, 0"), 3);
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const SceneEdges edges(*scene);
    const DirectBoundary direct(*scene, edges);
    const IndirectBoundary indirect(*scene, edges);
    const Estimate d =
        sum(interior(*scene, params, 16), batches(*scene, params, direct, 64, true, FirstVertex::Auto, 3));
    const auto start = std::chrono::steady_clock::now();
    const Estimate i = batches(*scene, params, indirect, 128, true, FirstVertex::Auto, 3);
    std::printf("  indirect term %.2f s\n", seconds_since(start));
    const Reference r = reference(*scene, params, 2e-2, 128);
    const DiffCheck total = report("interior + direct + indirect", sum(d, i), r);
    const DiffCheck direct_only = report("interior + direct only", d, r);
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(direct_only.passes()) << "multiple scattering must matter: " << describe(direct_only);
}

// (5) A light at infinity (§4.3: a zero-measure emitter whose boundary segments start outside the scene and
// enter the fog through its null boundary): the sun's volumetric shadow. Its shadow on the floor is perfectly
// hard: the reference needs a smaller step (and more samples) than the point light's.
// The fog the camera sees directly is parameterized along its fixed rays (image space): the sheet's velocity
// at such an endpoint is taken relative to that point (seen_medium_point), not to the shell motion X around the
// occluder, which deeper vertices follow.
TEST(BoundaryMedia, VolumetricShadowUnderADirectionalLight) {
    auto scene =
        fog_scene(16, 2.3f,
                  "<emitter type=\"directional\" id=\"sun\"><vector name=\"direction\" value=\"-0.1, -1, "
                  "0.05\"/><rgb name=\"irradiance\" value=\"3\"/></emitter>");
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const SceneEdges edges(*scene);
    const DirectBoundary direct(*scene, edges);
    const Reference r = reference(*scene, params, 1e-2, 512, true);
    const Estimate in = interior(*scene, params, 16);
    const DiffCheck total =
        report("interior + direct (volume endpoints)", sum(in, batches(*scene, params, direct, 64, true)), r);
    const DiffCheck surface = report("interior + direct (surface endpoints only)",
                                     sum(in, batches(*scene, params, direct, 64, false)), r);
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(surface.passes()) << "surface endpoints alone must miss the shadow sheet: "
                                   << describe(surface);
}

// Reverse mode: each boundary term's gradient equals its forward derivative on the same samples through media
// (⟨a, D v⟩ = ⟨Dᵀ a, v⟩), with medium endpoints, volumetric detector subpaths and the primary term's far
// side.
TEST(BoundaryMedia, ReverseModeMatchesForward) {
    auto scene = fog_scene(16, 1.0f, point_light("0.2, 3.2, 0"), 3);
    Parameters params(*scene);
    params.enable({parse_param_selection("occluder.translate=1,0,0")});
    const SceneEdges edges(*scene);
    const PrimaryBoundary primary(*scene, edges);
    const DirectBoundary direct(*scene, edges);
    const IndirectBoundary indirect(*scene, edges);
    Image adjoint(16, 16);
    PCG32 rng(3);
    for (auto& a : adjoint.pixels)
        a = Color3f(rng.next_float(), rng.next_float(), rng.next_float());
    for (const BoundaryTerm* term :
         {static_cast<const BoundaryTerm*>(&primary), static_cast<const BoundaryTerm*>(&direct),
          static_cast<const BoundaryTerm*>(&indirect)}) {
        BoundaryOptions o;
        o.samples_per_pixel = 4;
        o.seed = 5;
        o.path.max_depth = 3;
        const Image forward = term->derivative(params, o);
        std::vector<double> gradient(1, 0.0);
        term->gradient(params, adjoint, o, gradient);
        double lhs = 0, scale = 0;
        for (size_t i = 0; i < adjoint.pixels.size(); ++i) {
            lhs += dot(Vec3d(adjoint.pixels[i]), Vec3d(forward.pixels[i]));
            scale += std::abs(dot(Vec3d(adjoint.pixels[i]), Vec3d(forward.pixels[i])));
        }
        EXPECT_GT(scale, 0.0);
        EXPECT_NEAR(lhs, gradient[0], 1e-4 * scale + 1e-6)
            << "⟨a, Jv⟩ = " << lhs << ", ⟨Jᵀa, v⟩ = " << gradient[0];
    }
}

// (3) A point light translating inside the fog (§4.3: boundary segments that end at a zero-measure emitter in
// a medium): the interior term (the light's falloff and transmittance, in-scattering) plus the direct term
// (the occluder's shadow on the floor and its shadow sheet through the fog, both cast from the moving apex)
// match the finite differences; the interior term alone misses the moving shadows.
TEST(BoundaryMedia, PointLightTranslatingInTheFog) {
    auto scene = fog_scene(16, 2.3f);
    Parameters params(*scene);
    params.enable({parse_param_selection("bulb.translate=1,0,0")});
    PsdrOptions o;
    o.interior.spp = 16;
    o.interior.batches = 16;
    o.interior.seed = 11;
    o.interior.path.max_depth = 2;
    o.primary_spp = o.indirect_spp = o.pixel_spp = 0;
    o.direct_spp = 64;
    const auto start = std::chrono::steady_clock::now();
    const DerivativeImage d = psdr_derivative(*scene, params, o);
    std::printf("  psdr (interior 16 spp + direct 64 spp, 16 batches) %.2f s\n", seconds_since(start));
    const Reference r = reference(*scene, params, 2e-2, 64);
    const DiffCheck total = report("interior + direct", {d.derivative, d.stderr_img}, r);
    const DiffCheck interior =
        report("interior only", {d.term("interior").derivative, d.term("interior").stderr_img}, r);
    EXPECT_TRUE(total.passes()) << describe(total);
    EXPECT_FALSE(interior.passes()) << "the interior term alone must miss the moving shadows: "
                                    << describe(interior);
}
