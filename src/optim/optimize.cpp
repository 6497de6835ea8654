#include "optim/optimize.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "core/plot.h"
#include "diff/psdr/budget.h"
#include "optim/adam.h"
#include "optim/shape_metrics.h"
#include "render/render.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <span>
#include <sstream>

#include <sys/resource.h>

namespace penumbra {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------------------------------------------
// Configuration
namespace {

std::string type_name(const json& j) { return j.is_number() ? "number" : j.type_name(); }

// Reads the keys of one JSON object; every key must be read, so that a typo is an error, not a default.
class ConfigObject {
  public:
    ConfigObject(const json& j, std::string where, const std::string& source)
        : j_(j), where_(std::move(where)), source_(source) {
        if (!j.is_object()) fail(where_.empty() ? "the configuration" : "'" + where_ + "'", "an object", j);
    }

    const json* find(const std::string& key, bool required) {
        known_.insert(key);
        auto it = j_.find(key);
        if (it == j_.end()) {
            if (required) throw Error(source_ + ": missing key '" + path(key) + "'");
            return nullptr;
        }
        return &*it;
    }
    bool has(const std::string& key) const { return j_.contains(key); }

    double number(const std::string& key, double fallback, bool required = false) {
        const json* v = find(key, required);
        if (!v) return fallback;
        if (!v->is_number()) fail(key, "a number", *v);
        return v->get<double>();
    }
    int64_t integer(const std::string& key, int64_t fallback, int64_t min, bool required = false) {
        const json* v = find(key, required);
        if (!v) return fallback;
        if (!v->is_number_integer()) fail(key, "an integer", *v);
        const int64_t i = v->get<int64_t>();
        if (i < min)
            throw Error(source_ + ": key '" + path(key) + "' must be at least " + std::to_string(min));
        return i;
    }
    std::string string(const std::string& key, const std::string& fallback, bool required = false) {
        const json* v = find(key, required);
        if (!v) return fallback;
        if (!v->is_string()) fail(key, "a string", *v);
        return v->get<std::string>();
    }
    // A number (1 value) or an array of numbers.
    std::vector<float> values(const std::string& key) {
        const json* v = find(key, true);
        std::vector<float> out;
        if (v->is_number()) return {v->get<float>()};
        if (!v->is_array() || v->empty()) fail(key, "a number or a non-empty array of numbers", *v);
        for (const json& e : *v) {
            if (!e.is_number()) fail(key, "an array of numbers", *v);
            out.push_back(e.get<float>());
        }
        return out;
    }

    // Rejects every key that was not read.
    void finish() const {
        for (auto it = j_.begin(); it != j_.end(); ++it)
            if (!known_.count(it.key())) {
                std::string expected;
                for (const std::string& k : known_)
                    expected += (expected.empty() ? "" : ", ") + k;
                throw Error(source_ + ": unknown key '" + path(it.key()) + "' (expected: " + expected + ")");
            }
    }

    std::string path(const std::string& key) const { return where_.empty() ? key : where_ + "." + key; }
    [[noreturn]] void fail(const std::string& key, const std::string& expected, const json& got) const {
        throw Error(source_ + ": key '" + path(key) + "': expected " + expected + ", got " + type_name(got));
    }

