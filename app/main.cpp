// The `penumbra` command line: a thin front over the library.
#include "cli.h"

#include "core/atomic_file.h"
#include "core/interrupt.h"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>

namespace {

// The first SIGINT/SIGTERM received (0: none), written by the handler.
std::atomic<int> received_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

// The first signal asks the work to stop (core/interrupt.h): it unwinds at its next check (a sample, a chunk
// of samples, an iteration) and main reports it. A second one takes the default action, so that a run stuck
// where nothing checks can still be stopped. Only async-signal-safe calls: lock-free atomics, sigaction,
// raise.
void on_signal(int sig) {
    if (received_signal.exchange(sig) != 0) {
        struct sigaction action = {};
        action.sa_handler = SIG_DFL;
        sigemptyset(&action.sa_mask);
        sigaction(sig, &action, nullptr);
        raise(sig); // delivered when the handler returns
        return;
    }
    penumbra::request_interrupt();
}

void install_signal_handlers() {
    struct sigaction action = {};
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    sigaddset(&action.sa_mask, SIGINT);
    sigaddset(&action.sa_mask, SIGTERM);
    action.sa_flags = SA_RESTART; // file reads in progress complete; the work stops at its next check
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

const char* signal_name(int sig) { return sig == SIGTERM ? "SIGTERM" : "SIGINT"; }

// 128 + the signal, as a shell reports a process killed by it: 130 for SIGINT, 143 for SIGTERM.
int report_interrupt(const std::string& complete) {
    const int sig = received_signal.load() != 0 ? received_signal.load() : SIGINT;
    const size_t files = penumbra::files_written_atomically();
    if (!complete.empty())
        std::fprintf(stderr, "penumbra: interrupted (%s); %s\n", signal_name(sig), complete.c_str());
    else if (files == 0)
        std::fprintf(stderr, "penumbra: interrupted (%s); no output written\n", signal_name(sig));
    else
        std::fprintf(
            stderr,
            "penumbra: interrupted (%s); the %zu file(s) written before it are complete, none partial\n",
            signal_name(sig), files);
    return 128 + sig;
}

} // namespace

int main(int argc, char** argv) {
    install_signal_handlers();
    CLI::App app{"penumbra: a physics-based differentiable renderer"};
    app.require_subcommand(1);
    penumbra::cli::add_render_commands(app);
    penumbra::cli::add_diff_commands(app);
    penumbra::cli::add_optimize_command(app);
    penumbra::cli::add_study_commands(app);
    penumbra::cli::add_suite_command(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const penumbra::Interrupted& e) {
        return report_interrupt(e.complete);
    } catch (const std::exception& e) {
        // An error raised while the work unwinds from a signal is the interruption's, not the run's.
        if (received_signal.load() != 0) return report_interrupt("");
        std::fprintf(stderr, "penumbra: error: %s\n", e.what());
        return 1;
    }
    if (const int sig = received_signal.load(); sig != 0)
        std::fprintf(stderr, "penumbra: %s arrived after the work was done; the outputs are complete\n",
                     signal_name(sig));
    return 0;
}
