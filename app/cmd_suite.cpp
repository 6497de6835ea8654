// `penumbra ad-suite`: psdr's derivatives on the Mitsuba differentiable-rendering test suite (studies/ad_suite.h,
// scenes/mitsuba_ad/suite.json) against finite-difference references kept in a cache directory: per scene relerr,
// relerr4, the reference's own noise, the z-score of the image mean and the times, as a markdown table.
#include "cli.h"

#include "core/atomic_file.h"
#include "core/colormap.h"
#include "core/error.h"
#include "scene/scene.h"
#include "studies/ad_suite.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace penumbra::cli {

namespace {

namespace fs = std::filesystem;

// Independent random numbers for the derivative and its reference (z-scores assume independence).
constexpr uint64_t DerivativeSeed = 1, ReferenceSeed = 2;

struct SuiteOptions {
    std::string manifest = "scenes/mitsuba_ad/suite.json";
    int res = 0; // 0: the manifest's
    std::vector<std::string> only, defines;
    double fd_spp_scale = 1.0;
    std::string cache = "ad-suite-cache";
    int threads = 0;
    std::string output;
    bool quiet = false;
    bool fd_only = false; // compute and cache the references, no derivatives
};

struct Row {
    std::string name;
    int spp = 0;
    std::string skipped; // why the scene did not run (empty: it ran)
    AdSuiteScore score;
    double interior_relerr4 = 0; // the interior term alone: what the boundary terms add
    double derivative_seconds = 0, fd_seconds = 0;
    bool fd_cached = false;
};

struct Reference {
    FiniteDifference fd;
    bool cached = false;
};

// The reference from the cache when everything it depends on matches, else computed and stored.
Reference cached_reference(const SuiteOptions& o, const AdSuiteScene& s, AdSuiteCase& c, int res, double h, int spp) {
    if (auto fd = read_cached_reference(o.cache, s, res, h, spp, o.defines, ReferenceSeed)) return {*fd, true};
    ProgressBar bar(!o.quiet, s.name + " fd");
    Reference r{suite_reference(*c.scene, *c.params, h, spp, ReferenceSeed, o.threads, bar.callback()), false};
    write_cached_reference(o.cache, s, res, h, spp, o.defines, ReferenceSeed, r.fd);
    return r;
}

Row run_scene(const SuiteOptions& o, const AdSuite& suite, const AdSuiteScene& s, int res) {
    Row row;
    row.name = s.name;
    row.spp = s.spp;
    const std::vector<std::string> missing = missing_files(s);
    if (!missing.empty()) {
        if (!s.optional) throw Error("ad-suite: scene '" + s.name + "' needs '" + missing[0] + "', which does not exist");
        row.skipped = "skipped: " + missing[0] + " is absent";
        return row;
    }
    AdSuiteCase c = load_case(s, res, parse_defines(o.defines));
    const FdSettings settings = fd_settings(suite, s, res);
    const int fd_spp = square_reference_spp(settings.spp * o.fd_spp_scale);
    if (!o.quiet) std::fprintf(stderr, "%s: reference (h = %g, %d spp per side)\n", s.name.c_str(), settings.eps, fd_spp);
    const Reference ref = cached_reference(o, s, c, res, settings.eps, fd_spp);
    row.fd_seconds = ref.fd.seconds;
    row.fd_cached = ref.cached;
    if (o.fd_only) {
        row.skipped = "reference only (" + std::to_string(int(std::lround(ref.fd.seconds))) + " s" +
                      (ref.cached ? ", cached)" : ")");
        return row;
    }

    if (!o.quiet) std::fprintf(stderr, "%s: derivative (%d spp, psdr_budget split)\n", s.name.c_str(), s.spp);
    ProgressBar bar(!o.quiet, s.name + " derivative");
    const auto start = std::chrono::steady_clock::now();
    const DerivativeImage d =
        suite_derivative(*c.scene, *c.params, s.spp, DerivativeSeed, o.threads, bar.callback());
    row.derivative_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    row.score = score(d.derivative, d.stderr_img, ref.fd);
    const DerivativeTerm& interior = d.term("interior");
    row.interior_relerr4 = score(interior.derivative, interior.stderr_img, ref.fd).blocks.relerr;

    // Pictures on one color scale (the reference's), and the values for `penumbra compare`.
    const std::string base = (fs::path(o.cache) / s.name).string();
    const float scale = robust_scale(ref.fd.derivative);
    write_signed(base + "_derivative.png", d.derivative, scale);
    write_signed(base + "_fd.png", ref.fd.derivative, scale);
    write_z_map(base + "_z.png", d.derivative, ref.fd.derivative, d.stderr_img, ref.fd.stderr_img);
    write_image(base + "_derivative.exr", d.derivative);
    write_image(base + "_derivative_stderr.exr", d.stderr_img);
    return row;
}

std::string table_header() {
    return "| scene | spp | relerr | relerr4 | noise4 | ref noise4 | z (mean) | interior-only relerr4 | derivative s | FD s |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
}

std::string table_row(const Row& r) {
    char line[512];
    if (!r.skipped.empty()) {
        std::snprintf(line, sizeof line, "| %s | %d | %s | | | | | | | |\n", r.name.c_str(), r.spp, r.skipped.c_str());
        return line;
    }
    std::snprintf(line, sizeof line, "| %s | %d | %.4f | %.4f | %.4f | %.4f | %+.2f | %.4f | %.1f | %.1f%s |\n",
                  r.name.c_str(), r.spp, r.score.full.relerr, r.score.blocks.relerr, r.score.blocks.noise_relerr,
                  r.score.reference_noise4, r.score.full.mean_z, r.interior_relerr4, r.derivative_seconds, r.fd_seconds,
                  r.fd_cached ? " (cached)" : "");
    return line;
}

std::string legend(const SuiteOptions& o, int res) {
    std::string filter = "box";
    for (const auto& [name, value] : parse_defines(o.defines))
        if (name == "filter") filter = value;
    return "penumbra ad-suite (" + o.manifest + ") at " + std::to_string(res) + "x" + std::to_string(res) + ", " +
           filter + " filter. Derivative: psdr at the scene's Mitsuba spp in total, split by psdr_budget (" +
           std::to_string(AdSuiteDerivativeBatches) + " batches); reference: central differences with common random "
           "numbers (" + std::to_string(AdSuiteReferenceBatches) + " batches). relerr = Σ|D−R|/Σ|R|; relerr4 after "
           "4x4 block averaging; noise4 = relerr4 expected from both estimators' noise, ref noise4 from the "
           "reference's alone; z = z-score of the image mean; interior-only relerr4: the same without the boundary "
           "terms.\n\n";
}

void cmd_suite(const SuiteOptions& o) {
    const std::string ext = lower_extension(o.output);
    if (!o.output.empty() && ext != ".md") throw Error("ad-suite: output '" + o.output + "' must end in .md");
    const AdSuite suite = load_ad_suite(o.manifest);
    for (const std::string& name : o.only) {
        bool known = false;
        for (const AdSuiteScene& s : suite.scenes) known = known || s.name == name;
        if (!known) {
            std::string names;
            for (const AdSuiteScene& s : suite.scenes) names += (names.empty() ? "" : ", ") + s.name;
            throw Error("ad-suite: --only: no scene '" + name + "' in " + o.manifest + " (scenes: " + names + ")");
        }
    }
    const int res = o.res > 0 ? o.res : suite.res;
    fs::create_directories(o.cache);
    std::string report = legend(o, res) + table_header();
    std::printf("%s", report.c_str());
    for (const AdSuiteScene& s : suite.scenes) {
        if (!o.only.empty() && std::find(o.only.begin(), o.only.end(), s.name) == o.only.end()) continue;
        const std::string row = table_row(run_scene(o, suite, s, res));
        std::printf("%s", row.c_str());
        std::fflush(stdout);
        report += row;
    }
    if (!o.output.empty()) write_text_atomically(o.output, report);
    if (!o.quiet) std::fprintf(stderr, "images and references in %s%s%s\n", o.cache.c_str(), o.output.empty() ? "" : ", table in ",
                               o.output.c_str());
}

} // namespace