  private:
    const json& j_;
    std::string where_;
    const std::string& source_;
    std::set<std::string> known_;
};

std::string resolve(const std::string& base_dir, const std::string& path) {
    return fs::path(path).is_absolute() ? path : (fs::path(base_dir) / path).lexically_normal().string();
}

// A number, an array of numbers, or a mesh file whose vertex positions are the values.
std::vector<float> values_or_mesh(ConfigObject& o, const std::string& key, const std::string& base_dir) {
    const json* v = o.find(key, true);
    if (v->is_string()) return load_vertex_positions(resolve(base_dir, v->get<std::string>()));
    return o.values(key);
}

OptimizedParameter parse_parameter(const std::string& name, const json& j, const std::string& where,
                                   const std::string& source, const std::string& base_dir) {
    ConfigObject o(j, where, source);
    OptimizedParameter p;
    p.name = name;
    if (o.has("init")) p.init = values_or_mesh(o, "init", base_dir);
    p.learning_rate = o.number("lr", 0.0, true);
    if (!(p.learning_rate > 0.0)) throw Error(source + ": key '" + o.path("lr") + "' must be positive");
    if (const json* b = o.find("bounds", false)) {
        if (!b->is_array() || b->size() != 2) o.fail("bounds", "[lower, upper] (numbers or null)", *b);
        for (int k = 0; k < 2; ++k) {
            const json& e = (*b)[size_t(k)];
            if (e.is_null()) continue;
            if (!e.is_number()) o.fail("bounds", "[lower, upper] (numbers or null)", *b);
            (k == 0 ? p.lower : p.upper) = e.get<double>();
        }
        if (!(p.lower <= p.upper)) throw Error(source + ": key '" + o.path("bounds") + "': lower > upper");
    }
    if (const json* f = o.find("free", false)) {
        if (!f->is_array() || f->empty()) o.fail("free", "a non-empty array of booleans", *f);
        for (const json& e : *f) {
            if (!e.is_boolean()) o.fail("free", "an array of booleans", *f);
            p.free.push_back(e.get<bool>());
        }
    }
    if (const json* pz = o.find("parameterization", false)) {
        ConfigObject q(*pz, o.path("parameterization"), source);
        const std::string type = q.string("type", "", true);
        if (type != "large_steps")
            throw Error(source + ": key '" + q.path("type") + "': unknown parameterization '" + type +
                        "' (expected: large_steps)");
        p.large_steps_lambda = q.number("lambda", 19.0);
        if (const json* u = q.find("uniform_adam", false)) {
            if (!u->is_boolean()) q.fail("uniform_adam", "a boolean", *u);
            p.uniform_adam = u->get<bool>();
        }
        if (!(p.large_steps_lambda > 0.0))
            throw Error(source + ": key '" + q.path("lambda") + "' must be positive");
        q.finish();
    }
    o.finish();
    return p;
}

} // namespace

OptimizeConfig parse_optimize_config(const json& j, const std::string& base_dir, const std::string& source) {
    ConfigObject root(j, "", source);
    OptimizeConfig c;
    c.scene = resolve(base_dir, root.string("scene", "", true));
    if (const json* d = root.find("defines", false)) {
        if (!d->is_object()) root.fail("defines", "an object", *d);
        for (auto it = d->begin(); it != d->end(); ++it) {
            if (it->is_string())
                c.defines[it.key()] = it->get<std::string>();
            else if (it->is_number())
                c.defines[it.key()] = it->dump();
            else
                root.fail("defines." + it.key(), "a string or a number", *it);
        }
    }
    const json* params = root.find("parameters", true);
    if (!params->is_object() || params->empty()) root.fail("parameters", "a non-empty object", *params);
    for (auto it = params->begin(); it != params->end(); ++it)
        c.parameters.push_back(parse_parameter(it.key(), *it, "parameters." + it.key(), source, base_dir));

    if (const json* views = root.find("views", false)) c.views = parse_views(*views, base_dir, source);
    c.views_per_iteration = int(root.integer("views_per_iteration", 0, 0));
    const size_t view_images = size_t(std::count_if(
        c.views.begin(), c.views.end(), [](const ViewSpec& v) { return !v.target_image.empty(); }));
    if (view_images > 0 && view_images < c.views.size())
        throw Error(source +
                    ": key 'views': give every view its target 'image', or none (a rendered target)");
    if (view_images > 0) {
        if (root.has("target"))
            throw Error(source + ": key 'target': the views give their target images; remove 'target'");
    } else {
        ConfigObject target(*root.find("target", true), "target", source);
        if (target.has("image") == target.has("values"))
            throw Error(source + ": key 'target' needs exactly one of 'image' or 'values'");
        if (target.has("image")) {
            if (!c.views.empty())
                throw Error(source + ": key 'target.image': with 'views', give each view its target 'image'");
            c.target_image = resolve(base_dir, target.string("image", ""));
        } else {
            ConfigObject values(*target.find("values", true), "target.values", source);
            for (const OptimizedParameter& p : c.parameters)
                if (values.has(p.name)) c.target_values[p.name] = values_or_mesh(values, p.name, base_dir);
            values.finish(); // a target value for a parameter that is not optimized is an error
            c.target_spp = int(target.integer("spp", c.target_spp, 1));
        }
        target.finish();
    }

    c.method = root.string("method", "auto");
    if (c.method != "auto") {
        try {
            find_method(c.method);
        } catch (const Error& e) {
            throw Error(source + ": key 'method': " + e.what());
        }
    }
    for (const char* key : {"primary_spp", "direct_spp", "indirect_spp"})
        if (root.has(key) && c.method != "auto" && c.method != "psdr")
            throw Error(source + ": key '" + key + "' is a boundary-term budget; method '" + c.method +
                        "' has no boundary terms");
    if (root.has("primary_spp") || root.has("direct_spp") || root.has("indirect_spp"))
        for (const std::string term : {"primary", "direct", "indirect"})
            c.method_options.set(term + "-spp", std::to_string(root.integer(term + "_spp", 4, 0)));
    if (const nlohmann::json* options = root.find("options", false)) {
        if (!options->is_object())
            throw Error(source + ": key 'options' must be an object (option name → value)");
        for (const auto& [key, value] : options->items()) {
            std::string name = key;
            std::replace(name.begin(), name.end(), '_', '-');
            if (value.is_string())
                c.method_options.set(name, value.get<std::string>());
            else if (value.is_boolean())
                c.method_options.set(name, value.get<bool>() ? "true" : "false");
            else if (value.is_number())
                c.method_options.set(name, value.dump());
            else
                throw Error(source + ": key 'options." + key + "' must be a string, number or boolean");
        }
    }
    c.loss = parse_loss_kind(root.string("loss", "l2"));
    c.iterations = int(root.integer("iterations", c.iterations, 0));
    c.spp = int(root.integer("spp", c.spp, 1));
    c.gradient_spp = int(root.integer("gradient_spp", c.gradient_spp, 1));
    c.seed = uint64_t(root.integer("seed", 0, 0));
    c.output = root.string("output", c.output);
    c.snapshot_every = int(root.integer("snapshot_every", c.snapshot_every, 0));
    c.lr_decay = root.number("lr_decay", c.lr_decay);
    if (!(c.lr_decay > 0.0 && c.lr_decay <= 1.0)) throw Error(source + ": key 'lr_decay' must be in (0, 1]");
    c.threads = int(root.integer("threads", 0, 0));
    root.finish();
    return c;
}

OptimizeConfig load_optimize_config(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot open optimization config '" + path + "'");
    json j;
    try {
        j = json::parse(in);
    } catch (const json::parse_error& e) {
        throw Error(path + ": invalid JSON: " + e.what());
    }
    return parse_optimize_config(j, fs::path(path).parent_path().string(), path);
}

// ---------------------------------------------------------------------------------------------------------------
// The loop
namespace {

// SplitMix64: independent sample streams for the target, each primal and each gradient.
uint64_t stream_seed(uint64_t seed, uint64_t stream) {
    uint64_t z = seed * 0x9E3779B97F4A7C15ULL + stream + 0x632BE59BD9B4E019ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

// A parameter's values from the config: its size, or (Data only) 1 value broadcast.
std::vector<double> expand(const InverseProblem::Entry& e, const std::vector<float>& v) {
    if (int(v.size()) == e.size) return {v.begin(), v.end()};
    if (v.size() == 1 && e.kind == InverseProblem::Kind::Data)
        return std::vector<double>(size_t(e.size), double(v[0]));
    if (e.kind == InverseProblem::Kind::Translate)
        throw Error("parameter '" + e.name + "' (a translation) takes 3 values [x, y, z]; got " +
                    std::to_string(v.size()));
    if (e.kind == InverseProblem::Kind::Rotate)
        throw Error("parameter '" + e.name +
                    "' (a rotation vector in degrees: axis × angle) takes 3 values; got " +
                    std::to_string(v.size()));
    throw Error("parameter '" + e.name + "' has " + std::to_string(e.size) + " values; got " +
                std::to_string(v.size()));
}

std::vector<double> slice(const std::vector<double>& v, int offset, int size) {
    return {v.begin() + offset, v.begin() + offset + size};
}

Image render_image(const Scene& scene, int spp, uint64_t seed, int threads) {
    RenderOptions options;
    options.spp = spp;
    options.seed = seed;
    options.threads = threads;
    return render(scene, options);
}

std::string snapshot_name(int iteration) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "iter_%04d", iteration);
    return buf;
}

// CSV columns: iteration, loss, parameter_error, translation_error, rotation_error, seconds, dropped_samples
// (the gradient's samples left out for a non-finite value or derivative: the NaN policy), then every
// optimized scalar (rotations as rotation vectors in degrees). The whole file is rewritten atomically after
// each iteration (core/atomic_file.h), so that a reader, or an interrupted run, sees whole lines only.
// Measured on an ext4 disk: 0.24 ms per rewrite after 1000 iterations of 8 columns, 0.8 ms with 64 columns (6
// ms after 10000), against 14 ms for an iteration of a 16x16, 2-spp problem and 120 ms for
// scenes/optimize/config.json.
class CsvLog {
  public:
    CsvLog(const fs::path& path, const InverseProblem& problem) : path_(path.string()) {
        std::ostringstream out;
        out << "iteration,loss,parameter_error,translation_error,rotation_error,seconds,dropped_samples";
        for (const InverseProblem::Entry& e : problem.entries())
            for (int k = 0; k < e.size && listed(e); ++k) {
                // A deformation handle's name holds its center (blob.deform@0.3,0.9,0): quoted (RFC 4180).
                const std::string column = e.name + (e.size > 1 ? "[" + std::to_string(k) + "]" : "");
                out << "," << (column.find(',') == std::string::npos ? column : "\"" + column + "\"");
            }
        out << "\n";
        text_ = out.str();
        write_text_atomically(path_, text_);
    }
    void write(const IterationRecord& r, const std::vector<double>& x, const InverseProblem& problem) {
        std::ostringstream out;
        char buf[128];
        std::snprintf(buf, sizeof(buf), "%d,%.9g", r.iteration, r.loss);
        out << buf;
        for (double error : {r.parameter_error, r.translation_error, r.rotation_error}) {
            out << ",";
            if (std::isfinite(error)) out << std::to_string(error);
        }
        std::snprintf(buf, sizeof(buf), ",%.3f,%llu", r.seconds, (unsigned long long)r.dropped_samples);
        out << buf;
        for (const InverseProblem::Entry& e : problem.entries())
            for (int k = e.offset; k < e.offset + e.size && listed(e); ++k) {
                std::snprintf(buf, sizeof(buf), ",%.7g", x[size_t(k)]);
                out << buf;
            }
        out << "\n";
        text_ += out.str();
        write_text_atomically(path_, text_);
    }
    // A mesh's vertex positions are not listed (its final values are in final_<shape>.ply).
    static bool listed(const InverseProblem::Entry& e) { return e.size <= 64; }

