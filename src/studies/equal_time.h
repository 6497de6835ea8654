// Equal-time comparison of derivative methods (paper 001 §7, Fig. 10 (d)-(e): psdr against DTRT, Zhang et al.
// 2019, in equal time). Each method estimates the forward derivative dI/dθ in independent batches; its cost
// is measured as CPU seconds of the process (all threads; wall time on a shared machine varies with other
// processes' load) and its noise as the per-pixel variance of one batch. Variance falls as 1/time for an
// unbiased Monte Carlo estimator, so variance × time per batch is the equal-time figure of merit: a method
// with half the product reaches the same noise in half the time. With a finite-difference reference, each
// method's bias is reported too (relerr after 4 × 4 block averaging, and the z-score of the image mean),
// since a baseline that leaves out a boundary term is cheaper and biased.
#pragma once
#include "diff/finite_difference.h"
#include "diff/method.h"

#include <functional>
#include <string>
#include <vector>

namespace penumbra {

// A method and its options as on the command line: "psdr", "psdr --no-volume-boundary", "interior".
struct MethodSpec {
    std::string text;
    std::string name;
    MethodOptions options;
};
// Parses "NAME [--option [value]]...": a flag not followed by a value (or followed by another flag) is
// "true".
MethodSpec parse_method_spec(const std::string& text);

struct EqualTimeOptions {
    int spp = 64;     // samples per pixel per batch, every method (psdr: its total budget)
    int batches = 16; // independent batches (≥ 2)
    uint64_t seed = 0;
    int threads = 0;
    bool warm_up = true; // one untimed batch first (psdr calibrates its budget split once per configuration)
    std::function<void(const std::string&)> progress;
};

struct EqualTimeRow {
    std::string method;
    std::string description;
    double seconds_per_batch = 0; // CPU seconds
    double variance = 0;          // mean over pixels and channels of a batch's variance
    double variance_time = 0;     // variance × seconds_per_batch
    double ratio = 1;             // variance_time / the first method's
    Comparison full, blocks;      // against the reference (when given): relerr, z of the mean; relerr4
    Image derivative, stderr_img;
};

// The methods in order (the first is the ratios' reference). `reference` / `reference_stderr` may be empty.
std::vector<EqualTimeRow> equal_time_study(const Scene& scene, const Parameters& params,
                                           const std::vector<MethodSpec>& methods,
                                           const EqualTimeOptions& options, const Image& reference = Image(),
                                           const Image& reference_stderr = Image());

// Markdown table of the rows.
std::string equal_time_markdown(const std::vector<EqualTimeRow>& rows, bool with_reference);

} // namespace penumbra
