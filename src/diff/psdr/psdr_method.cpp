// The methods `psdr` (the total derivative of paper 001 Eq. 19: interior + boundary terms, diff/psdr/psdr.h, with
// the budget split by diff/psdr/budget.h) and `interior` (the material-form interior term alone) behind the common
// front of diff/method.h.
#include "core/seconds.h"
#include "diff/method_adapter.h"
#include "diff/psdr/budget.h"
#include "diff/psdr/psdr.h"

#include <chrono>
#include <cstdio>
#include <algorithm>
#include <utility>
#include <vector>

namespace penumbra {

namespace {

using Type = MethodOption::Type;

const MethodOption FirstVertexOption{
    "first-vertex",
    Type::String,
    "parameterization of the vertex the camera sees: image (fixed camera rays; needs a static camera), "
    "material "
    "(material points; the filter and pixel edges move) or auto (image unless the camera moves or a moving "
    "surface has a checkerboard/nearest texture)",
    {"auto", "image", "material"}};
const MethodOption InteriorEstimatorOption{
    "interior-estimator",
    Type::String,
    "estimator of the interior term: unidirectional (path tracing), bidirectional (bdpt's strategies with "
    "t >= 2, diff/psdr/bdpt_interior.h) or auto (bidirectional when the scene's integrator is bdpt)",
    {"auto", "unidirectional", "bidirectional"}};
const MethodOption NoAntitheticOption{
    "no-antithetic", Type::Bool, "disable pixel-level antithetic sampling", {}};

class PsdrMethod final : public DerivativeMethod {
  public:
    PsdrMethod(const MethodOptions& o, bool boundary) : boundary_(boundary) {
        first_vertex_ = parse_first_vertex(o.get_string("first-vertex", "auto"));
        antithetic_ = !o.get_bool("no-antithetic", false);
        estimator_ = parse_interior_estimator(o.get_string("interior-estimator", "auto"));
        guiding_ = !o.get_bool("no-guiding", false);
        volume_boundary_ = !o.get_bool("no-volume-boundary", false);
        const int fallback = o.get_int("boundary-spp", -1);
        manual_ = fallback >= 0;
        for (size_t k = 0; k < term_spp_.size(); ++k) {
            term_spp_[k] = o.get_int(std::string(PsdrTermNames[k + 1]) + "-spp", fallback);
            manual_ = manual_ || term_spp_[k] >= 0;
        }
    }

  protected:
    DerivativeImage estimate_derivative(const Scene& scene, const Parameters& params,
                                        const MethodRun& run) override {
        const auto start = std::chrono::steady_clock::now();
        PsdrOptions o = options(scene, params, run, nullptr);
        o.interior.progress = run.progress;
        if (!boundary_) return render_derivative(scene, params, o.interior);
        DerivativeImage d = psdr_derivative(scene, params, o);
        if (run.verbose) print_costs(d);
        d.seconds = seconds_since(start); // with the calibration
        return d;
    }

    Gradient estimate_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                               const MethodRun& run) override {
        const auto start = std::chrono::steady_clock::now();
        PsdrOptions o = options(scene, params, run, &adjoint);
        o.interior.progress = run.progress;
        if (!boundary_) return render_gradient(scene, params, adjoint, o.interior);
        Gradient g = psdr_gradient(scene, params, adjoint, o);
        g.seconds = seconds_since(start); // with the calibration
        return g;
    }

