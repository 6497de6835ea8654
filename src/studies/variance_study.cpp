#include "studies/variance_study.h"

#include "core/error.h"
#include "core/rng.h"
#include "render/render.h"
#include "scene/integrator_settings.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

namespace penumbra {

std::string StudyVariant::name() const {
    std::string s = differential ? "differential" : "BSDF";
    if (adaptive) s += " + adaptive";
    if (nee) s += " + NEE";
    return s;
}

std::vector<StudyVariant> study_variants() {
    std::vector<StudyVariant> v;
    for (bool differential : {false, true})
        for (bool adaptive : {false, true})
            for (bool nee : {false, true}) v.push_back({differential, adaptive, nee});
    return v;
}

double process_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

namespace {

// Running mean and unbiased variance (Welford) of a scalar.
struct Moments {
    double n = 0, mean = 0, m2 = 0;
    void add(double x) {
        n += 1;
        const double d = x - mean;
        mean += d / n;
        m2 += d * (x - mean);
    }
    double variance() const { return n > 1 ? m2 / (n - 1) : 0.0; }
    double standard_error() const { return std::sqrt(variance() / n); }
};

double directional(const std::vector<double>& gradient, const std::vector<float>& direction) {
    double s = 0;
    for (size_t k = 0; k < gradient.size(); ++k) s += gradient[k] * double(direction[k]);
    return s;
}

double film_mean(const Image& image) {
    double s = 0;
    for (const Color3f& c : image.pixels) s += double(c[0]) + double(c[1]) + double(c[2]);
    return s / (3.0 * double(image.pixels.size()));
}

double z_score(double m, double se, double m0, double se0) {
    const double s = std::sqrt(se * se + se0 * se0);
    return s > 0 ? (m - m0) / s : 0.0;
}

template <class F> double timed(F&& f) {
    const double start = process_cpu_seconds();
    f();
    return process_cpu_seconds() - start;
}

// Seed of run `run` of variant `variant` for measurement `kind` (0 image, 1 loss; 2 calibration).
uint64_t run_seed(uint64_t seed, int variant, int kind, int run) {
    return mix_bits(mix_bits(seed * 8 + uint64_t(variant)) * 4 + uint64_t(kind)) + uint64_t(run) * 0x9E3779B97F4A7C15ULL;
}

} // namespace

VarianceStudy run_variance_study(Scene& scene, Parameters& params, const VarianceStudyOptions& o) {
    if (params.enabled().size() != 1) throw Error("variance study: enable exactly one parameter");
    if (o.runs < 2) throw Error("variance study: --runs must be at least 2");
    if (o.spp < 1 || o.target_spp < 1 || o.reference_spp < 1 || o.calibration_runs < 1)
        throw Error("variance study: spp, target_spp, reference_spp and calibration_runs must be positive");
    if (!(o.time_budget >= 0)) throw Error("variance study: the time budget must be non-negative");
    PathSamplingOptions base;
    base.threads = o.threads;
    base.path = path_settings(scene);
    base.q = o.q;
    base.defensive = o.defensive;
    base.primal_fraction = o.primal_fraction;
    check_path_sampling(scene, params, base);

    VarianceStudy study;
    study.parameter = params.enabled().front().first->name;
    study.value = params.values();
    study.target_value = o.target_value;
    if (study.target_value.size() == 1) study.target_value.assign(study.value.size(), o.target_value[0]);
    if (study.target_value.empty())
        for (float v : study.value) study.target_value.push_back(float(v * o.target_scale));
    if (study.target_value.size() != study.value.size())
        throw Error("variance study: the target value of '" + study.parameter + "' needs " +
                    std::to_string(study.value.size()) + " values, got " + std::to_string(study.target_value.size()));
    study.width = scene.sensor->film->width;
    study.height = scene.sensor->film->height;
    study.runs = o.runs;
    const auto report = [&](const std::string& stage, float f) {
        if (o.progress) o.progress(stage, f);
    };

    // Target at θ_t, and the reference adjoint at θ (pixel importance of adaptive image gradients).
    report("target", 0.f);
    RenderOptions ro;
    ro.spp = o.target_spp;
    ro.seed = run_seed(o.seed, 0, 3, 0);
    ro.threads = o.threads;
    params.set_values(scene, study.target_value);
    Image target;
    try {
        target = render(scene, ro);
    } catch (...) {
        params.set_values(scene, study.value);
        throw;
    }
    params.set_values(scene, study.value);
    ro.spp = o.reference_spp;
    ro.seed = run_seed(o.seed, 0, 3, 1);
    const Image reference_adjoint = l2_loss(render(scene, ro), target).adjoint;
    report("target", 1.f);

    const std::vector<StudyVariant> variants = study_variants();
    const auto options_of = [&](const StudyVariant& v, int spp, uint64_t seed) {
        PathSamplingOptions p = base;
        p.differential = v.differential;
        p.adaptive = v.adaptive;
        p.nee = v.nee;
        p.spp = spp;
        p.seed = seed;
        return p;
    };
    const auto image_run = [&](const StudyVariant& v, int spp, uint64_t seed) {
        return path_sampling_derivative(scene, params, options_of(v, spp, seed), reference_adjoint);
    };
    const auto loss_run = [&](const StudyVariant& v, int spp, uint64_t seed) {
        return path_sampling_loss_gradient(scene, params, target, LossKind::L2, options_of(v, spp, seed));
    };

    // Calibration: seconds per sample per pixel of each variant and measurement, after one warm-up run; the
    // fastest of `calibration_runs` runs (the least disturbed by other processes).
    const int cal_image = o.spp, cal_loss = std::max(4, 2 * o.spp);
    std::vector<double> tps_image(variants.size()), tps_loss(variants.size());
    image_run(variants[0], cal_image, run_seed(o.seed, 0, 2, 0));
    for (size_t i = 0; i < variants.size(); ++i) {
        report("calibration", float(i) / float(variants.size()));
        double ti = INFINITY, tl = INFINITY;
        for (int r = 0; r < o.calibration_runs; ++r) {
            const uint64_t seed = run_seed(o.seed, int(i), 2, r + 1);
            ti = std::min(ti, timed([&] { image_run(variants[i], cal_image, seed); }));
            tl = std::min(tl, timed([&] { loss_run(variants[i], cal_loss, seed); }));
        }
        tps_image[i] = ti / cal_image;
        tps_loss[i] = tl / cal_loss;
    }
    report("calibration", 1.f);
    study.time_budget = o.time_budget > 0 ? o.time_budget : tps_image[0] * o.spp;
    // The loss gradient needs at least one gradient sample after the primal share (path_sampling_loss_gradient).
    int min_loss_spp = 2;
    while (min_loss_spp - std::max(1, int(std::lround(min_loss_spp * o.primal_fraction))) < 1) ++min_loss_spp;

    struct Accumulator {
        std::vector<Moments> pixels;
        Moments image_mean, loss;
        double seconds_image = 0, seconds_loss = 0;
    };
    std::vector<VariantStatistics> stats(variants.size());
    std::vector<Accumulator> acc(variants.size());
    for (size_t i = 0; i < variants.size(); ++i) {
        stats[i].variant = variants[i];
        stats[i].spp_image = std::max(1, int(std::lround(study.time_budget / tps_image[i])));
        stats[i].spp_loss = std::max(min_loss_spp, int(std::lround(study.time_budget / tps_loss[i])));
        acc[i].pixels.resize(size_t(study.width) * study.height * 3);
    }
    // Runs interleaved over the variants, so that slow drifts of the machine's state affect all of them alike.
    for (int r = 0; r < o.runs; ++r) {
        report("runs", float(r) / float(o.runs));
        for (size_t i = 0; i < variants.size(); ++i) {
            const StudyVariant& v = variants[i];
            Accumulator& a = acc[i];
            DerivativeImage d;
            a.seconds_image += timed([&] { d = image_run(v, stats[i].spp_image, run_seed(o.seed, int(i), 0, r)); });
            for (size_t p = 0; p < d.derivative.pixels.size(); ++p)
                for (int c = 0; c < 3; ++c) a.pixels[3 * p + size_t(c)].add(double(d.derivative.pixels[p][c]));
            a.image_mean.add(film_mean(d.derivative));
            Gradient g;
            a.seconds_loss += timed([&] { g = loss_run(v, stats[i].spp_loss, run_seed(o.seed, int(i), 1, r)); });
            a.loss.add(directional(g.values, params.direction()));
        }
    }
    report("runs", 1.f);
    for (size_t i = 0; i < variants.size(); ++i) {
        VariantStatistics& s = stats[i];
        const Accumulator& a = acc[i];
        double variance = 0;
        for (const Moments& m : a.pixels) variance += m.variance();
        s.image_variance = variance / double(a.pixels.size());
        s.image_mean = a.image_mean.mean;
        s.image_mean_se = a.image_mean.standard_error();
        s.loss_gradient = a.loss.mean;
        s.loss_gradient_se = a.loss.standard_error();
        s.loss_variance = a.loss.variance();
        s.seconds_image = a.seconds_image / o.runs;
        s.seconds_loss = a.seconds_loss / o.runs;
        s.image_variance_at_budget = s.image_variance * s.seconds_image / study.time_budget;
        s.loss_variance_at_budget = s.loss_variance * s.seconds_loss / study.time_budget;
        if (i > 0) {
            s.z_image = z_score(s.image_mean, s.image_mean_se, stats[0].image_mean, stats[0].image_mean_se);
            s.z_loss = z_score(s.loss_gradient, s.loss_gradient_se, stats[0].loss_gradient, stats[0].loss_gradient_se);
        }
    }
    study.variants = std::move(stats);
    return study;
}

namespace {

std::string format(const char* fmt, double v) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), fmt, v);
    return buf;
}

