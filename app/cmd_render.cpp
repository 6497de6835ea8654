// `penumbra render` and `penumbra info`.
#include "cli.h"

#include "render/film_output.h"
#include "render/integrator.h"
#include "render/light_medium.h"
#include "render/render.h"
#include "scene/factory.h"
#include "scene/medium.h"
#include "scene/scene.h"

#include <cstdio>

namespace penumbra::cli {

namespace {

int cmd_render(const std::string& scene_path, const std::string& output, int spp, uint64_t seed, int threads,
               const std::vector<std::string>& defines, const std::string& integrator,
               const std::string& sensor, bool quiet) {
    const std::string ext = lower_extension(output);
    if (ext != ".exr" && ext != ".png") throw Error("output '" + output + "': expected a .exr or .png file name");
    auto scene = load_scene(scene_path, parse_defines(defines));
    scene->select_sensor(sensor);
    if (!integrator.empty()) {
        auto obj =
            make_integrator_settings(Properties(integrator, SourceLocation{"--integrator", 0}), LoadContext{});
        obj->plugin = integrator;
        scene->integrator = std::static_pointer_cast<const IntegratorSettings>(obj);
    }
    // As in Mitsuba, surface integrators render a scene with media as if it had none: say so.
    const std::string& used = scene->integrator->plugin;
    if (scene_has_media(*scene) && used != "volpath" && used != "volpathmis" && used != "bdpt" && used != "ptracer" &&
        used != "sppm" && used != "moment")
        std::fprintf(stderr,
                     "warning: integrator '%s' ignores the scene's participating media (volpath, volpathmis, "
                     "bdpt and sppm render them)\n",
                     used.c_str());
    RenderOptions options;
    options.spp = spp;
    options.seed = seed;
    options.threads = threads;
    ProgressBar bar(!quiet);
    options.progress = bar.callback();
    RenderStats stats;
    const std::vector<Layer> layers = render_layers(*scene, options, &stats);

    const Film& film = *scene->sensor->film;
    write_film(output, film, layers);
    const SamplerDesc& sampler = *scene->sensor->sampler;
    const int used_spp = sampler.effective_spp(spp);
    if (spp > 0 && used_spp != spp)
        std::fprintf(stderr, "note: the %s sampler rounds --spp %d to %d\n", sampler_type_name(sampler.type), spp,
                     used_spp);
    std::fprintf(stderr, "rendered %dx%d at %d spp (%s) in %.2f s (%.2f M samples/s, %.2f M rays/s) -> %s\n",
                 film.width, film.height, used_spp, sampler_type_name(sampler.type), stats.seconds, stats.samples / stats.seconds * 1e-6,
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
    std::printf("sensor: %s, film %dx%d, rfilter %s, %d spp (%s)\n", scene->sensor->plugin.c_str(), film.width,
                film.height, film.rfilter->plugin.c_str(), scene->sensor->sampler->sample_count,
                sampler_type_name(scene->sensor->sampler->type));
    if (scene->integrator) std::printf("integrator: %s\n", scene->integrator->plugin.c_str());
    std::printf("shapes: %zu (%zu triangles)\n", scene->shapes.size(), scene->triangle_count());
    for (const auto& s : scene->shapes) {
        std::printf("  %-12s %-16s %8zu triangles  bsdf %-14s%s", s->plugin.c_str(),
                    s->id.empty() ? "-" : s->id.c_str(), s->mesh.face_count(),
                    s->bsdf ? s->bsdf->plugin.c_str() : "-", s->emitter ? "  [area emitter]" : "");
        if (s->degenerate_count()) std::printf("  (%zu degenerate triangles)", s->degenerate_count());
        std::printf("\n");
    }
    if (!scene->instances.empty()) {
        std::printf("instances: %zu (%zu triangles placed; each shapegroup's stored once)\n", scene->instances.size(),
                    scene->instanced_triangle_count());
        for (const auto& inst : scene->instances)
            std::printf("  %-16s of group %-16s %zu shape(s)\n", inst->id.empty() ? "-" : inst->id.c_str(),
                        inst->group->id.empty() ? "-" : inst->group->id.c_str(), inst->group->shapes.size());
    }
    std::printf("emitters: %zu\n", scene->emitters.size());
    for (const auto& e : scene->emitters)
        std::printf("  %-12s %s\n", e->plugin.c_str(), e->id.empty() ? "-" : e->id.c_str());
    // Media, with the objects that reference them (shape sides, the sensor, lights).
    std::vector<std::pair<const Medium*, std::string>> media;
    auto note_medium = [&](const Medium* m, const std::string& user) {
        if (!m) return;
        for (auto& [medium, users] : media)
            if (medium == m) {
                users += ", " + user;
                return;
            }
        media.emplace_back(m, user);
    };
    for (const auto& sensor : scene->sensors) note_medium(sensor->medium.get(), "sensor " + sensor->id);
    for (const auto& s : scene->shapes) {
        const std::string name = s->id.empty() ? s->plugin : s->id;
        note_medium(s->interior.get(), name + " (interior)");
        note_medium(s->exterior.get(), name + " (exterior)");
    }
    for (const auto& e : scene->emitters) note_medium(e->medium.get(), e->id.empty() ? e->plugin : e->id);
    if (!media.empty()) {
        std::printf("media: %zu\n", media.size());
        for (const auto& [m, users] : media)
            std::printf("  %-12s %-16s used by %s\n", m->plugin.c_str(), m->id.empty() ? "-" : m->id.c_str(),
                        users.c_str());
    }
    std::map<std::string, int> materials;
    for (const auto& s : scene->shapes)
        if (s->bsdf) materials[s->bsdf->id.empty() ? "(" + s->bsdf->plugin + ")" : s->bsdf->id]++;
    std::printf("materials: %zu\n", materials.size());
    for (const auto& [name, count] : materials) std::printf("  %-24s used by %d shape(s)\n", name.c_str(), count);
    return 0;
}

} // namespace

void add_render_commands(CLI::App& app) {
    struct Options {
        std::string scene, output, integrator, sensor = "0";
        int spp = 0, threads = 0;
        uint64_t seed = 0;
        std::vector<std::string> defines;
        bool quiet = false;
    };
    auto opt = std::make_shared<Options>();
    auto* render = app.add_subcommand("render", "render a Mitsuba 3 XML scene to an image");
    render->add_option("scene", opt->scene, "scene file (Mitsuba 3 XML)")->required();
    render->add_option("-o,--output", opt->output, "output image (.exr or .png)")->required();
    render->add_option("--spp", opt->spp, "samples per pixel (default: the scene's sampler)")->check(CLI::PositiveNumber);
    render->add_option("--seed", opt->seed, "random seed");
    render->add_option("--threads", opt->threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    render->add_option("-D", opt->defines, "override a <default> value: name=value");
    render->add_option("--integrator", opt->integrator, "replace the scene's integrator (path, volpath, volpathmis, bdpt, direct, ptracer, sppm)");
    render->add_option("--sensor", opt->sensor,
                       "the sensor to render: an index (default 0) or a sensor's id");
    render->add_flag("-q,--quiet", opt->quiet, "no progress bar");
    render->callback([opt] {
        cmd_render(opt->scene, opt->output, opt->spp, opt->seed, opt->threads, opt->defines, opt->integrator,
                   opt->sensor, opt->quiet);
    });

    auto info_opt = std::make_shared<Options>();
    auto* info = app.add_subcommand("info", "print what a scene contains");
    info->add_option("scene", info_opt->scene, "scene file (Mitsuba 3 XML)")->required();
    info->add_option("-D", info_opt->defines, "override a <default> value: name=value");
    info->callback([info_opt] { cmd_info(info_opt->scene, info_opt->defines); });
}

} // namespace penumbra::cli
