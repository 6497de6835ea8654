// The Mitsuba differentiable-rendering test suite (scenes/mitsuba_ad/suite.json): scenes written from the
// discontinuity configurations of Mitsuba 3's src/integrators/tests/test_ad_integrators.py, each with its motion,
// Mitsuba's sample count and the settings of its finite-difference reference. One definition of the manifest and
// of the measurement serves both `penumbra ad-suite` (the study at 128²) and tests/test_mitsuba_ad_suite.cpp (the
// CI check at reduced resolution), so that the CI test checks what the study reports.
#pragma once
#include "diff/finite_difference.h"
#include "diff/psdr/psdr.h"

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace penumbra {

struct AdSuiteScene {
    std::string name;
    std::string file;                  // scene file (absolute, or relative to the working directory)
    std::vector<std::string> params;   // --param selections; all move with the same θ
    int spp = 0;                       // Mitsuba's sample count: psdr's whole budget
    double fd_eps = 0;                 // central-difference step at the suite's resolution (see fd_step)
    int fd_spp = 0;                    // reference samples per pixel and side, over all batches, at the suite's res
    int ci_res = 0;                    // the CI test's resolution
    double ci_fd_eps = 0;              // the CI test's central-difference step
    int ci_fd_spp = 0;                 // the CI test's reference samples per pixel and side
    bool optional = false;             // may be skipped when files it needs are absent
    std::vector<std::string> requires_files; // files an optional scene needs (relative to the manifest)
};

struct AdSuite {
    int res = 128;  // resolution of the study, at which fd_eps and fd_spp were chosen
    std::vector<AdSuiteScene> scenes;
};

// Throws Error naming the manifest and the entry on a missing or malformed field.
AdSuite load_ad_suite(const std::string& manifest);

// The files of `requires` that do not exist (empty: the scene can run).
std::vector<std::string> missing_files(const AdSuiteScene& scene);

// The reference's step and samples at `res`: (fd_eps, fd_spp) at the suite's resolution, (ci_fd_eps, ci_fd_spp) at
// ci_res (each step checked against one twice as large), else fd_eps scaled by suite.res / res so that edges move
// by the same fraction of a pixel (unchecked: at low resolutions curved edges may need a smaller step).
struct FdSettings {
    double eps;
    int spp;
};
FdSettings fd_settings(const AdSuite& suite, const AdSuiteScene& scene, int res);

// The scene loaded at `res` (a `res` define) with its parameters enabled. `defines` may override others (filter).
struct AdSuiteCase {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Parameters> params;
};
AdSuiteCase load_case(const AdSuiteScene& scene, int res, std::map<std::string, std::string> defines = {});

// Reference batches: their standard errors make z-scores and the reference's own noise measurable.
inline constexpr int AdSuiteReferenceBatches = 16;
// Derivative batches (standard errors for z-scores).
inline constexpr int AdSuiteDerivativeBatches = 8;

// The nearest reference sample count whose batches hold a square number of samples each (16 k²): film samples are
// stratified in a k × k grid only then (core/stratified.h; other counts are n-rooks, much noisier at curved edges).
int square_reference_spp(double spp);

// psdr's derivative given only the total sample count: psdr_budget's split over 8 batches.
DerivativeImage suite_derivative(const Scene& scene, const Parameters& params, int spp, uint64_t seed,
                                 int threads, std::function<void(float)> progress = {});

// Central differences with common random numbers and stratified film samples, `spp` per side split over 16
// batches.
FiniteDifference suite_reference(Scene& scene, Parameters& params, double h, int spp, uint64_t seed, int threads,
                                 std::function<void(float)> progress = {});

// The reference cache of `penumbra ad-suite --cache DIR`: <DIR>/<name>_fd.exr, _fd_stderr.exr and _fd.json, whose key
// (the scene file's FNV-1a hash, res, step, spp, params, defines, batches, seed) must match for the images to be
// used. A test may read references a study stored (scenes/validation/media_fd).
// The cached reference, or an empty optional when it is absent or its key does not match.
std::optional<FiniteDifference> read_cached_reference(const std::string& cache, const AdSuiteScene& scene, int res,
                                                      double h, int spp, const std::vector<std::string>& defines,
                                                      uint64_t seed);
// Writes images first and the key last (an interrupted write leaves a key that does not match).
void write_cached_reference(const std::string& cache, const AdSuiteScene& scene, int res, double h, int spp,
                            const std::vector<std::string>& defines, uint64_t seed, const FiniteDifference& fd);

struct AdSuiteScore {
    Comparison full;            // relerr and the z-score of the image mean
    Comparison blocks;          // after 4 × 4 block averaging: relerr4 and the relerr4 expected from both noises
    double reference_noise4 = 0; // relerr4 expected from the reference's noise alone
};
AdSuiteScore score(const Image& derivative, const Image& derivative_stderr, const FiniteDifference& reference);

} // namespace penumbra