std::string values_text(const std::vector<float>& v) {
    std::string s;
    for (float x : v) s += (s.empty() ? "" : ", ") + format("%.4g", x);
    return s;
}

} // namespace

std::string variance_study_markdown(const VarianceStudy& study) {
    if (study.variants.size() < 2) throw Error("variance study: no result to print");
    const VariantStatistics& b0 = study.variants[0];
    const VariantStatistics& b1 = study.variants[1]; // BSDF + NEE
    std::string s = "Variance study of `" + study.parameter + "` = " + values_text(study.value) + " (target at " +
                    values_text(study.target_value) + "), " + std::to_string(study.width) + "x" +
                    std::to_string(study.height) + ", " + std::to_string(study.runs) + " runs per variant, " +
                    format("%.3g", study.time_budget) + " CPU s per run.\n\n";
    s += "Ratios compare variances at equal time: Var x (achieved CPU s/run) / budget (variance ~ 1 / time), so that "
         "calibration errors of the spp cancel to first order; the raw variances are those of the achieved times.\n\n";
    s += "| variant | spp img / loss | CPU s/run img / loss | Var dI/dθ | ÷BSDF | ÷BSDF+NEE | Var dL/dθ | ÷BSDF | ÷BSDF+NEE "
         "| mean dI/dθ (z) | dL/dθ (z) |\n";
    s += "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const VariantStatistics& v : study.variants) {
        s += "| " + v.variant.name() + " | " + std::to_string(v.spp_image) + " / " + std::to_string(v.spp_loss) + " | " +
             format("%.3f", v.seconds_image) + " / " + format("%.3f", v.seconds_loss) + " | " + format("%.3g", v.image_variance) +
             " | " + format("%.3g", v.image_variance_at_budget / b0.image_variance_at_budget) + " | " +
             format("%.3g", v.image_variance_at_budget / b1.image_variance_at_budget) + " | " + format("%.3g", v.loss_variance) +
             " | " + format("%.3g", v.loss_variance_at_budget / b0.loss_variance_at_budget) + " | " +
             format("%.3g", v.loss_variance_at_budget / b1.loss_variance_at_budget) + " | " + format("%.4g", v.image_mean) +
             format(" (%+.2f)", v.z_image) + " | " + format("%.4g", v.loss_gradient) + format(" (%+.2f)", v.z_loss) + " |\n";
    }
    return s;
}

