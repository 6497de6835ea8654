// Cooperative interruption of long work (Ctrl-C in the Python module, SIGINT/SIGTERM in the CLI): a front
// requests it, the parallel loops check it between work items and throw Interrupted, which unwinds like any
// Error (outputs are written atomically, core/atomic_file.h, so no partial file is left).
#pragma once
#include "core/error.h"

#include <atomic>
#include <string>

namespace penumbra {

struct Interrupted : Error {
    Interrupted() : Error("interrupted") {}
    // `complete`: the outputs that a run writing several files had completed (e.g. an optimization's log).
    explicit Interrupted(std::string complete) : Error("interrupted"), complete(std::move(complete)) {}
    std::string complete;
};

// Lock-free, so that request_interrupt() may be called from a signal handler.
static_assert(std::atomic<bool>::is_always_lock_free);
inline std::atomic<bool>& interrupt_flag() {
    static std::atomic<bool> flag{false}; // constant-initialized: no guard, safe in a signal handler
    return flag;
}

inline void request_interrupt() { interrupt_flag().store(true, std::memory_order_relaxed); }
inline void clear_interrupt() { interrupt_flag().store(false, std::memory_order_relaxed); }
inline bool interrupt_requested() { return interrupt_flag().load(std::memory_order_relaxed); }
inline void check_interrupt() {
    if (interrupt_requested()) throw Interrupted();
}

} // namespace penumbra
