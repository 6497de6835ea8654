// Participating media and bidirectional path tracing (issue 12), measured in one run:
//  - time per camera sample of `volpath`, `volpathmis` and `bdpt` relative to `path` on the same room without
//    media, and of the same integrators with the room filled with haze;
//  - variance x time of `bdpt` relative to `path` on a caustic scene (a glass sphere focusing a small area
//  light
//    onto a diffuse floor) and on a room lit through a small opening: the mean per-pixel variance over
//    independent renders times the seconds per render, at equal samples per pixel (a ratio below 1 means bdpt
//    reaches a given noise level sooner).
//
// Usage: build/penumbra_bench_media [--runs N] [--spp N] [--res N]   (defaults 16, 32, 96)
#include "render/render.h"
#include "scene/scene.h"

#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

using namespace penumbra;

namespace {

// The scene's opening: `integrator` (max_depth 8) and a perspective camera of `res` x `res` pixels.
std::string scene_head(const std::string& integrator, float fov, const std::string& lookat, int res,
                       const std::string& sensor_medium = "") {
    return R"(<scene version="3.0.0"><integrator type=")" + integrator +
           R"("><integer name="max_depth" value="8"/></integrator><sensor type="perspective"><float name="fov" value=")" +
           std::to_string(fov) + R"("/><transform name="to_world">)" + lookat + "</transform>" +
           sensor_medium + R"(<film type="hdrfilm"><integer name="width" value=")" + std::to_string(res) +
           R"("/><integer name="height" value=")" + std::to_string(res) + R"("/></film></sensor>)";
}

// A closed diffuse room with a box and a sphere, lit by a ceiling panel; `haze` fills it with a medium.
std::string room_scene(const std::string& integrator, bool haze, int res) {
    const std::string medium_ref = haze ? R"(<ref name="interior" id="haze"/>)" : "";
    const std::string exterior_ref = haze ? R"(<ref name="exterior" id="haze"/>)" : "";
    return scene_head(integrator, 60.f, R"(<lookat origin="0, 0, 1.8" target="0, -0.2, 0" up="0, 1, 0"/>)",
                      res, haze ? R"(<ref name="medium" id="haze"/>)" : "") +
           R"(
  <medium type="homogeneous" id="haze"><float name="sigma_t" value="0.3"/><rgb name="albedo" value="0.8"/>
    <phase type="hg"><float name="g" value="0.4"/></phase></medium>
  <shape type="cube"><transform name="to_world"><scale value="2"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></bsdf>)" +
           medium_ref + R"(</shape>
  <shape type="cube"><transform name="to_world"><scale value="0.4"/><translate value="-0.6, -1.6, -0.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.2, 0.1"/></bsdf>)" +
           exterior_ref + R"(</shape>
  <shape type="sphere"><point name="center" value="0.6, -1.5, 0"/><float name="radius" value="0.5"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf>)" +
           exterior_ref + R"(</shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/>
    <translate value="0, 1.99, 0"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="10"/></emitter>)" +
           exterior_ref + medium_ref + R"(</shape>
</scene>)";
}

// A glass sphere over a diffuse floor under a small, bright, downward-facing area light, seen from above: the
// caustic under the sphere is found by a unidirectional tracer only when BSDF sampling through the glass hits
// the small light, and by bdpt through light tracing and connections of light subpaths.
std::string caustic_scene(const std::string& integrator, int res) {
    return scene_head(integrator, 35.f, R"(<lookat origin="0, 2.2, -2.2" target="0, 0.2, 0" up="0, 1, 0"/>)",
                      res) +
           R"(
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>
  <shape type="sphere"><point name="center" value="0, 0.6, 0"/><float name="radius" value="0.4"/>
    <bsdf type="dielectric"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.05"/><rotate x="1" angle="90"/>
    <translate value="0, 2, 0"/></transform><emitter type="area"><rgb name="radiance" value="400"/></emitter></shape>
</scene>)";
}

