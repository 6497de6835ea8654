// The methods `dpm-c` and `dpm-g`: differentiable photon mapping (paper 003, diff/dpm/dpm.h) behind the common
// front of diff/method.h. `--spp` counts SPPM passes; one term: the photon-mapped light's derivative.
#include "diff/dpm/dpm.h"
#include "diff/method_adapter.h"

namespace penumbra {

namespace {

class DpmMethod final : public DerivativeMethod {
  public:
    DpmMethod(const MethodOptions& o, DpmVariant variant) {
        base_.variant = variant;
        base_.pixel_fraction = o.get_float("pixel-fraction", base_.pixel_fraction);
        base_.paths = o.get_int("paths", base_.paths);
        base_.matching.scaling = o.get_float("matching-scaling", base_.matching.scaling);
        base_.matching.max_iterations = o.get_int("matching-iterations", base_.matching.max_iterations);
        base_.matching_jackknife = !o.get_bool("no-matching-jackknife", false);
    }

  protected:
    DerivativeImage estimate_derivative(const Scene& scene, const Parameters& params,
                                        const MethodRun& run) override {
        return dpm_derivative(scene, params, options(run, run.batches));
    }

    Gradient estimate_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                               const MethodRun& run) override {
        return dpm_gradient(scene, params, adjoint, options(run, 1));
    }

    Gradient estimate_loss_gradient(const Scene& scene, const Parameters& params, const Image& target,
                                    LossKind loss, const MethodRun& run) override {
        if (loss != LossKind::Matching)
            return DerivativeMethod::estimate_loss_gradient(scene, params, target, loss, run);
        return dpm_matching_gradient(scene, params, target, options(run, 1));
    }

  private:
    DpmOptions options(const MethodRun& run, int batches) const {
        DpmOptions o = base_;
        o.batches = batches;
        o.spp = std::max(1, run.spp / batches);
        o.seed = run.seed;
        o.threads = run.threads;
        o.progress = run.progress;
        return o;
    }

    DpmOptions base_;
};

std::vector<MethodOption> dpm_options() {
    using Type = MethodOption::Type;
    return {
        {"pixel-fraction",
         Type::Float,
         "fraction of the pixels that differentiate photon-mapping paths in each pass (default 1; the "
         "paper's 1/16 has 100-300 times the variance x time on the Fig. 6 scene, docs/dpm.md)",
         {},
         1e-6,
         1.0},
        {"matching-scaling",
         Type::Float,
         "Sinkhorn's blur ratio per annealing step for the matching loss (default 0.5, GeomLoss's)",
         {},
         0.0,
         0.99},
        {"matching-iterations",
         Type::Int,
         "Sinkhorn iterations at the final blur for the matching loss (default 1: stop after the annealing)",
         {},
         1,
         100000},
        {"no-matching-jackknife",
         Type::Bool,
         "the matching loss's gradient from the whole image's matching only, without the jackknife over two "
         "halves of the passes that removes its O(1/passes) bias (a third of the Sinkhorn time)",
         {}},
        {"paths",
         Type::Int,
         "photon-mapping paths differentiated per sampled pixel and pass (default 16, by measurement; the "
         "paper: 1)",
         {},
         1,
         1024}};
}

} // namespace

MethodInfo dpm_c_method_info() {
    return {"dpm-c",
            "differentiable photon mapping of paper 003, DPM-C: SPPM at its initial radius (fixed), one "
            "photon-mapping path per sampled pixel on the fixed-eye-ray EPSM: contribution derivatives through "
            "specular chains (caustics), no visibility boundaries",
            dpm_options(), [](const MethodOptions& o) { return std::make_unique<DpmMethod>(o, DpmVariant::C); }};
}

MethodInfo dpm_g_method_info() {
    return {"dpm-g",
            "differentiable photon mapping of paper 003, DPM-G: as dpm-c on the average of the fixed-density "
            "and vertex-merging EPSMs, whose eye rays move (screen-space derivatives for matching losses)",
            dpm_options(), [](const MethodOptions& o) { return std::make_unique<DpmMethod>(o, DpmVariant::G); }};
}

} // namespace penumbra