void add_suite_command(CLI::App& app) {
    auto o = std::make_shared<SuiteOptions>();
    auto* cmd = app.add_subcommand("ad-suite", "derivative accuracy on the Mitsuba differentiable-rendering test suite "
                                               "(scenes/mitsuba_ad) against cached finite differences");
    cmd->add_option("--manifest", o->manifest, "suite manifest (default scenes/mitsuba_ad/suite.json)");
    cmd->add_option("--res", o->res, "film resolution (default: the manifest's, 128)")->check(CLI::PositiveNumber);
    cmd->add_option("--only", o->only, "run only these scenes: NAME,...")->delimiter(',');
    cmd->add_option("--fd-spp-scale", o->fd_spp_scale, "multiply every reference's sample count (rounded to a square number per batch; default 1)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--cache", o->cache,
                    "directory of the reference cache and of each scene's derivative, reference and z-map images "
                    "(default ad-suite-cache)");
    cmd->add_option("-D", o->defines, "override a <default> value of every scene: name=value (e.g. filter=gaussian)");
    cmd->add_option("--threads", o->threads, "worker threads (default: all)")->check(CLI::NonNegativeNumber);
    cmd->add_option("-o,--output", o->output, "write the table as markdown (.md)");
    cmd->add_flag("--fd-only", o->fd_only,
                  "compute and cache the finite-difference references only (tests may read a committed cache, "
                  "e.g. scenes/validation/media_fd)");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress output");
    cmd->callback([o] { cmd_suite(*o); });
}

} // namespace penumbra::cli