// A closed diffuse room lit only through a small opening in its right wall, by an area light outside that
// faces away from the room toward a diffuse reflector (Veach's "door ajar"): next-event estimation from
// inside never reaches the light, a camera path must leave through the opening and hit the reflector first,
// while light subpaths reflected through the opening connect to every camera vertex.
std::string opening_scene(const std::string& integrator, int res) {
    auto wall = [](const std::string& transform) {
        return R"(<shape type="rectangle"><transform name="to_world">)" + transform +
               R"(</transform><bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf></shape>)";
    };
    // The right wall (x = 1) as four panels around a 0.3 x 0.3 opening at its centre.
    auto panel = [&](float y, float z, float sy, float sz) {
        return wall(R"(<scale x=")" + std::to_string(sz) + R"(" y=")" + std::to_string(sy) +
                    R"("/><rotate y="1" angle="-90"/><translate x="1" y=")" + std::to_string(y) + R"(" z=")" +
                    std::to_string(z) + R"("/>)");
    };
    return scene_head(integrator, 70.f, R"(<lookat origin="0, 0, 0.9" target="0, 0, -1" up="0, 1, 0"/>)",
                      res) +
           wall(R"(<rotate x="1" angle="-90"/><translate y="-1"/>)") +
           wall(R"(<rotate x="1" angle="90"/><translate y="1"/>)") + wall(R"(<translate z="-1"/>)") +
           wall(R"(<rotate y="1" angle="180"/><translate z="1"/>)") +
           wall(R"(<rotate y="1" angle="90"/><translate x="-1"/>)") + panel(0.575f, 0.f, 0.425f, 1.f) +
           panel(-0.575f, 0.f, 0.425f, 1.f) + panel(0.f, 0.575f, 0.15f, 0.425f) +
           panel(0.f, -0.575f, 0.15f, 0.425f) +
           wall(R"(<scale value="1.5"/><rotate y="1" angle="-90"/><translate x="2"/>)") + R"(
  <shape type="rectangle"><transform name="to_world"><scale value="0.3"/><rotate y="1" angle="90"/>
    <translate x="1.4"/></transform><emitter type="area"><rgb name="radiance" value="100"/></emitter></shape>
</scene>)";
}

struct Timing {
    double seconds_per_sample = 0;
    Image image;
};

Timing time_render(const std::string& xml, int spp, uint64_t seed) {
    const auto scene = load_scene_string(xml);
    RenderOptions options;
    options.spp = spp;
    options.seed = seed;
    RenderStats stats;
    const auto start = std::chrono::steady_clock::now();
    Image image = render(*scene, options, &stats);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Film& film = *scene->sensor->film;
    return {seconds / (double(film.width) * film.height * spp), std::move(image)};
}

// Mean over pixels and channels of the sample variance across `runs` independent renders, and the mean time
// of one render.
std::pair<double, double> variance_and_time(const std::string& xml, int spp, int runs) {
    std::vector<Image> images;
    double seconds = 0;
    for (int r = 0; r < runs; ++r) {
        const auto start = std::chrono::steady_clock::now();
        images.push_back(time_render(xml, spp, 1000 + r).image);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    double variance = 0;
    const size_t n = images[0].pixels.size();
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            double mean = 0, sq = 0;
            for (const Image& im : images)
                mean += im.pixels[i][c];
            mean /= runs;
            for (const Image& im : images)
                sq += (im.pixels[i][c] - mean) * (im.pixels[i][c] - mean);
            variance += sq / (runs - 1);
        }
    return {variance / (3.0 * n), seconds / runs};
}

} // namespace

int main(int argc, char** argv) {
    int runs = 16, spp = 32, res = 96;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--runs"))
            runs = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--spp"))
            spp = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--res"))
            res = std::atoi(argv[i + 1]);
    }
    try {
        std::printf("%d threads, %dx%d, %d spp\n", tbb::this_task_arena::max_concurrency(), res, res, spp);
        const double path = time_render(room_scene("path", false, res), spp, 1).seconds_per_sample;
        std::printf("room without media: path %.3f us/sample\n", path * 1e6);
        for (const char* integrator : {"volpath", "volpathmis", "bdpt"})
            std::printf("  %-10s / path, time per sample: without media %.2f, with haze %.2f\n", integrator,
                        time_render(room_scene(integrator, false, res), spp, 1).seconds_per_sample / path,
                        time_render(room_scene(integrator, true, res), spp, 1).seconds_per_sample / path);
        using SceneMaker = std::string (*)(const std::string&, int);
        const std::pair<const char*, SceneMaker> efficiency_scenes[] = {{"caustic", caustic_scene},
                                                                        {"small opening", opening_scene}};
        for (const auto& [name, make] : efficiency_scenes) {
            const auto [var_path, t_path] = variance_and_time(make("path", res), spp, runs);
            const auto [var_bdpt, t_bdpt] = variance_and_time(make("bdpt", res), spp, runs);
            std::printf("%s scene, %d runs: path variance %.4g in %.2f s, bdpt variance %.4g in %.2f s\n",
                        name, runs, var_path, t_path, var_bdpt, t_bdpt);
            std::printf("  bdpt variance x time / path variance x time = %.3f\n",
                        var_bdpt * t_bdpt / (var_path * t_path));
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