  private:
    // The options of one run: the interior gets run.spp and the boundary terms the given budgets, or (psdr
    // without given budgets) run.spp is the total, split by a calibration pass whose split is kept while the
    // sensor, its film, the parameter dimension and spp stay the same. `adjoint` null: forward mode.
    PsdrOptions options(const Scene& scene, const Parameters& params, const MethodRun& run,
                        const Image* adjoint) {
        const int batches = adjoint ? 1 : run.batches;
        PsdrOptions o;
        o.interior.batches = batches;
        o.interior.spp = std::max(1, run.spp / batches);
        o.interior.seed = run.seed;
        o.interior.threads = run.threads;
        o.interior.antithetic = antithetic_;
        o.interior.path = path_settings(scene);
        o.interior.first_vertex = first_vertex_;
        o.interior.estimator = estimator_;
        o.primary_spp = o.direct_spp = o.indirect_spp = o.pixel_spp = 0;
        o.guiding = guiding_;
        o.volume_boundary = volume_boundary_;
        if (!boundary_) return o;
        if (manual_) {
            int* spp[4] = {&o.primary_spp, &o.direct_spp, &o.indirect_spp, &o.pixel_spp};
            for (size_t k = 0; k < 4; ++k) {
                const int total = term_spp_[k] >= 0 ? term_spp_[k] : run.spp;
                *spp[k] = total > 0 ? std::max(1, total / batches) : 0;
            }
            return o;
        }
        const Film& film = *scene.sensor->film;
        const Key key{adjoint != nullptr,
                      scene.sensor.get(),
                      film.width,
                      film.height,
                      params.dimension(),
                      run.spp,
                      batches};
        auto it = std::find_if(calibrated_.begin(), calibrated_.end(), [&](const auto& k) { return k.first == key; });
        if (it == calibrated_.end()) {
            if (run.verbose) std::fprintf(stderr, "calibrating the terms' budgets...\n");
            calibrated_.emplace_back(key, adjoint ? psdr_gradient_budget(scene, params, *adjoint, o, run.spp)
                                                  : psdr_budget(scene, params, o, run.spp));
            it = calibrated_.end() - 1;
            if (run.verbose)
                std::fprintf(stderr, "budget: %s (calibrated)\n", describe_budget(it->second).c_str());
        }
        PsdrOptions c = it->second;
        c.interior.seed = run.seed;
        c.interior.threads = run.threads;
        return c;
    }

    static void print_costs(const DerivativeImage& d) {
        std::fprintf(stderr, "%-9s %12s %10s %12s %9s\n", "term", "samples", "rays/smp", "tape/smp",
                     "seconds");
        for (const DerivativeTerm& t : d.terms) {
            if (t.cost.samples == 0) continue;
            std::fprintf(stderr, "%-9s %12llu %10.2f %12.1f %9.2f\n", t.name.c_str(),
                         (unsigned long long)t.cost.samples, double(t.cost.rays) / double(t.cost.samples),
                         double(t.cost.tape_nodes) / double(t.cost.samples), t.seconds);
        }
    }

    struct Key {
        bool reverse;
        const Sensor* sensor;
        int width, height, dimension, spp, batches;
        bool operator==(const Key& o) const {
            return reverse == o.reverse && sensor == o.sensor && width == o.width && height == o.height &&
                   dimension == o.dimension && spp == o.spp && batches == o.batches;
        }
    };

    bool boundary_;
    FirstVertex first_vertex_;
    InteriorEstimator estimator_ = InteriorEstimator::Auto;
    bool antithetic_ = true, guiding_ = true, volume_boundary_ = true, manual_ = false;
    std::array<int, 4> term_spp_{}; // primary, direct, indirect, pixel; -1: unset
    std::vector<std::pair<Key, PsdrOptions>> calibrated_; // one split per configuration (e.g. per view)
};

} // namespace

MethodInfo interior_method_info() {
    return {"interior",
            "the material-form interior term alone (paper 001 Eq. 19, first term): exact for parameters that "
            "move "
            "no visibility edge",
            {FirstVertexOption, NoAntitheticOption, InteriorEstimatorOption},
            [](const MethodOptions& o) { return std::make_unique<PsdrMethod>(o, false); }};
}

MethodInfo psdr_method_info() {
    const auto spp_option = [](const std::string& term) {
        return MethodOption{
            term + "-spp",
            Type::Int,
            "samples per pixel of the " + term +
                " boundary term (experts; by default --spp is a total budget that a calibration "
                "pass splits over the terms)",
            {},
            0.0};
    };
    MethodOption boundary = spp_option("boundary");
    boundary.help = "samples per pixel of each boundary term (experts; default: calibrated split of --spp)";
    return {"psdr",
            "interior + boundary terms of paper 001 (primary, direct, indirect, pixel), the budget split by "
            "measurement",
            {FirstVertexOption,
             NoAntitheticOption,
             InteriorEstimatorOption,
             boundary,
             spp_option("primary"),
             spp_option("direct"),
             spp_option("indirect"),
             spp_option("pixel"),
             {"no-guiding",
              Type::Bool,
              "sample the primary term's edges by projected length only (no contrast pilot)",
              {}},
             {"no-volume-boundary",
              Type::Bool,
              "boundary segments end at surfaces only (no shadow sheets in media: a DTRT-like baseline)",
              {}}},
            [](const MethodOptions& o) { return std::make_unique<PsdrMethod>(o, true); }};
}

} // namespace penumbra
