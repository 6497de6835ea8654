// `penumbra optimize config.json`: inverse rendering driven by a JSON configuration (src/optim/optimize.h).
#include "cli.h"

#include "core/error.h"
#include "optim/optimize.h"

#include <cmath>
#include <cstdio>

namespace penumbra::cli {

namespace {

std::string format_values(const std::vector<double>& v) {
    if (v.size() > 64) return "[" + std::to_string(v.size()) + " values]"; // a mesh: see final_<shape>.ply
    std::string s;
    for (double x : v) {
        char buf[32];
        std::snprintf(buf, sizeof(buf), "%s%.4g", s.empty() ? "" : ", ", x);
        s += buf;
    }
    return v.size() > 1 ? "(" + s + ")" : s;
}

void print_summary(const OptimizeConfig& config, const OptimizeResult& result) {
    const double loss = result.history.empty() ? NAN : result.history.back().loss;
    std::fprintf(stderr,
                 "%s: %d iterations in %.1f s (%.2f s/iteration; target %.1f s); last loss %.4g; peak memory "
                 "%.0f MB -> %s\n",
                 result.method.c_str(), config.iterations, result.seconds,
                 config.iterations ? result.seconds / config.iterations : 0.0, result.target_seconds, loss,
                 result.peak_memory_mb, config.output.c_str());
    if (!result.description.empty()) std::fprintf(stderr, "  gradient: %s\n", result.description.c_str());
    for (const ParameterResult& p : result.parameters) {
        std::fprintf(stderr, "  %-28s %s -> %s", p.name.c_str(), format_values(p.initial).c_str(),
                     format_values(p.final).c_str());
        if (!p.truth.empty() && std::isfinite(p.pose_error))
            std::fprintf(stderr, "  (true %s, error %.4g%s)", format_values(p.truth).c_str(), p.pose_error,
                         p.name.ends_with(".rotate") ? " degrees" : "");
        else if (!p.truth.empty())
            std::fprintf(stderr, "  (true %s, relative error %.2f%%)", format_values(p.truth).c_str(),
                         100.0 * p.relative_error);
        std::fprintf(stderr, "\n");
    }
    if (std::isfinite(result.final_parameter_error))
        std::fprintf(stderr, "parameter error (relative L2 over the material/emitter parameters): %.2f%%\n",
                     100.0 * result.final_parameter_error);
    for (const ShapeResult& r : result.shapes)
        std::fprintf(stderr, "shape '%s': mean vertex error %.4g -> %.4g, Chamfer distance %.4g -> %.4g\n",
                     r.name.c_str(), r.initial_vertex_error, r.final_vertex_error, r.initial_chamfer,
                     r.final_chamfer);
    if (std::isfinite(result.final_translation_error))
        std::fprintf(stderr, "translation error: %.4g scene units\n", result.final_translation_error);
    if (std::isfinite(result.final_rotation_error))
        std::fprintf(stderr, "rotation error: %.3g degrees\n", result.final_rotation_error);
}

} // namespace

void add_optimize_command(CLI::App& app) {
    struct Options {
        std::string config, output;
        int iterations = -1;
        bool quiet = false;
    };
    auto opt = std::make_shared<Options>();
    auto* cmd =
        app.add_subcommand("optimize", "recover scene parameters from a target image (JSON configuration)");
    cmd->add_option("config", opt->config, "optimization configuration (JSON)")->required();
    cmd->add_option("--iterations", opt->iterations, "override the configuration's iterations")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("-o,--output", opt->output, "override the configuration's output directory");
    cmd->add_flag("-q,--quiet", opt->quiet, "no progress bar");
    cmd->callback([opt] {
        OptimizeConfig config = load_optimize_config(opt->config);
        if (opt->iterations >= 0) config.iterations = opt->iterations;
        if (!opt->output.empty()) config.output = opt->output;
        ProgressBar bar(!opt->quiet, "optimize");
        const OptimizeResult result = optimize(config, [&](const IterationRecord& r) {
            bar.update(float(r.iteration + 1) / float(config.iterations));
        });
        print_summary(config, result);
    });
}

} // namespace penumbra::cli