  private:
    std::string path_, text_; // the file's content
};

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(); }

void write_result_json(const fs::path& path, const OptimizeResult& result) {
    json j;
    j["method"] = result.method;
    j["method_description"] = result.description;
    j["final_parameter_error"] = finite_or_null(result.final_parameter_error);
    j["final_translation_error"] = finite_or_null(result.final_translation_error);
    j["final_rotation_error_degrees"] = finite_or_null(result.final_rotation_error);
    j["seconds"] = result.seconds;
    if (!result.history.empty()) j["seconds_per_iteration"] = result.seconds / double(result.history.size());
    j["peak_memory_mb"] = result.peak_memory_mb;
    for (const ShapeResult& r : result.shapes)
        j["shapes"][r.name] = {{"mean_vertex_error", {r.initial_vertex_error, r.final_vertex_error}},
                               {"chamfer_distance", {r.initial_chamfer, r.final_chamfer}}};
    for (const ParameterResult& p : result.parameters) {
        const bool listed = p.final.size() <= 64; // as in log.csv
        json e = listed ? json{{"initial", p.initial}, {"final", p.final}} : json{{"size", p.final.size()}};
        if (!p.truth.empty()) {
            if (listed) e["truth"] = p.truth;
            if (std::isfinite(p.relative_error)) e["relative_error"] = p.relative_error;
            if (std::isfinite(p.pose_error)) e["error"] = p.pose_error;
        }
        j["parameters"][p.name] = e;
    }
    write_text_atomically(path.string(), j.dump(2) + "\n");
}

