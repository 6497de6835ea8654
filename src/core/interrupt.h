// Cooperative interruption of long work (Ctrl-C in the Python module): a front requests it, the parallel
// loops check it between work items and throw Interrupted, which unwinds like any Error (no partial output is
// written).
#pragma once
#include "core/error.h"

#include <atomic>

namespace penumbra {

struct Interrupted : Error {
    Interrupted() : Error("interrupted") {}
};

inline std::atomic<bool>& interrupt_flag() {
    static std::atomic<bool> flag{false};
    return flag;
}

inline void request_interrupt() { interrupt_flag().store(true, std::memory_order_relaxed); }
inline void clear_interrupt() { interrupt_flag().store(false, std::memory_order_relaxed); }
inline void check_interrupt() {
    if (interrupt_flag().load(std::memory_order_relaxed)) throw Interrupted();
}

} // namespace penumbra
