// `penumbra params | derivative | gradient | fd | compare`: differentiation from the command line.
#include "cli.h"

#include "diff/budget.h"
#include "diff/finite_difference.h"
#include "diff/interior.h"
#include "diff/path_sampling.h"
#include "diff/psdr.h"
#include "scene/scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <chrono>
#include <filesystem>
#include <fstream>

namespace penumbra::cli {

namespace {

struct Common {
    std::string scene;
    std::string method = "psdr";
    std::string first_vertex = "auto";
    // Per-term samples per pixel for experts (-1: unset). Unset everywhere: --spp is the total budget, split by
    // a calibration pass (diff/budget.h).
    int boundary_spp = -1, primary_spp = -1, direct_spp = -1, indirect_spp = -1, pixel_spp = -1;
    std::vector<std::string> defines, params;
    int spp = 64, threads = 0, batches = 0;
    uint64_t seed = 0;
    std::string output, stderr_output, terms_prefix;
    bool quiet = false, no_guiding = false;
    // --method paths (paper 002)
    std::string sampling = "differential";
    float q = 0.5f;
    bool no_nee = false, adaptive = false;
    double defensive = 0.05, primal_fraction = 0.75;
    std::string adjoint, target, loss = "l2";
};

void add_common(CLI::App* cmd, Common& c, bool needs_params) {
    cmd->add_option("scene", c.scene, "scene file (Mitsuba 3 XML)")->required();
    auto* p = cmd->add_option(
        "--param", c.params,
        "parameter to differentiate, optionally with a direction: NAME[=v1,v2,...] (repeatable); "
        "shape rotate/scale motions take a center: NAME@cx,cy,cz[=...]");
    if (needs_params) p->required();
    cmd->add_option("-D", c.defines, "override a <default> value: name=value");
    cmd->add_option("--spp", c.spp, "samples per pixel (in total)")->check(CLI::PositiveNumber);
    cmd->add_option("--seed", c.seed, "random seed");
    cmd->add_option("--threads", c.threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    cmd->add_flag("-q,--quiet", c.quiet, "no progress bar");
}

void add_method(CLI::App* cmd, Common& c) {
    cmd->add_option("--method", c.method,
                    "interior (material-form interior term only), psdr (interior + boundary) or paths (path sampling "
                    "methods of paper 002, non-geometric parameters only)")
        ->check(CLI::IsMember({"interior", "psdr", "paths"}));
    cmd->add_option("--boundary-spp", c.boundary_spp,
                    "samples per pixel of each boundary term (experts; by default --spp is a total budget that a "
                    "calibration pass splits over the terms)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--primary-spp", c.primary_spp, "samples per pixel of the primary boundary term (experts)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--direct-spp", c.direct_spp, "samples per pixel of the direct boundary term (experts)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--indirect-spp", c.indirect_spp, "samples per pixel of the indirect boundary term (experts)")->check(CLI::NonNegativeNumber);
    cmd->add_option("--pixel-spp", c.pixel_spp, "samples per pixel of the pixel-boundary term (experts)")->check(CLI::NonNegativeNumber);
    cmd->add_flag("--no-guiding", c.no_guiding, "sample the primary term's edges by projected length only (no contrast pilot)");
    cmd->add_option("--first-vertex", c.first_vertex,
                    "parameterization of the vertex the camera sees: image (fixed camera rays; needs a static camera), "
                    "material (material points; the filter and pixel edges move) or auto (image unless the camera "
                    "moves or a moving surface has a checkerboard/nearest texture)")
        ->check(CLI::IsMember({"auto", "image", "material"}));
    cmd->add_option("--sampling", c.sampling, "--method paths: differential (differential vertex sampling) or bsdf")
        ->check(CLI::IsMember({"differential", "bsdf"}));
    cmd->add_option("--q", c.q, "--method paths: probability that a vertex becomes the differential vertex (default 0.5)")
        ->check(CLI::Range(0.0, 0.999));
    cmd->add_flag("--no-nee", c.no_nee, "--method paths: no next-event estimation");
    cmd->add_flag("--adaptive", c.adaptive, "--method paths: adaptive pixel sampling by |adjoint| (needs --adjoint or --target)");
    cmd->add_option("--defensive", c.defensive, "--method paths: uniform share of the adaptive pixel density (default 0.05)")
        ->check(CLI::Range(0.0, 1.0));
}

// --method paths: the options of diff/path_sampling.h from the command line.
PathSamplingOptions path_sampling_options(const Scene& scene, const Common& c, int batches) {
    PathSamplingOptions o;
    o.batches = batches;
    o.spp = c.spp / batches;
    o.seed = c.seed;
    o.threads = c.threads;
    o.path = path_settings(scene);
    o.differential = c.sampling == "differential";
    o.q = c.q;
    o.nee = !c.no_nee;
    o.adaptive = c.adaptive;
    o.defensive = c.defensive;
    o.primal_fraction = c.primal_fraction;
    return o;
}

std::string path_sampling_name(const Common& c) {
    return c.sampling + " sampling" + (c.no_nee ? "" : " + NEE") + (c.adaptive ? " + adaptive pixels" : "");
}

// The options shared by every psdr run from the command line; the per-term budgets are set by the callers.
PsdrOptions psdr_base(const Scene& scene, const Common& c, int batches, bool antithetic) {
    PsdrOptions o;
    o.interior.batches = batches;
    o.interior.spp = c.spp / batches;
    o.interior.seed = c.seed;
    o.interior.threads = c.threads;
    o.interior.antithetic = antithetic;
    o.interior.path = path_settings(scene);
    o.interior.first_vertex = parse_first_vertex(c.first_vertex);
    o.primary_spp = o.direct_spp = o.indirect_spp = o.pixel_spp = 0;
    o.guiding = !c.no_guiding;
    return o;
}

bool manual_budget(const Common& c) {
    return c.boundary_spp >= 0 || c.primary_spp >= 0 || c.direct_spp >= 0 || c.indirect_spp >= 0 || c.pixel_spp >= 0;
}

// Expert budgets: the interior gets --spp, each boundary term its own flag, else --boundary-spp, else --spp
// (split over the batches).
void set_manual_budget(PsdrOptions& o, const Common& c, int batches) {
    const int fallback = c.boundary_spp >= 0 ? c.boundary_spp : c.spp;
    auto per_batch = [&](int term) {
        const int spp = term >= 0 ? term : fallback;
        return spp > 0 ? std::max(1, spp / batches) : 0;
    };
    o.primary_spp = per_batch(c.primary_spp);
    o.direct_spp = per_batch(c.direct_spp);
    o.indirect_spp = per_batch(c.indirect_spp);
    o.pixel_spp = per_batch(c.pixel_spp);
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
    auto scene = load_scene(c.scene, parse_defines(c.defines));
    Parameters params(*scene);
    std::printf("%-48s %10s  %s\n", "name", "size", "kind");
    for (const Parameter& p : params.all()) {
        const char* kind = p.kind == Parameter::Kind::Data        ? (p.geometry ? "geometry" : "value")
                           : p.kind == Parameter::Kind::Translate ? "motion (direction: world vector)"
                           : p.sensor || p.emitter                ? "motion (direction: world axis; radians)"
                           : p.kind == Parameter::Kind::Rotate
                               ? "motion (direction: world axis; radians; NAME@cx,cy,cz: about that center)"
                               : "motion (uniform scale; NAME@cx,cy,cz: about that center)";
        std::printf("%-48s %10d  %s\n", p.name.c_str(), p.size, kind);
    }
}

// `derivative --method paths`: forward mode of the path sampling estimator.
void cmd_derivative_paths(const Common& c, Scene& scene, Parameters& params) {
    if (c.adaptive && c.adjoint.empty()) throw Error("--adaptive needs --adjoint (the pixel importance |∂L/∂I|)");
    const Image adjoint = c.adjoint.empty() ? Image() : read_image(c.adjoint, false);
    PathSamplingOptions o = path_sampling_options(scene, c, batches_for(c));
    ProgressBar bar(!c.quiet, "derivative");
    o.progress = bar.callback();
    const DerivativeImage d = path_sampling_derivative(scene, params, o, adjoint);
    write_signed(c.output, d.derivative);
    if (!c.stderr_output.empty()) write_image(c.stderr_output, d.stderr_img);
    const Film& film = *scene.sensor->film;
    std::fprintf(stderr, "derivative (path sampling: %s) %dx%d at %d spp in %.2f s, mean %.6g -> %s\n",
                 path_sampling_name(c).c_str(), film.width, film.height, o.spp * o.batches, d.seconds,
                 image_mean(d.derivative), c.output.c_str());
}

void cmd_derivative(const Common& c, bool no_antithetic) {
    check_output(c.output);
    auto scene = load_scene(c.scene, parse_defines(c.defines));
    Parameters params(*scene);
    params.enable(selection(c.params));
    if (c.method == "paths") return cmd_derivative_paths(c, *scene, params);
    const int batches = batches_for(c);
    const bool total = c.method == "psdr";
    PsdrOptions o = psdr_base(*scene, c, batches, !no_antithetic);
    const auto start = std::chrono::steady_clock::now();
    if (total && manual_budget(c)) set_manual_budget(o, c, batches);
    else if (total) {
        if (!c.quiet) std::fprintf(stderr, "calibrating the terms' budgets...\n");
        o = psdr_budget(*scene, params, o, c.spp);
    }
    if (total && !c.quiet) std::fprintf(stderr, "budget: %s%s\n", describe_budget(o).c_str(), manual_budget(c) ? "" : " (calibrated)");
    ProgressBar bar(!c.quiet, "derivative");
    o.interior.progress = bar.callback();
    const PsdrDerivative d = psdr_derivative(*scene, params, o);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    write_signed(c.output, total ? d.total : d.interior.derivative);
    if (!c.stderr_output.empty()) write_image(c.stderr_output, total ? d.total_stderr : d.interior.stderr_img);
    if (!c.terms_prefix.empty()) {
        // Each term's image (and, with --stderr, its standard error as PREFIX_<term>_stderr.exr).
        const auto terms = d.terms();
        for (size_t k = 0; k < terms.size(); ++k) {
            if (k > 0 && !total) break;
            if (k == 4 && !needs_pixel_boundary(*scene, params, o.interior.first_vertex)) continue;
            const std::string name = c.terms_prefix + "_" + PsdrTermNames[k];
            write_signed(name + lower_extension(c.output), *terms[k].first);
            if (!c.stderr_output.empty() && !terms[k].second->pixels.empty()) write_image(name + "_stderr.exr", *terms[k].second);
        }
    }
    if (total && !c.quiet) {
        std::fprintf(stderr, "%-9s %12s %10s %12s %9s\n", "term", "samples", "rays/smp", "tape/smp", "seconds");
        for (size_t k = 0; k < d.cost.size(); ++k) {
            const SampleCost& t = d.cost[k];
            if (t.samples == 0) continue;
            std::fprintf(stderr, "%-9s %12llu %10.2f %12.1f %9.2f\n", PsdrTermNames[k], (unsigned long long)t.samples,
                         double(t.rays) / double(t.samples), double(t.tape_nodes) / double(t.samples), d.seconds[k]);
        }
    }
    const Film& film = *scene->sensor->film;
    std::fprintf(stderr, "derivative (%s, %s first vertex) %dx%d, %d spp in %.2f s, mean %.6g -> %s\n",
                 total ? "interior + boundary terms" : "interior term",
                 image_space_first_vertex(*scene, params, o.interior.first_vertex) ? "image-space" : "material-form",
                 film.width, film.height, c.spp, seconds, image_mean(total ? d.total : d.interior.derivative), c.output.c_str());
}

void cmd_fd(const Common& c, double eps) {
    check_output(c.output);
    auto scene = load_scene(c.scene, parse_defines(c.defines));
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

// `gradient --method paths`: PRB passes 2-3 given an adjoint image, or all three passes given a target image.
Gradient gradient_paths(const Common& c, const Scene& scene, const Parameters& params, nlohmann::json& out) {
    PathSamplingOptions o = path_sampling_options(scene, c, 1);
    ProgressBar bar(!c.quiet, "gradient");
    o.progress = bar.callback();
    out["method"] = "paths: " + path_sampling_name(c);
    if (!c.target.empty()) {
        const LossGradient l = path_sampling_loss_gradient(scene, params, read_image(c.target, false), parse_loss_kind(c.loss), o);
        out["loss"] = l.loss;
        out["seconds_primal"] = l.seconds_primal;
        std::fprintf(stderr, "loss (%s) of the pass-1 image: %.6g\n", c.loss.c_str(), l.loss);
        return {l.values, l.primal, l.seconds, {}};
    }
    const SampledGradient g = path_sampling_gradient(scene, params, read_image(c.adjoint, false), o);
    return {g.values, g.primal, g.seconds, {}};
}

void cmd_gradient(const Common& c) {
    if (c.adjoint.empty() == c.target.empty()) throw Error("gradient: give exactly one of --adjoint and --target");
    if (!c.target.empty() && c.method != "paths") throw Error("gradient: --target needs --method paths");
    if (c.adaptive && c.method != "paths") throw Error("gradient: --adaptive needs --method paths");
    auto scene = load_scene(c.scene, parse_defines(c.defines));
    Parameters params(*scene);
    if (c.params.empty()) params.enable_all_data();
    else params.enable(selection(c.params));
    nlohmann::json out;
    Gradient g;
    if (c.method == "paths") {
        g = gradient_paths(c, *scene, params, out);
    } else {
        const Image adjoint = read_image(c.adjoint, false);
        PsdrOptions o = psdr_base(*scene, c, 1, true);
        if (c.method == "psdr" && manual_budget(c)) {
            set_manual_budget(o, c, 1);
        } else if (c.method == "psdr") {
            if (!c.quiet) std::fprintf(stderr, "calibrating the terms' budgets...\n");
            o = psdr_gradient_budget(*scene, params, adjoint, o, c.spp);
        }
        if (c.method == "psdr") out["budget"] = describe_budget(o);
        ProgressBar bar(!c.quiet, "gradient");
        o.interior.progress = bar.callback();
        g = psdr_gradient(*scene, params, adjoint, o);
    }
    out["seconds"] = g.seconds;
    out["spp"] = c.spp;
    for (const auto& [p, index] : params.enabled()) {
        std::vector<double> values(g.values.begin() + index, g.values.begin() + index + p->size);
        double norm2 = 0;
        for (double v : values) norm2 += v * v;
        out["parameters"].push_back({{"name", p->name}, {"size", p->size}, {"gradient", values}});
        std::printf("%-48s %8d  |dL/dθ| = %.6g\n", p->name.c_str(), p->size, std::sqrt(norm2));
    }
    if (!c.output.empty()) {
        const std::string tmp = c.output + ".tmp";
        {
            std::ofstream file(tmp);
            file << out.dump(1) << "\n";
            if (!file) throw Error("cannot write '" + c.output + "'");
        }
        std::filesystem::rename(tmp, c.output);
    }
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
    auto no_antithetic = std::make_shared<bool>(false);
    auto* d = app.add_subcommand("derivative", "forward mode: the image derivative dI/dθ (interior term)");
    add_common(d, *deriv, true);
    d->add_option("-o,--output", deriv->output, "derivative image (.exr values, .png colormap)")->required();
    d->add_option("--stderr", deriv->stderr_output, "per-pixel standard-error image (.exr)");
    d->add_option("--batches", deriv->batches, "independent batches for --stderr (default 8)")->check(CLI::PositiveNumber);
    d->add_flag("--no-antithetic", *no_antithetic, "disable pixel-level antithetic sampling");
    d->add_option("--terms", deriv->terms_prefix,
                  "also write each term's image as PREFIX_interior / _primary / _direct / _indirect (/ _pixel with a box "
                  "filter and a moving camera), and with --stderr their standard errors as PREFIX_<term>_stderr.exr");
    d->add_option("--adjoint", deriv->adjoint, "--method paths --adaptive: adjoint image ∂L/∂I giving the pixel importance");
    add_method(d, *deriv);
    d->callback([deriv, no_antithetic] { cmd_derivative(*deriv, *no_antithetic); });

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
    auto* g = app.add_subcommand("gradient", "reverse mode: dL/dθ for all parameters given an adjoint image ∂L/∂I "
                                             "(or, with --method paths, a target image and a loss)");
    add_common(g, *grad, false);
    g->add_option("--adjoint", grad->adjoint, "adjoint image ∂L/∂I (.exr, the film's size)");
    g->add_option("--target", grad->target,
                  "--method paths: target image; a primal pass (its own samples) gives the loss and its adjoint");
    g->add_option("--loss", grad->loss, "loss for --target: l2 or rel_l2")->check(CLI::IsMember({"l2", "rel_l2"}));
    g->add_option("--primal-fraction", grad->primal_fraction,
                  "share of --spp spent on the primal pass with --target (default 0.75, the paper's 3:1)")
        ->check(CLI::Range(0.01, 0.99));
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
