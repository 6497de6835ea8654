// Shared pieces of the `penumbra` command line. Each command family registers itself on the CLI11 app.
#pragma once
#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace penumbra::cli {

// -D name=value overrides of <default> values.
std::map<std::string, std::string> parse_defines(const std::vector<std::string>& defines);
// Lower-case extension including the dot (".exr").
std::string lower_extension(const std::string& path);

// A progress bar on stderr, redrawn at most every 100 ms, only when stderr is a terminal.
class ProgressBar {
public:
    explicit ProgressBar(bool enabled, std::string label = "");
    void update(float fraction);
    std::function<void(float)> callback() {
        return [this](float f) { update(f); };
    }

private:
    bool enabled_;
    std::string label_;
    std::chrono::steady_clock::time_point start_, last_;
};

void add_render_commands(CLI::App& app);   // render, info
void add_diff_commands(CLI::App& app);     // params, derivative, gradient, fd, compare
void add_optimize_command(CLI::App& app);  // optimize
void add_study_commands(CLI::App& app);    // variance-study, sampling-demo

} // namespace penumbra::cli
