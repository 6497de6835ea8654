// Equal-time variance study of the path sampling estimators (paper 002 §5.2, Figure 6 and Table 2): for the
// eight variants differential ∈ {BSDF, differential} × adaptive × NEE, the per-pixel variance of the image
// gradient dI/dθ and the variance of the loss gradient dL/dθ over independent runs that each take about the
// same time.
//
// Setup (as the paper's Table 1/2): the loss is L2 against a target rendered at a different parameter value
// θ_t (default θ · 1.3), so that dL/dθ is non-trivial; the loss gradient is path_sampling_loss_gradient (pass 1
// for the adjoint, passes 2-3 for the gradient, budget 3:1). Adaptive image gradients use as pixel importance
// the adjoint of a reference primal image (render() at `reference_spp`) against the target.
// Equal time, measured as CPU time of the process (all threads; wall time on a shared machine varies by tens of
// percent with other processes' load, CPU time does not): each variant's time per sample is measured first (a warm-up and `calibration_runs` runs), then
// its spp is chosen so that a run takes `time_budget` CPU seconds (default: the time of one BSDF-sampling run
// without NEE at `spp`); the achieved mean CPU seconds per run are reported next to the variances, and the ratios
// compare variances scaled to the budget (Var · achieved / budget), which cancels the residual timing error
// (on a shared machine the calibration is only good to ~20%) to first order.
// Unbiasedness check: every variant's mean (film mean of dI/dθ, and dL/dθ) is compared with BSDF sampling's
// by z = (m − m_BSDF) / √(se² + se_BSDF²).
#pragma once
#include "diff/paths/path_sampling.h"

#include <functional>
#include <string>
#include <vector>

namespace penumbra {

struct StudyVariant {
    bool differential = false, adaptive = false, nee = false;
    std::string name() const; // "BSDF", "BSDF + NEE", "differential + adaptive + NEE", ...
};
// CPU seconds of this process, all threads (the equal-time clock of the study and of studies/sampling_race.h).
double process_cpu_seconds();

// The eight variants in table order; the first (BSDF sampling without NEE) is the baseline.
std::vector<StudyVariant> study_variants();

struct VarianceStudyOptions {
    int runs = 100;                 // independent runs per variant and measurement (≥ 2)
    double time_budget = 0;         // CPU seconds per run; 0 = one BSDF (no NEE) image-gradient run at `spp`
    int spp = 16;                   // spp of the baseline that sets the default time budget
    std::vector<float> target_value; // θ_t (the parameter's size, or 1 value broadcast); empty = θ · target_scale
    double target_scale = 1.3;
    int target_spp = 256, reference_spp = 64;
    int calibration_runs = 3;      // calibration: fastest of these runs at spp (image) and 2·spp (loss)
    uint64_t seed = 0;
    int threads = 0;
    float q = 0.5f;
    double defensive = 0.05, primal_fraction = 0.75;
    // Called with a stage name ("target", "calibration", "runs") and the fraction done in it.
    std::function<void(const std::string&, float)> progress;
};

struct VariantStatistics {
    StudyVariant variant;
    int spp_image = 0, spp_loss = 0;             // calibrated samples per pixel (loss: all three passes)
    double seconds_image = 0, seconds_loss = 0;  // mean CPU seconds per run
    double image_variance = 0;                   // mean over pixels and channels of Var[dI/dθ] across runs
    double image_mean = 0, image_mean_se = 0;    // film mean of dI/dθ: mean over runs and standard error
    double loss_gradient = 0, loss_gradient_se = 0, loss_variance = 0; // dL/dθ (along the direction)
    double z_image = 0, z_loss = 0;              // against the baseline (0 for the baseline itself)
    // Variances scaled to the time budget, Var · (achieved s/run) / budget (variance ∝ 1 / time): the equal-time
    // values the ratios of the table compare, robust to calibration errors.
    double image_variance_at_budget = 0, loss_variance_at_budget = 0;
};

struct VarianceStudy {
    std::string parameter;
    std::vector<float> value, target_value;
    int width = 0, height = 0, runs = 0;
    double time_budget = 0; // CPU seconds per run
    std::vector<VariantStatistics> variants; // study_variants() order
};

// Throws Error for an unknown parameter, a geometric one, more than one enabled parameter, or bad options.
// The scene is restored to its parameter values on return.
VarianceStudy run_variance_study(Scene& scene, Parameters& params, const VarianceStudyOptions& options);

// Markdown table: rows = variants; columns = spp, seconds per run, variances and their ratios to BSDF
// sampling without / with NEE, the means and their z-scores.
std::string variance_study_markdown(const VarianceStudy& study);
std::string variance_study_json(const VarianceStudy& study);

} // namespace penumbra
