#include "core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace penumbra {

ProgressBar::ProgressBar(bool enabled, std::string label)
    : enabled_(enabled && isatty(STDERR_FILENO)), label_(std::move(label)), start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() {
    if (unfinished_) std::fprintf(stderr, "\n");
}

void ProgressBar::update(float fraction) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (fraction < 1.f && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const int width = 40, filled = int(fraction * width);
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    std::string bar(size_t(std::max(0, filled)), '=');
    bar.resize(width, ' ');
    std::fprintf(stderr, "\r%s[%s] %5.1f%%  %.1fs", label_.empty() ? "" : (label_ + " ").c_str(), bar.c_str(),
                 100.0 * fraction, elapsed);
    if (fraction >= 1.f) std::fprintf(stderr, "\n");
    unfinished_ = fraction < 1.f;
    std::fflush(stderr);
}

} // namespace penumbra