// loss.png, and parameter_error.png when the true values are known (log-scale y): the relative error of the
// Data parameters, the translation error (scene units) and the rotation error (degrees), those that exist.
void write_curves(const fs::path& out, const OptimizeConfig& config, const OptimizeResult& result) {
    if (result.history.empty()) return;
    PlotSeries loss{"loss (" + loss_kind_name(config.loss) + ")", {}, {}};
    PlotSeries data{"parameter error (relative)", {}, {}},
        translation{"translation error (scene units)", {}, {}}, rotation{"rotation error (degrees)", {}, {}};
    for (const IterationRecord& r : result.history) {
        loss.x.push_back(r.iteration), loss.y.push_back(r.loss);
        data.x.push_back(r.iteration), data.y.push_back(r.parameter_error);
        translation.x.push_back(r.iteration), translation.y.push_back(r.translation_error);
        rotation.x.push_back(r.iteration), rotation.y.push_back(r.rotation_error);
    }
    write_plot((out / "loss.png").string(), {loss},
               {"Inverse rendering: loss", "iteration", "loss", true, 720, 440});
    std::vector<PlotSeries> errors;
    if (std::isfinite(result.final_parameter_error)) errors.push_back(data);
    if (std::isfinite(result.final_translation_error)) errors.push_back(translation);
    if (std::isfinite(result.final_rotation_error)) errors.push_back(rotation);
    if (!errors.empty())
        write_plot((out / "parameter_error.png").string(), errors,
                   {"Inverse rendering: parameter error", "iteration", "error", true, 720, 440});
}

