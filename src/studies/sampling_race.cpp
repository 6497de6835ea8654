#include "studies/sampling_race.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/plot.h"
#include "core/rng.h"
#include "diff/paths/path_sampling.h"
#include "optim/adam.h"
#include "render/render.h"
#include "scene/integrator_settings.h"
#include "studies/variance_study.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace penumbra {

namespace {

namespace fs = std::filesystem;

double parameter_error(const std::vector<float>& x, const std::vector<float>& truth) {
    double s = 0;
    for (size_t k = 0; k < x.size(); ++k) {
        const double r = (double(x[k]) - double(truth[k])) / double(truth[k]);
        s += r * r;
    }
    return std::sqrt(s / double(x.size()));
}

void write_csv(const std::string& path, const SamplingRaceResult& result) {
    std::ostringstream out;
    out << "method,spp,iteration,seconds,loss,parameter_error";
    for (const std::string& p : result.parameters) out << "," << p;
    out << "\n";
    for (const RaceMethod& m : result.methods)
        for (const RaceRecord& r : m.history) {
            out << m.name << "," << m.spp << "," << r.iteration << "," << r.seconds << "," << r.loss << "," << r.parameter_error;
            for (float v : r.values) out << "," << v;
            out << "\n";
        }
    write_text_atomically(path, out.str());
}

// Loss (top) and parameter error (bottom) against estimator time, both methods on each chart, one PNG.
void write_race_plot(const std::string& path, const SamplingRaceResult& result) {
    std::vector<PlotSeries> loss, error;
    for (const RaceMethod& m : result.methods) {
        PlotSeries l{m.name, {}, {}}, e{m.name, {}, {}};
        for (const RaceRecord& r : m.history) {
            l.x.push_back(r.seconds), l.y.push_back(r.loss);
            e.x.push_back(r.seconds), e.y.push_back(r.parameter_error);
        }
        loss.push_back(std::move(l));
        error.push_back(std::move(e));
    }
    const Image top = plot_lines(loss, {"Equal-time inverse rendering: loss", "estimator CPU time (s)", "loss", true, 720, 400});
    const Image bottom = plot_lines(error, {"Parameter error (relative RMS)", "estimator CPU time (s)", "error", true, 720, 400});
    Image both(top.width, top.height + bottom.height);
    std::copy(top.pixels.begin(), top.pixels.end(), both.pixels.begin());
    std::copy(bottom.pixels.begin(), bottom.pixels.end(), both.pixels.begin() + std::ptrdiff_t(top.pixels.size()));
    write_image(path, both);
}

} // namespace