std::string variance_study_json(const VarianceStudy& study) {
    nlohmann::json j;
    j["parameter"] = study.parameter;
    j["value"] = study.value;
    j["target_value"] = study.target_value;
    j["width"] = study.width;
    j["height"] = study.height;
    j["runs"] = study.runs;
    j["time_budget"] = study.time_budget;
    for (const VariantStatistics& v : study.variants) {
        j["variants"].push_back({{"name", v.variant.name()},
                                 {"differential", v.variant.differential},
                                 {"adaptive", v.variant.adaptive},
                                 {"nee", v.variant.nee},
                                 {"spp_image", v.spp_image},
                                 {"spp_loss", v.spp_loss},
                                 {"seconds_image", v.seconds_image},
                                 {"seconds_loss", v.seconds_loss},
                                 {"image_variance", v.image_variance},
                                 {"image_variance_at_budget", v.image_variance_at_budget},
                                 {"image_mean", v.image_mean},
                                 {"image_mean_se", v.image_mean_se},
                                 {"z_image", v.z_image},
                                 {"loss_gradient", v.loss_gradient},
                                 {"loss_gradient_se", v.loss_gradient_se},
                                 {"loss_variance", v.loss_variance},
                                 {"loss_variance_at_budget", v.loss_variance_at_budget},
                                 {"z_loss", v.z_loss}});
    }
    return j.dump(2) + "\n";
}

} // namespace penumbra
