#include "studies/ad_suite.h"

#include "core/atomic_file.h"
#include "diff/psdr/budget.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <cstdio>

namespace penumbra {

namespace fs = std::filesystem;

namespace {

template <typename T> T field(const nlohmann::json& entry, const char* key, const std::string& where) {
    if (!entry.contains(key)) throw Error(where + ": missing field '" + key + "'");
    try {
        return entry.at(key).get<T>();
    } catch (const nlohmann::json::exception&) {
        throw Error(where + ": field '" + key + "' has the wrong type (" + entry.at(key).dump() + ")");
    }
}

int reference_spp(const nlohmann::json& entry, const char* key, const std::string& where) {
    const int spp = field<int>(entry, key, where);
    if (spp <= 0 || spp != square_reference_spp(spp))
        throw Error(where + ": field '" + key + "' must be " + std::to_string(AdSuiteReferenceBatches) +
                    " k² (a square number of samples per batch, for stratification), e.g. " +
                    std::to_string(square_reference_spp(std::max(spp, 1))));
    return spp;
}

// As with scene files, a misspelt field is an error rather than a silent default.
void reject_unknown(const nlohmann::json& object, std::initializer_list<const char*> known, const std::string& where) {
    for (auto it = object.begin(); it != object.end(); ++it)
        if (std::none_of(known.begin(), known.end(), [&](const char* k) { return it.key() == k; }))
            throw Error(where + ": unknown field '" + it.key() + "'");
}

template <typename T> T positive(T value, const char* key, const std::string& where) {
    if (!(value > T(0))) throw Error(where + ": field '" + key + "' must be positive");
    return value;
}

} // namespace

AdSuite load_ad_suite(const std::string& manifest) {
    std::ifstream file(manifest);
    if (!file) throw Error("ad-suite: cannot read the manifest '" + manifest + "'");
    nlohmann::json root;
    try {
        root = nlohmann::json::parse(file);
    } catch (const nlohmann::json::parse_error& e) {
        throw Error(manifest + ": " + e.what());
    }
    const fs::path dir = fs::path(manifest).parent_path();
    reject_unknown(root, {"about", "res", "scenes"}, manifest);
    AdSuite suite;
    suite.res = positive(field<int>(root, "res", manifest), "res", manifest);
    for (const nlohmann::json& entry : field<nlohmann::json>(root, "scenes", manifest)) {
        const std::string where = manifest + ": scene " + std::to_string(suite.scenes.size() + 1);
        AdSuiteScene s;
        s.name = field<std::string>(entry, "name", where);
        const std::string named = where + " (" + s.name + ")";
        reject_unknown(entry, {"name", "file", "params", "spp", "fd_eps", "fd_spp", "ci_res", "ci_fd_eps", "ci_fd_spp",
                               "optional", "requires", "fd_note"},
                       named);
        for (const AdSuiteScene& other : suite.scenes)
            if (other.name == s.name) throw Error(named + ": a scene of this name comes earlier");
        s.file = (dir / field<std::string>(entry, "file", named)).string();
        s.params = field<std::vector<std::string>>(entry, "params", named);
        if (s.params.empty()) throw Error(named + ": 'params' is empty");
        s.spp = positive(field<int>(entry, "spp", named), "spp", named);
        s.fd_eps = positive(field<double>(entry, "fd_eps", named), "fd_eps", named);
        s.fd_spp = reference_spp(entry, "fd_spp", named);
        s.ci_res = positive(field<int>(entry, "ci_res", named), "ci_res", named);
        s.ci_fd_eps = positive(field<double>(entry, "ci_fd_eps", named), "ci_fd_eps", named);
        s.ci_fd_spp = reference_spp(entry, "ci_fd_spp", named);
        s.optional = field<bool>(entry, "optional", named);
        if (entry.contains("requires"))
            for (const std::string& f : field<std::vector<std::string>>(entry, "requires", named))
                s.requires_files.push_back((dir / f).lexically_normal().string());
        suite.scenes.push_back(std::move(s));
    }
    if (suite.scenes.empty()) throw Error(manifest + ": no scenes");
    return suite;
}

std::vector<std::string> missing_files(const AdSuiteScene& scene) {
    std::vector<std::string> missing;
    for (const std::string& f : scene.requires_files)
        if (!fs::exists(f)) missing.push_back(f);
    return missing;
}

FdSettings fd_settings(const AdSuite& suite, const AdSuiteScene& scene, int res) {
    if (res == suite.res) return {scene.fd_eps, scene.fd_spp};
    if (res == scene.ci_res) return {scene.ci_fd_eps, scene.ci_fd_spp};
    return {scene.fd_eps * double(suite.res) / double(res), scene.fd_spp};
}

AdSuiteCase load_case(const AdSuiteScene& scene, int res, std::map<std::string, std::string> defines) {
    defines["res"] = std::to_string(res);
    AdSuiteCase c;
    c.scene = load_scene(scene.file, defines);
    c.params = std::make_unique<Parameters>(*c.scene);
    std::vector<std::pair<std::string, std::vector<float>>> selection;
    for (const std::string& p : scene.params) selection.push_back(parse_param_selection(p));
    c.params->enable(selection);
    return c;
}

int square_reference_spp(double spp) {
    const int k = std::max(1, int(std::lround(std::sqrt(spp / AdSuiteReferenceBatches))));
    return AdSuiteReferenceBatches * k * k;
}

DerivativeImage suite_derivative(const Scene& scene, const Parameters& params, int spp, uint64_t seed,
                                 int threads, std::function<void(float)> progress) {
    PsdrOptions base;
    base.interior.batches = AdSuiteDerivativeBatches;
    base.interior.seed = seed;
    base.interior.threads = threads;
    base.interior.path = path_settings(scene);
    base.interior.progress = std::move(progress);
    return psdr_derivative(scene, params, psdr_budget(scene, params, base, spp));
}

FiniteDifference suite_reference(Scene& scene, Parameters& params, double h, int spp, uint64_t seed, int threads,
                                 std::function<void(float)> progress) {
    if (spp < AdSuiteReferenceBatches)
        throw Error("ad-suite: the reference needs at least " + std::to_string(AdSuiteReferenceBatches) +
                    " samples per pixel (one per batch), got " + std::to_string(spp));
    RenderOptions o;
    o.spp = spp / AdSuiteReferenceBatches;
    o.seed = seed;
    o.threads = threads;
    o.progress = std::move(progress);
    return finite_difference(scene, params, h, o, AdSuiteReferenceBatches);
}

AdSuiteScore score(const Image& derivative, const Image& derivative_stderr, const FiniteDifference& reference) {
    const Image r4 = block_average(reference.derivative, 4), r4_se = block_average_stderr(reference.stderr_img, 4);
    AdSuiteScore s;
    s.full = compare_images(derivative, reference.derivative, derivative_stderr, reference.stderr_img);
    s.blocks = compare_images(block_average(derivative, 4), r4, block_average_stderr(derivative_stderr, 4), r4_se);
    s.reference_noise4 = compare_images(r4, r4, r4_se).noise_relerr;
    return s;
}

namespace {

std::string read_text(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw Error("cannot read '" + path + "'");
    std::ostringstream s;
    s << file.rdbuf();
    return s.str();
}

// FNV-1a: a stable hash of the scene file, so that an edited scene invalidates its cached reference.
std::string content_hash(const std::string& bytes) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ULL;
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
    return hex;
}

nlohmann::json reference_key(const AdSuiteScene& scene, int res, double h, int spp,
                             const std::vector<std::string>& defines, uint64_t seed) {
    return {{"scene_fnv1a", content_hash(read_text(scene.file))}, {"res", res}, {"eps", h}, {"spp", spp},
            {"params", scene.params}, {"defines", defines}, {"batches", AdSuiteReferenceBatches}, {"seed", seed}};
}

std::string cache_base(const std::string& cache, const AdSuiteScene& scene) {
    return (fs::path(cache) / scene.name).string();
}

} // namespace