// Seed of a sample stream of view v: the single-view streams for v = 0, independent ones for the others.
uint64_t view_stream(uint64_t seed, uint64_t stream, size_t view) {
    return view == 0 ? stream_seed(seed, stream) : stream_seed(stream_seed(seed, stream), view);
}

// `base.png` for the scene's sensor alone, `base_<view>.png` with several views.
std::string view_file(const std::string& base, const std::string& ext, const OptimizeConfig& config,
                      const ViewSelector& views, size_t v) {
    return config.views.empty() ? base + ext : base + "_" + views.view(v).name + ext;
}

double peak_memory_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0; // kilobytes on Linux
}

// The shape's name: the parameter's without ".vertex_positions".
std::string shape_of(const std::string& parameter) {
    const size_t dot = parameter.rfind('.');
    return dot == std::string::npos ? parameter : parameter.substr(0, dot);
}

// What an optimization has completely written so far: what an interrupted run reports (every file is written
// atomically, so these are whole; files of an earlier run in the same directory may remain).
struct OutputsSoFar {
    std::string directory;
    int iterations = 0;
    int logged = -1; // the iterations in log.csv (-1: no log.csv yet)
    int last_snapshot = -1;
    size_t targets = 0;
    bool finishing = false; // the iterations are done; the final renders and files are being written

    std::string describe() const {
        std::string s = "complete in " + directory + ": ";
        if (targets > 0) s += "the targets (.exr, .png) of " + std::to_string(targets) + " view(s), ";
        if (logged < 0)
            s += "no log.csv yet";
        else if (logged == 0)
            s += "log.csv (header only)";
        else
            s += "log.csv (iterations 0-" + std::to_string(logged - 1) + " of " + std::to_string(iterations) +
                 ")";
        if (last_snapshot >= 0) s += ", snapshots up to " + snapshot_name(last_snapshot);
        s += finishing ? "; not all of the final images, meshes, result.json and plots were written"
                       : "; no final image, mesh, result.json or plot of this run";
        return s;
    }
};

