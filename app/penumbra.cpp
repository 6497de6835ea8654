// The `penumbra` command line: a thin front over the library (load scene -> render / inspect).
#include "core/exr_layers.h"
#include "render/integrator.h"
#include "render/render.h"
#include "scene/scene.h"

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>

using namespace penumbra;

namespace {

std::map<std::string, std::string> parse_defines(const std::vector<std::string>& defines) {
    std::map<std::string, std::string> result;
    for (const std::string& d : defines) {
        const size_t eq = d.find('=');
        if (eq == std::string::npos || eq == 0) throw Error("-D expects name=value, got '" + d + "'");
        result[d.substr(0, eq)] = d.substr(eq + 1);
    }
    return result;
}

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

// A progress bar on stderr, redrawn at most every 100 ms, only when stderr is a terminal.
class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}
    void update(float fraction) {
        if (!enabled_) return;
        const auto now = std::chrono::steady_clock::now();
        if (fraction < 1.f && now - last_ < std::chrono::milliseconds(100)) return;
        last_ = now;
        const int width = 40, filled = int(fraction * width);
        const double elapsed = std::chrono::duration<double>(now - start_).count();
        std::string bar(size_t(filled), '=');
        bar.resize(width, ' ');
        std::fprintf(stderr, "\r[%s] %5.1f%%  %.1fs", bar.c_str(), 100.0 * fraction, elapsed);
        if (fraction >= 1.f) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

private:
    bool enabled_;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

int cmd_render(const std::string& scene_path, const std::string& output, int spp, uint64_t seed, int threads,
               const std::vector<std::string>& defines, const std::string& integrator, bool quiet) {
    const std::string ext = lower_extension(output);
    if (ext != ".exr" && ext != ".png") throw Error("output '" + output + "': expected a .exr or .png file name");
    auto scene = load_scene(scene_path, parse_defines(defines));
    if (!integrator.empty()) {
        auto obj = make_integrator(Properties(integrator, SourceLocation{"--integrator", 0}), LoadContext{});
        scene->integrator = std::static_pointer_cast<Integrator>(obj);
    }
    RenderOptions options;
    options.spp = spp;
    options.seed = seed;
    options.threads = threads;
    ProgressBar bar(!quiet);
    options.progress = [&](float f) { bar.update(f); };
    RenderStats stats;
    const std::vector<Layer> layers = render_layers(*scene, options, &stats);

    if (ext == ".exr" && layers.size() > 1) {
        std::vector<std::pair<std::string, const Image*>> out;
        for (const Layer& l : layers) out.emplace_back(l.name, &l.image);
        write_exr_layers(output, out);
    } else {
        write_image(output, layers.front().image);
    }
    const Film& film = *scene->sensor->film;
    const int used_spp = spp > 0 ? spp : scene->sensor->sampler->sample_count;
    std::fprintf(stderr, "rendered %dx%d at %d spp in %.2f s (%.2f M samples/s, %.2f M rays/s) -> %s\n", film.width,
                 film.height, used_spp, stats.seconds, stats.samples / stats.seconds * 1e-6,
                 stats.rays / stats.seconds * 1e-6, output.c_str());
    if (stats.dropped_samples > 0)
        std::fprintf(stderr, "warning: %llu samples had non-finite values and were dropped\n",
                     (unsigned long long)stats.dropped_samples);
    return 0;
}

int cmd_info(const std::string& scene_path, const std::vector<std::string>& defines) {
    auto scene = load_scene(scene_path, parse_defines(defines));
    std::printf("scene %s\n", scene_path.c_str());
    const Film& film = *scene->sensor->film;
    std::printf("sensor: %s, film %dx%d, rfilter %s, %d spp\n", scene->sensor->plugin.c_str(), film.width,
                film.height, film.rfilter->plugin.c_str(), scene->sensor->sampler->sample_count);
    if (scene->integrator) std::printf("integrator: %s\n", scene->integrator->plugin.c_str());
    std::printf("shapes: %zu (%zu triangles)\n", scene->shapes.size(), scene->triangle_count());
    for (const auto& s : scene->shapes) {
        std::printf("  %-12s %-16s %8zu triangles  bsdf %-14s%s", s->plugin.c_str(),
                    s->id.empty() ? "-" : s->id.c_str(), s->mesh.face_count(),
                    s->bsdf ? s->bsdf->plugin.c_str() : "-", s->emitter ? "  [area emitter]" : "");
        if (s->degenerate_count()) std::printf("  (%zu degenerate triangles)", s->degenerate_count());
        std::printf("\n");
    }
    std::printf("emitters: %zu\n", scene->emitters.size());
    for (const auto& e : scene->emitters)
        std::printf("  %-12s %s\n", e->plugin.c_str(), e->id.empty() ? "-" : e->id.c_str());
    std::map<std::string, int> materials;
    for (const auto& s : scene->shapes)
        if (s->bsdf) materials[s->bsdf->id.empty() ? "(" + s->bsdf->plugin + ")" : s->bsdf->id]++;
    std::printf("materials: %zu\n", materials.size());
    for (const auto& [name, count] : materials) std::printf("  %-24s used by %d shape(s)\n", name.c_str(), count);
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"penumbra: a physics-based differentiable renderer"};
    app.require_subcommand(1);

    std::string scene_path, output;
    int spp = 0, threads = 0;
    uint64_t seed = 0;
    std::vector<std::string> defines;
    std::string integrator;
    bool quiet = false;
    auto* render = app.add_subcommand("render", "render a Mitsuba 3 XML scene to an image");
    render->add_option("scene", scene_path, "scene file (Mitsuba 3 XML)")->required();
    render->add_option("-o,--output", output, "output image (.exr or .png)")->required();
    render->add_option("--spp", spp, "samples per pixel (default: the scene's sampler)")->check(CLI::PositiveNumber);
    render->add_option("--seed", seed, "random seed");
    render->add_option("--threads", threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    render->add_option("-D", defines, "override a <default> value: name=value");
    render->add_option("--integrator", integrator, "replace the scene's integrator (path, direct, ptracer)");
    render->add_flag("-q,--quiet", quiet, "no progress bar");

    std::string info_path;
    std::vector<std::string> info_defines;
    auto* info = app.add_subcommand("info", "print what a scene contains");
    info->add_option("scene", info_path, "scene file (Mitsuba 3 XML)")->required();
    info->add_option("-D", info_defines, "override a <default> value: name=value");

    CLI11_PARSE(app, argc, argv);
    try {
        if (*render) return cmd_render(scene_path, output, spp, seed, threads, defines, integrator, quiet);
        if (*info) return cmd_info(info_path, info_defines);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "penumbra: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
