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
    // Ends a bar left unfinished (by an error or an interrupt), so that the message starts a line.
    ~ProgressBar();
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;
    void update(float fraction);
    std::function<void(float)> callback() {
        return [this](float f) { update(f); };
    }

private:
    bool enabled_;
    bool unfinished_ = false; // a bar below 100% is on the terminal's current line
    std::string label_;
    std::chrono::steady_clock::time_point start_, last_;
};

} // namespace penumbra
