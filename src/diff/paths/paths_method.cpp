// The method `paths`: the path sampling methods of paper 002 (diff/paths/path_sampling.h) behind the common front
// of diff/method.h. Non-geometric parameters only.
#include "diff/method_adapter.h"
#include "diff/paths/path_sampling.h"

namespace penumbra {

namespace {

class PathsMethod final : public DerivativeMethod {
  public:
    explicit PathsMethod(const MethodOptions& o) {
        base_.differential = o.get_string("sampling", "differential") == "differential";
        base_.q = float(o.get_float("q", 0.5));
        base_.nee = !o.get_bool("no-nee", false);
        base_.adaptive = o.get_bool("adaptive", false);
        base_.defensive = o.get_float("defensive", 0.05);
        base_.primal_fraction = o.get_float("primal-fraction", 0.75);
    }

  protected:
    DerivativeImage estimate_derivative(const Scene& scene, const Parameters& params,
                                        const MethodRun& run) override {
        if (base_.adaptive && !run.importance)
            throw Error("method paths: adaptive needs a pixel importance (--adjoint: the image |∂L/∂I|)");
        return path_sampling_derivative(scene, params, run_options(base_, scene, run, run.batches),
                                        run.importance ? *run.importance : Image());
    }

    Gradient estimate_gradient(const Scene& scene, const Parameters& params, const Image& adjoint,
                               const MethodRun& run) override {
        return path_sampling_gradient(scene, params, adjoint, run_options(base_, scene, run, 1));
    }

    // PRB's three passes (paper 002 Algorithm 1): pass 1 gets primal-fraction of the samples.
    Gradient estimate_loss_gradient(const Scene& scene, const Parameters& params, const Image& target,
                                    LossKind loss, const MethodRun& run) override {
        return path_sampling_loss_gradient(scene, params, target, loss, run_options(base_, scene, run, 1));
    }

  private:
    PathSamplingOptions base_;
};

} // namespace

MethodInfo paths_method_info() {
    using Type = MethodOption::Type;
    return {
        "paths",
        "path sampling methods of paper 002: differential vertex sampling, NEE, path replay, adaptive pixels "
        "(parameters that move no geometry)",
        {{"sampling",
          Type::String,
          "differential (differential vertex sampling) or bsdf",
          {"differential", "bsdf"}},
         {"q",
          Type::Float,
          "probability that a vertex becomes the differential vertex (default 0.5)",
          {},
          0.0,
          0.999},
         {"no-nee", Type::Bool, "no next-event estimation", {}},
         {"adaptive", Type::Bool, "adaptive pixel sampling by |adjoint| (derivative: needs --adjoint)", {}},
         {"defensive",
          Type::Float,
          "uniform share of the adaptive pixel density (default 0.05)",
          {},
          0.0,
          1.0},
         {"primal-fraction",
          Type::Float,
          "share of --spp spent on the primal pass of a loss gradient (default 0.75, the paper's 3:1)",
          {},
          0.01,
          0.99}},
        [](const MethodOptions& o) { return std::make_unique<PathsMethod>(o); }};
}

} // namespace penumbra
