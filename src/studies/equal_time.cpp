#include "studies/equal_time.h"

#include "core/error.h"
#include "studies/variance_study.h"

#include <cstdio>
#include <sstream>

namespace penumbra {

MethodSpec parse_method_spec(const std::string& text) {
    std::istringstream in(text);
    std::vector<std::string> words;
    for (std::string w; in >> w;)
        words.push_back(w);
    if (words.empty() || words[0].rfind("--", 0) == 0)
        throw Error("method '" + text +
                    "': expected a method name first (e.g. \"psdr --no-volume-boundary\")");
    MethodSpec spec{text, words[0], {}};
    for (size_t k = 1; k < words.size(); ++k) {
        if (words[k].rfind("--", 0) != 0)
            throw Error("method '" + text + "': expected an option, got '" + words[k] + "'");
        const std::string name = words[k].substr(2);
        const bool has_value = k + 1 < words.size() && words[k + 1].rfind("--", 0) != 0;
        spec.options.set(name, has_value ? words[++k] : "true");
    }
    make_method(spec.name, spec.options); // checks the name and the options
    return spec;
}

std::vector<EqualTimeRow> equal_time_study(const Scene& scene, const Parameters& params,
                                           const std::vector<MethodSpec>& methods,
                                           const EqualTimeOptions& options, const Image& reference,
                                           const Image& reference_stderr) {
    if (options.batches < 2) throw Error("equal-time study: at least 2 batches are needed for a variance");
    std::vector<EqualTimeRow> rows;
    for (const MethodSpec& spec : methods) {
        std::unique_ptr<DerivativeMethod> method = make_method(spec.name, spec.options);
        MethodRun run;
        run.spp = options.spp * options.batches;
        run.batches = options.batches;
        run.seed = options.seed;
        run.threads = options.threads;
        if (options.warm_up) {
            if (options.progress) options.progress(spec.text + ": warm-up");
            MethodRun warm = run;
            warm.seed = options.seed + 7919;
            method->derivative(scene, params, warm);
        }
        if (options.progress)
            options.progress(spec.text + ": " + std::to_string(options.batches) + " batches");
        const double start = process_cpu_seconds();
        DerivativeImage d = method->derivative(scene, params, run);
        const double seconds = process_cpu_seconds() - start;
        EqualTimeRow row;
        row.method = spec.text;
        row.description = d.description;
        row.seconds_per_batch = seconds / options.batches;
        // The variance of one batch from the standard error of the mean of `batches`: σ² · batches.
        double sum = 0;
        for (const Color3f& s : d.stderr_img.pixels)
            for (int k = 0; k < 3; ++k)
                sum += double(s[k]) * double(s[k]) * options.batches;
        row.variance = sum / (3.0 * double(d.stderr_img.pixels.size()));
        row.variance_time = row.variance * row.seconds_per_batch;
        row.ratio = rows.empty() ? 1.0 : row.variance_time / rows.front().variance_time;
        if (!reference.pixels.empty()) {
            row.full = compare_images(d.derivative, reference, d.stderr_img, reference_stderr);
            row.blocks = compare_images(
                block_average(d.derivative, 4), block_average(reference, 4),
                block_average_stderr(d.stderr_img, 4),
                reference_stderr.pixels.empty() ? Image() : block_average_stderr(reference_stderr, 4));
        }
        row.derivative = std::move(d.derivative);
        row.stderr_img = std::move(d.stderr_img);
        rows.push_back(std::move(row));
    }
    return rows;
}

std::string equal_time_markdown(const std::vector<EqualTimeRow>& rows, bool with_reference) {
    std::string out =
        with_reference ? "| method | CPU s / batch | variance | variance × time | ratio | relerr | relerr4 | "
                         "noise4 | z (mean) |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n"
                       : "| method | CPU s / batch | variance | variance × time | ratio |\n"
                         "|---|---:|---:|---:|---:|\n";
    for (const EqualTimeRow& r : rows) {
        char line[512];
        std::snprintf(line, sizeof line, "| %s | %.3f | %.4g | %.4g | %.3f |", r.method.c_str(),
                      r.seconds_per_batch, r.variance, r.variance_time, r.ratio);
        out += line;
        if (with_reference) {
            std::snprintf(line, sizeof line, " %.4f | %.4f | %.4f | %+.2f |", r.full.relerr, r.blocks.relerr,
                          r.blocks.noise_relerr, r.full.mean_z);
            out += line;
        }
        out += "\n";
    }
    return out;
}

} // namespace penumbra
