// Helpers shared by the mesh loader and shape factory tests.
#pragma once
#include "core/error.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <unistd.h>

namespace penumbra::test {

// A per-process scratch directory `<tmp>/<prefix><pid>`; hold it in a function-local static so that it is
// removed when the test program exits.
struct ScratchDir {
    explicit ScratchDir(const std::string& prefix)
        : path(std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()))) {
        std::filesystem::create_directories(path);
    }
    ~ScratchDir() { std::filesystem::remove_all(path); }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    std::filesystem::path path;
};

// Writes `contents` byte for byte to dir/name; returns the full path.
inline std::string write_file(const std::filesystem::path& dir, const std::string& name,
                              const std::string& contents) {
    const std::filesystem::path path = dir / name;
    std::ofstream(path, std::ios::binary) << contents;
    return path.string();
}

// The message of the penumbra::Error thrown by `f`, or "<no error>".
inline std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "<no error>";
}

} // namespace penumbra::test