SamplingRaceResult sampling_race(Scene& scene, const SamplingRaceOptions& o) {
    if (o.parameters.empty()) throw Error("sampling race: no parameter to recover");
    if (o.initial.size() != o.parameters.size())
        throw Error("sampling race: " + std::to_string(o.parameters.size()) + " parameters but " +
                    std::to_string(o.initial.size()) + " initial values");
    if (o.iterations < 1 || o.spp < 1 || o.target_spp < 1 || o.eval_spp < 1 || o.calibration_runs < 1)
        throw Error("sampling race: iterations, spp, target_spp, eval_spp and calibration_runs must be positive");
    if (!(o.learning_rate > 0) || !(o.lower < o.upper)) throw Error("sampling race: bad learning rate or bounds");
    Parameters params(scene);
    std::vector<std::pair<std::string, std::vector<float>>> selection;
    for (const std::string& name : o.parameters) selection.push_back({name, {}});
    params.enable(selection);
    // Each parameter is one scalar x_k broadcast over its components (float textures store 3 channels).
    std::vector<int> offset, size;
    for (const auto& [p, index] : params.enabled()) offset.push_back(index), size.push_back(p->size);
    const auto expand = [&](const std::vector<float>& x) {
        std::vector<float> v;
        for (size_t k = 0; k < x.size(); ++k) v.insert(v.end(), size_t(size[k]), x[k]);
        return v;
    };
    const auto reduce = [&](const std::vector<double>& g) { // chain rule of the broadcast: dL/dx_k = Σ_c dL/dθ_kc
        std::vector<double> r(size.size(), 0.0);
        for (size_t k = 0; k < size.size(); ++k)
            for (int c = 0; c < size[k]; ++c) r[k] += g[size_t(offset[k] + c)];
        return r;
    };
    PathSamplingOptions base;
    base.threads = o.threads;
    base.path = path_settings(scene);
    base.nee = true;
    check_path_sampling(scene, params, base);

    SamplingRaceResult result;
    result.parameters = o.parameters;
    const std::vector<float> truth_values = params.values();
    for (size_t k = 0; k < size.size(); ++k) {
        const auto first = truth_values.begin() + offset[k];
        if (std::any_of(first, first + size[k], [&](float v) { return v != *first; }))
            throw Error("sampling race: '" + o.parameters[k] + "' has different values per component; only parameters "
                        "recovered as one scalar (weights, roughnesses) are supported");
        if (*first == 0.f) throw Error("sampling race: '" + o.parameters[k] + "' is 0: no relative error");
        result.truth.push_back(*first);
    }
    result.initial = o.initial;
    RenderOptions ro;
    ro.spp = o.target_spp;
    ro.seed = mix_bits(o.seed + 11);
    ro.threads = o.threads;
    const Image target = render(scene, ro);
    // The logged loss compares renders at eval_spp with the same seed at x and at the truth (common random
    // numbers: most of the noise cancels, and the loss tends to 0 as x → x*).
    ro.spp = o.eval_spp;
    ro.seed = mix_bits(o.seed + 12);
    const Image eval_target = render(scene, ro);
    const auto evaluate = [&] { return compute_loss(o.loss, render(scene, ro), eval_target).value; };

    result.methods = {{"BSDF sampling", false, false, o.spp, 0, {}}, {"differential + adaptive", true, true, 0, 0, {}}};
    const auto options_of = [&](const RaceMethod& m, int spp, uint64_t seed) {
        PathSamplingOptions p = base;
        p.differential = m.differential;
        p.adaptive = m.adaptive;
        p.spp = spp;
        p.seed = seed;
        return p;
    };
    // Equal time per iteration: seconds per sample of each method at the initial values, after a warm-up.
    try {
        params.set_values(scene, expand(o.initial));
        std::vector<double> per_sample;
        for (const RaceMethod& m : result.methods) {
            path_sampling_loss_gradient(scene, params, target, o.loss, options_of(m, o.spp, mix_bits(o.seed + 13)));
            double t = INFINITY;
            for (int r = 0; r < o.calibration_runs; ++r) {
                const double start = process_cpu_seconds();
                path_sampling_loss_gradient(scene, params, target, o.loss, options_of(m, o.spp, mix_bits(o.seed + 14 + r)));
                t = std::min(t, process_cpu_seconds() - start);
            }
            per_sample.push_back(t / o.spp);
        }
        result.methods[1].spp = std::max(o.spp > 3 ? 4 : o.spp, int(std::lround(o.spp * per_sample[0] / per_sample[1])));

        for (size_t mi = 0; mi < result.methods.size(); ++mi) {
            RaceMethod& m = result.methods[mi];
            std::vector<AdamGroup> groups;
            for (size_t k = 0; k < o.parameters.size(); ++k)
                groups.push_back({o.parameters[k], int(k), 1, o.learning_rate, o.lower, o.upper});
            Adam adam(groups, int(o.parameters.size()));
            std::vector<double> x(o.initial.begin(), o.initial.end());
            adam.project(x);
            std::vector<float> xf(x.begin(), x.end());
            params.set_values(scene, expand(xf));
            double seconds = 0;
            m.history.push_back({0, 0.0, evaluate(), parameter_error(xf, result.truth), xf});
            for (int it = 1; it <= o.iterations; ++it) {
                // Same seeds for both methods (their sample streams differ anyway: different spp and densities).
                const double start = process_cpu_seconds();
                const Gradient g = path_sampling_loss_gradient(
                    scene, params, target, o.loss,
                    options_of(m, m.spp, mix_bits(o.seed * 1000003 + uint64_t(it))));
                seconds += process_cpu_seconds() - start;
                adam.step(x, reduce(g.values));
                xf.assign(x.begin(), x.end());
                params.set_values(scene, expand(xf));
                m.history.push_back({it, seconds, evaluate(), parameter_error(xf, result.truth), xf});
                if (o.progress) o.progress(m.name, it);
            }
            m.seconds_per_iteration = seconds / o.iterations;
        }
    } catch (...) {
        params.set_values(scene, truth_values);
        throw;
    }
    params.set_values(scene, truth_values);

    fs::create_directories(o.output);
    result.csv_path = (fs::path(o.output) / "race.csv").string();
    result.plot_path = (fs::path(o.output) / "race.png").string();
    write_csv(result.csv_path, result);
    write_race_plot(result.plot_path, result);
    return result;
}

} // namespace penumbra