OptimizeResult run_optimization(const OptimizeConfig& config,
                                const std::function<void(const IterationRecord&)>& on_iteration,
                                OutputsSoFar& written) {
    auto scene = load_scene(config.scene, config.defines);
    InverseProblem problem(*scene, config.parameters);
    // The scene's own sensor alone, or the configured views (optim/views.h).
    ViewSelector views(*scene, config.views.empty() ? std::vector<ViewSpec>{ViewSpec{}} : config.views);
    OptimizeResult result;
    if (config.method == "interior" && problem.geometric())
        throw Error(
            "method 'interior' cannot optimize a pose: the interior term alone has no silhouette or "
            "shadow-edge (boundary) terms, so its pose gradient is biased; use method 'psdr' (or 'auto')");
    result.method = config.method != "auto" ? config.method : problem.geometric() ? "psdr" : "interior";
    // Method auto without a pose: the interior term alone (psdr's budget keys, if given, do not apply).
    const std::unique_ptr<DerivativeMethod> method = make_method(
        result.method,
        config.method == "auto" && result.method == "interior" ? MethodOptions() : config.method_options);

    // Truth and initial values, in the problem's layout (poses: 0 = the scene's pose).
    std::vector<double> truth = problem.scene_values(), x = truth;
    for (size_t i = 0; i < config.parameters.size(); ++i) {
        const OptimizedParameter& op = config.parameters[i];
        const InverseProblem::Entry& e = problem.entries()[i];
        if (auto it = config.target_values.find(op.name); it != config.target_values.end()) {
            const std::vector<double> v = expand(e, it->second);
            std::copy(v.begin(), v.end(), truth.begin() + e.offset);
        }
        if (!op.init.empty()) {
            const std::vector<double> v = expand(e, op.init);
            std::copy(v.begin(), v.end(), x.begin() + e.offset);
        }
    }
    Adam adam(problem.adam_groups(), problem.dimension());
    adam.project(x);
    const std::vector<double> x_initial = x;

    fs::create_directories(config.output);
    const fs::path out(config.output);
    const bool known_truth = config.target_image.empty() && views.view(0).target_image.empty();

    // Targets, one per view: an image, or the scene at the true values rendered with many samples (stream 0).
    std::vector<Image> targets;
    const auto target_start = std::chrono::steady_clock::now();
    if (known_truth) problem.set_values(truth);
    for (size_t v = 0; v < views.size(); ++v) {
        views.select(v);
        if (known_truth) {
            targets.push_back(
                render_image(*scene, config.target_spp, view_stream(config.seed, 0, v), config.threads));
            write_image((out / view_file("target", ".exr", config, views, v)).string(), targets.back());
            write_image((out / view_file("target", ".png", config, views, v)).string(), targets.back());
            ++written.targets;
            continue;
        }
        const std::string& path = config.views.empty() ? config.target_image : views.view(v).target_image;
        targets.push_back(read_image(path));
        if (targets.back().width != views.width(v) || targets.back().height != views.height(v))
            throw Error("view '" + views.view(v).name + "': the target image '" + path + "' is " +
                        std::to_string(targets.back().width) + "x" + std::to_string(targets.back().height) +
                        ", the view's film " + std::to_string(views.width(v)) + "x" +
                        std::to_string(views.height(v)));
    }
    result.target_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - target_start).count();
    problem.set_values(x);

    // Shapes (vertex_positions) against their known target, at the start (Chamfer: optim/shape_metrics.h).
    auto shape_errors = [&](bool initial) {
        for (size_t i = 0; i < problem.entries().size() && known_truth; ++i) {
            const InverseProblem::Entry& e = problem.entries()[i];
            if (!e.shape) continue;
            if (initial) result.shapes.push_back({shape_of(e.name), 0, 0, 0, 0});
            ShapeResult& r = *std::find_if(result.shapes.begin(), result.shapes.end(),
                                           [&](const ShapeResult& s) { return s.name == shape_of(e.name); });
            const std::vector<double> now = problem.values();
            const std::span<const double> a(now.data() + e.offset, size_t(e.size)),
                b(truth.data() + e.offset, size_t(e.size));
            (initial ? r.initial_vertex_error : r.final_vertex_error) = mean_vertex_error(a, b);
            (initial ? r.initial_chamfer : r.final_chamfer) = chamfer_distance(a, b);
        }
    };
    shape_errors(true);

    MethodRun run;
    run.spp = config.gradient_spp;
    run.threads = config.threads;
    CsvLog log(out / "log.csv", problem);
    written.logged = 0;
    const auto start = std::chrono::steady_clock::now();
    auto elapsed = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    auto record_at = [&](int it, double loss) {
        IterationRecord r{it, loss, NAN, NAN, NAN, 0.0};
        if (known_truth) {
            r.parameter_error = problem.data_error(truth);
            r.translation_error = problem.translation_error(truth);
            r.rotation_error = problem.rotation_error(truth);
        }
        return r;
    };

    for (int it = 0; it < config.iterations; ++it) {
        check_interrupt();
        // Per view: the primal (stream 2i+1) gives the loss and the adjoint ∂L/∂I; the gradient uses
        // independent samples (stream 2i+2): for a nonlinear loss, E[∂L/∂I(Î)] · E[dÎ/dθ] is unbiased only if
        // the two are independent. Loss and gradient are the means over the iteration's views.
        const std::vector<size_t> subset =
            views_of_iteration(views.size(), config.views_per_iteration, config.seed, it);
        double loss_sum = 0;
        uint64_t dropped = 0;
        std::vector<double> gradient(size_t(problem.dimension()), 0.0);
        for (size_t v : subset) {
            views.select(v);
            std::string* description = it == 0 && v == subset[0] ? &result.description : nullptr;
            std::vector<double> g;
            Image primal;
            if (config.loss == LossKind::Matching) {
                // The method matches its paths to the target and differentiates them in one call.
                run.seed = view_stream(config.seed, 2 * uint64_t(it) + 2, v);
                Gradient mg;
                g = problem.loss_gradient(targets[v], config.loss, *method, run, mg, description);
                loss_sum += mg.loss;
                dropped += mg.cost.dropped;
                primal = mg.primal;
            } else {
                primal = render_image(*scene, config.spp, view_stream(config.seed, 2 * uint64_t(it) + 1, v),
                                      config.threads);
                const LossResult loss = compute_loss(config.loss, primal, targets[v]);
                loss_sum += loss.value;
                run.seed = view_stream(config.seed, 2 * uint64_t(it) + 2, v);
                uint64_t view_dropped = 0;
                g = problem.gradient(loss.adjoint, *method, run, description, &view_dropped);
                dropped += view_dropped;
            }
            if (config.snapshot_every > 0 && it % config.snapshot_every == 0 && primal.width > 0) {
                write_image((out / view_file(snapshot_name(it), ".png", config, views, v)).string(), primal);
                written.last_snapshot = it;
            }
            for (size_t k = 0; k < g.size(); ++k)
                gradient[k] += g[k] / double(subset.size());
            if (const auto bad = std::find_if(g.begin(), g.end(), [](double d) { return !std::isfinite(d); });
                bad != g.end())
                throw Error("iteration " + std::to_string(it) + ", view '" + views.view(v).name +
                            "': method '" + result.method + "' returned a non-finite gradient (scalar " +
                            std::to_string(bad - g.begin()) + ")");
        }
        IterationRecord record = record_at(it, loss_sum / double(subset.size()));
        record.dropped_samples = dropped;
        // Exponential schedule: the rates fall to lr_decay × lr at the last iteration.
        const double lr_scale =
            config.iterations > 1 ? std::pow(config.lr_decay, double(it) / (config.iterations - 1)) : 1.0;
        const std::vector<double> x_before = problem.values();
        problem.adam_step(adam, gradient, lr_scale);

        record.seconds = elapsed();
        log.write(record, x_before, problem);
        written.logged = it + 1;
        result.history.push_back(record);
        if (on_iteration) on_iteration(record);
    }
    result.seconds = elapsed();
    written.finishing = true;

    for (size_t v = 0; v < views.size(); ++v) {
        views.select(v);
        write_image((out / view_file("final", ".png", config, views, v)).string(),
                    render_image(*scene, config.spp,
                                 view_stream(config.seed, 2 * uint64_t(config.iterations) + 1, v),
                                 config.threads));
    }
    const std::vector<double> x_final = problem.values();
    for (size_t i = 0; i < problem.entries().size(); ++i) {
        const InverseProblem::Entry& e = problem.entries()[i];
        ParameterResult pr{
            e.name, slice(x_initial, e.offset, e.size), slice(x_final, e.offset, e.size), {}, NAN, NAN};
        if (known_truth) {
            pr.truth = slice(truth, e.offset, e.size);
            if (e.kind == InverseProblem::Kind::Data)
                pr.relative_error = relative_distance(pr.final, pr.truth);
            else
                pr.pose_error = problem.entry_error(i, truth);
        }
        if (e.shape)
            write_ply_mesh((out / ("final_" + shape_of(e.name) + ".ply")).string(), pr.final,
                           e.shape->mesh.indices);
        result.parameters.push_back(std::move(pr));
    }
    if (known_truth) {
        result.final_parameter_error = problem.data_error(truth);
        result.final_translation_error = problem.translation_error(truth);
        result.final_rotation_error = problem.rotation_error(truth);
    }
    shape_errors(false);
    result.peak_memory_mb = peak_memory_mb();
    write_result_json(out / "result.json", result);

    write_curves(out, config, result);
    return result;
}

} // namespace

OptimizeResult optimize(const OptimizeConfig& config,
                        const std::function<void(const IterationRecord&)>& on_iteration) {
    OutputsSoFar written{config.output, config.iterations};
    try {
        return run_optimization(config, on_iteration, written);
    } catch (const Interrupted&) {
        throw Interrupted(written.describe());
    }
}

} // namespace penumbra
