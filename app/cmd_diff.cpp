// `penumbra params | derivative | gradient | fd | compare`: differentiation from the command line.
#include "cli.h"

#include "core/atomic_file.h"
#include "diff/finite_difference.h"
#include "diff/method.h"
#include "diff/psdr/budget.h"
#include "diff/psdr/interior.h"
#include "scene/scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace penumbra::cli {

namespace {

struct Common {
    std::string scene;
    std::string method = "psdr";
    MethodOptions method_options; // the --<option> flags of the methods (diff/method.h) that were given
    std::vector<std::string> defines, params;
    std::string sensor = "0";
    int spp = 64, threads = 0, batches = 0;
    uint64_t seed = 0;
    std::string output, stderr_output, terms_prefix;
    bool quiet = false;
    std::string adjoint, target, loss = "l2";
};

void add_common(CLI::App* cmd, Common& c, bool needs_params) {
    cmd->add_option("scene", c.scene, "scene file (Mitsuba 3 XML)")->required();
    auto* p = cmd->add_option(
        "--param", c.params,
        "parameter to differentiate, optionally with a direction: NAME[=v1,v2,...] (repeatable); "
        "shape rotate/scale/deform motions take a center: NAME@cx,cy,cz[=...]");
    if (needs_params) p->required();
    cmd->add_option("-D", c.defines, "override a <default> value: name=value");
    cmd->add_option("--spp", c.spp, "samples per pixel (in total)")->check(CLI::PositiveNumber);
    cmd->add_option("--seed", c.seed, "random seed");
    cmd->add_option("--threads", c.threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    cmd->add_option(
        "--sensor", c.sensor,
        "the sensor: an index (default 0) or a sensor's id (its motions are <id>.translate/.rotate)");
    cmd->add_flag("-q,--quiet", c.quiet, "no progress bar");
}

// Loads the scene with -D overrides and selects --sensor.
std::unique_ptr<Scene> load(const Common& c) {
    auto scene = load_scene(c.scene, parse_defines(c.defines));
    scene->select_sensor(c.sensor);
    return scene;
}

// --method and every registered method's options (diff/method.h), each flag once; make_method() checks that
// the given ones belong to the chosen method.
void add_method(CLI::App* cmd, Common& c) {
    std::vector<std::string> names;
    std::string help = "derivative method:";
    std::map<std::string, std::string> owners;
    for (const MethodInfo& m : derivative_methods()) {
        names.push_back(m.name);
        help += " " + m.name + " (" + m.help + ");";
        for (const MethodOption& o : m.options)
            owners[o.name] += (owners[o.name].empty() ? "" : ", ") + m.name;
    }
    cmd->add_option("--method", c.method, help)->check(CLI::IsMember(names));
    std::set<std::string> added;
    for (const MethodInfo& m : derivative_methods())
        for (const MethodOption& o : m.options) {
            if (!added.insert(o.name).second) continue;
            const std::string flag = "--" + o.name, text = o.help + " [method " + owners[o.name] + "]";
            const std::string name = o.name;
            if (o.type == MethodOption::Type::Bool)
                cmd->add_flag_callback(
                    flag, [&c, name] { c.method_options.set(name, "true"); }, text);
            else
                cmd->add_option_function<std::string>(
                       flag, [&c, name](const std::string& v) { c.method_options.set(name, v); }, text)
                    ->type_name(o.type == MethodOption::Type::Int     ? "INT"
                                : o.type == MethodOption::Type::Float ? "FLOAT"
                                                                      : "TEXT");
        }
}

MethodRun method_run(const Common& c, int batches) {
    MethodRun run;
    run.spp = c.spp;
    run.batches = batches;
    run.seed = c.seed;
    run.threads = c.threads;
    run.verbose = !c.quiet;
    return run;
}

std::vector<std::pair<std::string, std::vector<float>>> selection(const std::vector<std::string>& params) {
    std::vector<std::pair<std::string, std::vector<float>>> s;
    for (const std::string& p : params) s.push_back(parse_param_selection(p));
    return s;
}

void check_output(const std::string& path) {
    const std::string ext = lower_extension(path);
    if (ext != ".exr" && ext != ".png") throw Error("output '" + path + "': expected a .exr or .png file name");
}

// Splits the sample budget into batches for standard errors (8 when --stderr is requested).
int batches_for(const Common& c) {
    const int b = c.batches > 0 ? c.batches : (c.stderr_output.empty() ? 1 : 8);
    if (c.spp < b) throw Error("--spp " + std::to_string(c.spp) + " is smaller than the " + std::to_string(b) + " batches");
    return b;
}

double image_mean(const Image& img) {
    double m = 0;
    for (const Color3f& c : img.pixels) m += double(c.x) + c.y + c.z;
    return m / (3.0 * double(img.pixels.size()));
}

void cmd_params(const Common& c) {
    auto scene = load(c);
    Parameters params(*scene);
    std::printf("%-48s %10s  %s\n", "name", "size", "kind");
    for (const Parameter& p : params.all()) {
        const char* kind = p.kind == Parameter::Kind::Data        ? (p.geometry ? "geometry" : "value")
                           : p.kind == Parameter::Kind::Translate ? "motion (direction: world vector)"
                           : p.sensor || p.emitter                ? "motion (direction: world axis; radians)"
                           : p.kind == Parameter::Kind::Rotate
                               ? "motion (direction: world axis; radians; NAME@cx,cy,cz: about that center)"
                           : p.kind == Parameter::Kind::Deform
                               ? "motion (x + θ d exp(-|x-c|²/2r²), r = bbox diagonal / 4; direction: world "
                                 "vector d; NAME@cx,cy,cz: c)"
                               : "motion (uniform scale; NAME@cx,cy,cz: about that center)";
        std::printf("%-48s %10d  %s\n", p.name.c_str(), p.size, kind);
    }
}

void cmd_derivative(const Common& c) {
    check_output(c.output);
    auto method = make_method(c.method, c.method_options);
    auto scene = load(c);
    Parameters params(*scene);
    params.enable(selection(c.params));
    const Image importance = c.adjoint.empty() ? Image() : read_image(c.adjoint, false);
    MethodRun run = method_run(c, batches_for(c));
    if (!c.adjoint.empty()) run.importance = &importance;
    ProgressBar bar(!c.quiet, "derivative");
    run.progress = bar.callback();
    const DerivativeImage d = method->derivative(*scene, params, run);
    for (const std::string& w : d.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    write_signed(c.output, d.derivative);
    if (!c.stderr_output.empty()) write_image(c.stderr_output, d.stderr_img);
    // Each term's image (and, with --stderr, its standard error as PREFIX_<term>_stderr.exr).
    if (!c.terms_prefix.empty())
        for (const DerivativeTerm& t : d.terms) {
            const std::string name = c.terms_prefix + "_" + t.name;
            write_signed(name + lower_extension(c.output), t.derivative);
            if (!c.stderr_output.empty() && !t.stderr_img.pixels.empty())
                write_image(name + "_stderr.exr", t.stderr_img);
        }
    const Film& film = *scene->sensor->film;
    std::fprintf(stderr, "derivative (%s: %s) %dx%d, %d spp in %.2f s, mean %.6g -> %s\n", c.method.c_str(),
                 d.description.c_str(), film.width, film.height, c.spp, d.seconds, image_mean(d.derivative),
                 c.output.c_str());
}

void cmd_fd(const Common& c, double eps) {
    check_output(c.output);
    auto scene = load(c);
    Parameters params(*scene);
    params.enable(selection(c.params));
    RenderOptions o;
    const int batches = batches_for(c);
    o.spp = c.spp / batches;
    o.seed = c.seed;
    o.threads = c.threads;
    ProgressBar bar(!c.quiet, "fd");
    o.progress = bar.callback();
    const FiniteDifference fd = finite_difference(*scene, params, eps, o, batches);
    write_signed(c.output, fd.derivative);
    if (!c.stderr_output.empty()) write_image(c.stderr_output, fd.stderr_img);
    std::fprintf(stderr, "central differences (h = %g) at %d spp per side in %.2f s, mean %.6g -> %s\n", eps,
                 o.spp * batches, fd.seconds, image_mean(fd.derivative), c.output.c_str());
}

void cmd_gradient(const Common& c) {
    if (c.adjoint.empty() == c.target.empty()) throw Error("gradient: give exactly one of --adjoint and --target");
    auto method = make_method(c.method, c.method_options);
    auto scene = load(c);
    Parameters params(*scene);
    if (c.params.empty()) params.enable_all_data();
    else params.enable(selection(c.params));
    nlohmann::json out;
    MethodRun run = method_run(c, 1);
    ProgressBar bar(!c.quiet, "gradient");
    run.progress = bar.callback();
    Gradient g;
    if (!c.target.empty()) {
        g = method->loss_gradient(*scene, params, read_image(c.target, false), parse_loss_kind(c.loss), run);
        out["loss"] = g.loss;
        std::fprintf(stderr, "loss (%s) of the primal image: %.6g\n", c.loss.c_str(), g.loss);
    } else {
        g = method->gradient(*scene, params, read_image(c.adjoint, false), run);
    }
    out["method"] = c.method + ": " + g.description;
    for (const std::string& w : g.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    out["warnings"] = g.warnings;
    out["dropped_samples"] = g.cost.dropped;
    out["seconds"] = g.seconds;
    out["spp"] = c.spp;
    for (const auto& [p, index] : params.enabled()) {
        std::vector<double> values(g.values.begin() + index, g.values.begin() + index + p->size);
        double norm2 = 0;
        for (double v : values) norm2 += v * v;
        out["parameters"].push_back({{"name", p->name}, {"size", p->size}, {"gradient", values}});
        std::printf("%-48s %8d  |dL/dθ| = %.6g\n", p->name.c_str(), p->size, std::sqrt(norm2));
    }
    if (!c.output.empty()) write_text_atomically(c.output, out.dump(1) + "\n");
    std::fprintf(stderr, "gradient of %d parameter scalars at %d spp in %.2f s%s%s\n", params.dimension(), c.spp,
                 g.seconds, c.output.empty() ? "" : " -> ", c.output.c_str());
}

void cmd_compare(const std::string& test, const std::string& ref, const std::string& test_se, const std::string& ref_se,
                 const std::string& z_map) {
    const Image a = read_image(test, false), b = read_image(ref, false);
    const Image sa = test_se.empty() ? Image() : read_image(test_se, false);
    const Image sb = ref_se.empty() ? Image() : read_image(ref_se, false);
    const Comparison c = compare_images(a, b, sa, sb);
    const Comparison c4 = compare_images(block_average(a, 4), block_average(b, 4), block_average_stderr(sa, 4),
                                         block_average_stderr(sb, 4));
    std::printf("relerr = %.6f   (Σ|D−R| / Σ|R| over %dx%d pixels)\n", c.relerr, a.width, a.height);
    std::printf("relerr4 = %.6f   (after 4x4 block averaging)\n", c4.relerr);
    std::printf("mean: test %.6g  reference %.6g\n", c.mean_test, c.mean_ref);
    if (!sa.pixels.empty() || !sb.pixels.empty()) {
        std::printf("z-score of the image mean = %.3f   pixels with |z| > 3: %.2f%%   relerr expected from noise: %.6f (relerr4: %.6f)\n",
                    c.mean_z, 100.0 * c.outlier_fraction, c.noise_relerr, c4.noise_relerr);
        for (const auto& [name, se] : {std::pair{"test", &sa}, std::pair{"reference", &sb}}) {
            if (se->pixels.empty()) continue;
            const Comparison alone = compare_images(b, b, *se, Image());
            const Comparison alone4 = compare_images(block_average(b, 4), block_average(b, 4), block_average_stderr(*se, 4), Image());
            std::printf("  noise of the %s alone: relerr %.6f, relerr4 %.6f\n", name, alone.noise_relerr, alone4.noise_relerr);
        }
    }
    if (!z_map.empty()) {
        if (sa.pixels.empty() && sb.pixels.empty()) throw Error("--z-map needs --stderr or --ref-stderr");
        write_z_map(z_map, a, b, sa, sb);
    }
}

} // namespace

void add_diff_commands(CLI::App& app) {
    auto params = std::make_shared<Common>();
    auto* p = app.add_subcommand("params", "list the differentiable parameters of a scene");
    p->add_option("scene", params->scene, "scene file (Mitsuba 3 XML)")->required();
    p->add_option("-D", params->defines, "override a <default> value: name=value");
    p->callback([params] { cmd_params(*params); });

    auto deriv = std::make_shared<Common>();
    auto* d = app.add_subcommand("derivative", "forward mode: the image derivative dI/dθ");
    add_common(d, *deriv, true);
    d->add_option("-o,--output", deriv->output, "derivative image (.exr values, .png colormap)")->required();
    d->add_option("--stderr", deriv->stderr_output, "per-pixel standard-error image (.exr)");
    d->add_option("--batches", deriv->batches, "independent batches for --stderr (default 8)")
        ->check(CLI::PositiveNumber);
    d->add_option("--terms", deriv->terms_prefix,
                  "also write each term's image as PREFIX_interior / _primary / _direct / _indirect (/ _pixel with a box "
                  "filter and a moving camera), and with --stderr their standard errors as PREFIX_<term>_stderr.exr");
    d->add_option("--adjoint", deriv->adjoint,
                  "adjoint image ∂L/∂I giving the pixel importance (--method paths --adaptive)");
    add_method(d, *deriv);
    d->callback([deriv] { cmd_derivative(*deriv); });

    auto fd = std::make_shared<Common>();
    auto eps = std::make_shared<double>(1e-2);
    auto* f = app.add_subcommand("fd", "central finite differences with common random numbers");
    add_common(f, *fd, true);
    f->add_option("-o,--output", fd->output, "derivative image (.exr values, .png colormap)")->required();
    f->add_option("--eps", *eps, "step h")->check(CLI::PositiveNumber);
    f->add_option("--stderr", fd->stderr_output, "per-pixel standard-error image (.exr)");
    f->add_option("--batches", fd->batches, "independent batches for --stderr (default 8)")->check(CLI::PositiveNumber);
    f->callback([fd, eps] { cmd_fd(*fd, *eps); });

    auto grad = std::make_shared<Common>();
    auto* g =
        app.add_subcommand("gradient", "reverse mode: dL/dθ for all parameters given an adjoint image ∂L/∂I "
                                       "(or a target image and a loss)");
    add_common(g, *grad, false);
    g->add_option("--adjoint", grad->adjoint, "adjoint image ∂L/∂I (.exr, the film's size)");
    g->add_option("--target", grad->target,
                  "target image: a primal pass (its own samples) gives the loss and its adjoint");
    g->add_option("--loss", grad->loss,
                  "loss for --target: l2, rel_l2 or matching (paper 003 Eq. 25: paths matched to the target's "
                  "pixels; methods dpm-g, dpm-c)")
        ->check(CLI::IsMember({"l2", "rel_l2", "matching"}));
    g->add_option("-o,--output", grad->output, "gradient as JSON");
    add_method(g, *grad);
    g->callback([grad] { cmd_gradient(*grad); });

    auto cmp = std::make_shared<std::array<std::string, 5>>();
    auto* c = app.add_subcommand("compare", "relerr and z-scores of a derivative image against a reference");
    c->add_option("test", (*cmp)[0], "image to test (.exr)")->required();
    c->add_option("reference", (*cmp)[1], "reference image (.exr)")->required();
    c->add_option("--stderr", (*cmp)[2], "standard-error image of the test image");
    c->add_option("--ref-stderr", (*cmp)[3], "standard-error image of the reference");
    c->add_option("--z-map", (*cmp)[4], "write the per-pixel z-scores (D − R)/σ as a .png (blue < 0 < red, saturated at ±4) or .exr");
    c->callback([cmp] { cmd_compare((*cmp)[0], (*cmp)[1], (*cmp)[2], (*cmp)[3], (*cmp)[4]); });
}

} // namespace penumbra::cli
