// Shared pieces of the `penumbra` command line. Each command family registers itself on the CLI11 app.
#pragma once
#include "core/progress.h"

#include <CLI/CLI.hpp>

#include <map>
#include <string>
#include <vector>

namespace penumbra {
struct Image;
}

namespace penumbra::cli {

// -D name=value overrides of <default> values.
std::map<std::string, std::string> parse_defines(const std::vector<std::string>& defines);
// Lower-case extension including the dot (".exr").
std::string lower_extension(const std::string& path);
// A signed image by extension: .exr (values) or .png (diverging colormap saturated at ±scale; 0: automatic).
void write_signed(const std::string& path, const Image& image, float scale = 0.f);
// Per pixel (a − b) / sqrt(σ_a² + σ_b²) by extension: .exr (values) or .png (diverging colormap saturated at ±4).
// Either standard-error image may be empty.
void write_z_map(const std::string& path, const Image& a, const Image& b, const Image& sa, const Image& sb);

using penumbra::ProgressBar;

void add_render_commands(CLI::App& app);   // render, info
void add_diff_commands(CLI::App& app);     // params, derivative, gradient, fd, compare
void add_optimize_command(CLI::App& app);  // optimize
void add_study_commands(CLI::App& app);    // variance-study, sampling-demo
void add_suite_command(CLI::App& app);     // ad-suite

} // namespace penumbra::cli