std::optional<FiniteDifference> read_cached_reference(const std::string& cache, const AdSuiteScene& scene, int res,
                                                      double h, int spp, const std::vector<std::string>& defines,
                                                      uint64_t seed) {
    const std::string base = cache_base(cache, scene);
    const std::string key_path = base + "_fd.json", value_path = base + "_fd.exr", se_path = base + "_fd_stderr.exr";
    if (!fs::exists(key_path) || !fs::exists(value_path) || !fs::exists(se_path)) return std::nullopt;
    const nlohmann::json stored = nlohmann::json::parse(read_text(key_path), nullptr, false);
    if (stored.is_discarded() || stored.value("key", nlohmann::json()) != reference_key(scene, res, h, spp, defines, seed))
        return std::nullopt;
    return FiniteDifference{read_image(value_path, false), read_image(se_path, false), stored.value("seconds", 0.0)};
}

void write_cached_reference(const std::string& cache, const AdSuiteScene& scene, int res, double h, int spp,
                            const std::vector<std::string>& defines, uint64_t seed, const FiniteDifference& fd) {
    const std::string base = cache_base(cache, scene);
    write_image(base + "_fd.exr", fd.derivative);
    write_image(base + "_fd_stderr.exr", fd.stderr_img);
    const nlohmann::json key{{"key", reference_key(scene, res, h, spp, defines, seed)},
                             {"seconds", fd.seconds}};
    write_text_atomically(base + "_fd.json", key.dump(1) + "\n");
}

} // namespace penumbra
