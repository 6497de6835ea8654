// `penumbra variance-study | sampling-demo`: the equal-time benchmarks of the path sampling methods (paper 002
// §5.2 and §5.3; src/studies/variance_study.h, src/studies/sampling_race.h); `penumbra equal-time`: variance × time of
// derivative methods (paper 001 §7: psdr against a DTRT-like baseline; src/studies/equal_time.h).
#include "cli.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "diff/parameters.h"
#include "scene/scene.h"
#include "studies/equal_time.h"
#include "studies/sampling_race.h"
#include "studies/variance_study.h"

#include <cstdio>

namespace penumbra::cli {

namespace {

void add_variance_study(CLI::App& app) {
    struct Options {
        std::string scene, param;
        std::vector<std::string> defines, outputs;
        VarianceStudyOptions study;
        bool quiet = false;
    };
    auto opt = std::make_shared<Options>();
    auto* cmd = app.add_subcommand("variance-study",
                                   "equal-time variance of image and loss gradients of the 8 path sampling variants "
                                   "(BSDF/differential x adaptive x NEE, paper 002 Table 2)");
    cmd->add_option("scene", opt->scene, "scene file (Mitsuba 3 XML)")->required();
    cmd->add_option("--param", opt->param, "the (non-geometric) parameter: NAME[=direction]")->required();
    cmd->add_option("-D", opt->defines, "override a <default> value: name=value (e.g. -D res=48)");
    cmd->add_option("--runs", opt->study.runs, "independent runs per variant (default 100)")->check(CLI::Range(2, 100000));
    cmd->add_option("--time-budget", opt->study.time_budget,
                    "CPU seconds per run (default: one BSDF-sampling run without NEE at --spp)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--spp", opt->study.spp, "spp of the baseline run that sets the default time budget (default 16)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--target-value", opt->study.target_value, "parameter value of the target image (default: value x 1.3)");
    cmd->add_option("--target-scale", opt->study.target_scale, "target at value x scale (default 1.3)");
    cmd->add_option("--seed", opt->study.seed, "random seed");
    cmd->add_option("--threads", opt->study.threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    cmd->add_option("-o,--output", opt->outputs, "write the table: .md (markdown) or .json (repeatable)");
    cmd->add_flag("-q,--quiet", opt->quiet, "no progress output");
    cmd->callback([opt] {
        for (const std::string& path : opt->outputs) {
            const std::string ext = lower_extension(path);
            if (ext != ".md" && ext != ".json") throw Error("variance-study: output '" + path + "' must end in .md or .json");
        }
        auto scene = load_scene(opt->scene, parse_defines(opt->defines));
        Parameters params(*scene);
        params.enable({parse_param_selection(opt->param)});
        std::string stage;
        ProgressBar bar(!opt->quiet, "");
        opt->study.progress = [&](const std::string& s, float f) {
            if (s != stage && !opt->quiet) std::fprintf(stderr, "\n%s", s.c_str()), stage = s;
            bar.update(f);
        };
        const VarianceStudy study = run_variance_study(*scene, params, opt->study);
        if (!opt->quiet) std::fprintf(stderr, "\n");
        const std::string table = variance_study_markdown(study);
        std::printf("%s", table.c_str());
        for (const std::string& path : opt->outputs)
            write_text_atomically(path, lower_extension(path) == ".md" ? table : variance_study_json(study));
    });
}

void add_sampling_demo(CLI::App& app) {
    struct Options {
        std::string scene, loss = "rel_l2";
        std::vector<std::string> defines, params;
        SamplingRaceOptions race;
        bool quiet = false;
    };
    auto opt = std::make_shared<Options>();
    auto* cmd = app.add_subcommand("sampling-demo",
                                   "equal-time inverse rendering: BSDF sampling vs differential + adaptive sampling "
                                   "(paper 002 §5.3); the scene's values are the truth");
    cmd->add_option("scene", opt->scene, "scene file (Mitsuba 3 XML)")->required();
    cmd->add_option("--param", opt->params, "parameter to recover and its initial value: NAME=VALUE (repeatable)")
        ->required();
    cmd->add_option("-D", opt->defines, "override a <default> value: name=value");
    cmd->add_option("--iterations", opt->race.iterations, "Adam iterations per method (default 40)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--spp", opt->race.spp, "BSDF sampling's spp per iteration, all passes (default 8)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--lr", opt->race.learning_rate, "Adam learning rate (default 0.02)")->check(CLI::PositiveNumber);
    cmd->add_option("--loss", opt->loss, "l2 or rel_l2 (default)")->check(CLI::IsMember({"l2", "rel_l2"}));
    cmd->add_option("--eval-spp", opt->race.eval_spp, "spp of the logged loss (not timed; default 32)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--target-spp", opt->race.target_spp, "spp of the target image (default 256)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--seed", opt->race.seed, "random seed");
    cmd->add_option("--threads", opt->race.threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    cmd->add_option("-o,--output", opt->race.output, "output directory for race.csv and race.png (default race)");
    cmd->add_flag("-q,--quiet", opt->quiet, "no progress bar");
    cmd->callback([opt] {
        for (const std::string& p : opt->params) {
            const auto [name, values] = parse_param_selection(p);
            if (values.size() != 1) throw Error("sampling-demo: --param needs NAME=VALUE (one initial value), got '" + p + "'");
            opt->race.parameters.push_back(name);
            opt->race.initial.push_back(values[0]);
        }
        opt->race.loss = parse_loss_kind(opt->loss);
        auto scene = load_scene(opt->scene, parse_defines(opt->defines));
        ProgressBar bar(!opt->quiet, "sampling-demo");
        const int total = 2 * opt->race.iterations;
        int done = 0;
        opt->race.progress = [&](const std::string&, int) { bar.update(float(++done) / float(total)); };
        const SamplingRaceResult r = sampling_race(*scene, opt->race);
        for (const RaceMethod& m : r.methods) {
            const RaceRecord& last = m.history.back();
            std::fprintf(stderr, "\n%-24s spp %3d, %.3f CPU s/iteration: loss %.4g -> %.4g, parameter error %.2f%% -> %.2f%% (",
                         m.name.c_str(), m.spp, m.seconds_per_iteration, m.history.front().loss, last.loss,
                         100.0 * m.history.front().parameter_error, 100.0 * last.parameter_error);
            for (size_t k = 0; k < r.parameters.size(); ++k)
                std::fprintf(stderr, "%s%s = %.4g [true %.4g]", k ? ", " : "", r.parameters[k].c_str(), last.values[k],
                             r.truth[k]);
            std::fprintf(stderr, ")");
        }
        std::fprintf(stderr, "\nwrote %s and %s\n", r.csv_path.c_str(), r.plot_path.c_str());
    });
}

void add_equal_time(CLI::App& app) {
    struct Options {
        std::string scene, reference, reference_stderr, output;
        std::vector<std::string> params, defines, methods{"psdr", "psdr --no-volume-boundary"};
        EqualTimeOptions study;
        bool quiet = false;
    };
    auto opt = std::make_shared<Options>();
    auto* cmd = app.add_subcommand("equal-time",
                                   "variance x time of derivative methods (default: psdr against the DTRT-like "
                                   "baseline psdr --no-volume-boundary, paper 001 §7)");
    cmd->add_option("scene", opt->scene, "scene file (Mitsuba 3 XML)")->required();
    cmd->add_option("--param", opt->params, "parameter to differentiate: NAME[=direction] (repeatable)")->required();
    cmd->add_option("-D", opt->defines, "override a <default> value: name=value (e.g. -D res=64)");
    cmd->add_option("--method", opt->methods,
                    "a method with its options, quoted: \"psdr\", \"psdr --no-volume-boundary\", \"interior\" "
                    "(repeatable; the first is the reference of the ratios)");
    cmd->add_option("--spp", opt->study.spp, "samples per pixel per batch, every method (default 64)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--batches", opt->study.batches, "independent batches (default 16)")->check(CLI::Range(2, 100000));
    cmd->add_option("--reference", opt->reference, "finite-difference reference (.exr) for the bias columns");
    cmd->add_option("--reference-stderr", opt->reference_stderr, "its standard-error image (.exr)");
    cmd->add_option("--seed", opt->study.seed, "random seed");
    cmd->add_option("--threads", opt->study.threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    cmd->add_option("-o,--output", opt->output, "write the table (.md)");
    cmd->add_flag("-q,--quiet", opt->quiet, "no progress output");
    cmd->callback([opt] {
        if (!opt->output.empty() && lower_extension(opt->output) != ".md")
            throw Error("equal-time: output '" + opt->output + "' must end in .md");
        std::vector<MethodSpec> methods;
        for (const std::string& m : opt->methods) methods.push_back(parse_method_spec(m));
        auto scene = load_scene(opt->scene, parse_defines(opt->defines));
        Parameters params(*scene);
        std::vector<std::pair<std::string, std::vector<float>>> selection;
        for (const std::string& p : opt->params) selection.push_back(parse_param_selection(p));
        params.enable(selection);
        const Image reference = opt->reference.empty() ? Image() : read_image(opt->reference, false);
        const Image reference_stderr = opt->reference_stderr.empty() ? Image() : read_image(opt->reference_stderr, false);
        if (!opt->quiet) opt->study.progress = [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); };
        const std::vector<EqualTimeRow> rows =
            equal_time_study(*scene, params, methods, opt->study, reference, reference_stderr);
        const std::string table = equal_time_markdown(rows, !reference.pixels.empty());
        std::printf("%s", table.c_str());
        if (!opt->output.empty()) write_text_atomically(opt->output, table);
    });
}

} // namespace

void add_study_commands(CLI::App& app) {
    add_variance_study(app);
    add_sampling_demo(app);
    add_equal_time(app);
}

} // namespace penumbra::cli
