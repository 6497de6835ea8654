// A progress bar on stderr for long work (the command line, and the Python module when asked), redrawn at most
// every 100 ms, only when stderr is a terminal.
#pragma once
#include <chrono>
#include <functional>
#include <string>

namespace penumbra {

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

} // namespace penumbra
