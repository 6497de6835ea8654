#include "core/atomic_file.h"

#include "core/error.h"
#include "core/interrupt.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace penumbra {

namespace {
std::atomic<size_t> files_written{0};
}

std::string atomic_temp_path(const std::string& path) {
    static std::atomic<unsigned> calls{0};
    return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(calls++);
}

void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& tmp_path)>& write) {
    const std::string tmp = atomic_temp_path(path);
    auto remove_tmp = [&] {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
    };
    try {
        write(tmp);
    } catch (const Interrupted&) {
        remove_tmp();
        throw;
    } catch (const std::exception& e) {
        remove_tmp();
        throw Error("cannot write '" + path + "': " + e.what());
    } catch (...) {
        remove_tmp();
        throw;
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        remove_tmp();
        throw Error("cannot write '" + path + "': renaming '" + tmp + "' failed: " + ec.message());
    }
    ++files_written;
}

size_t files_written_atomically() { return files_written.load(); }

void write_text_atomically(const std::string& path, std::string_view content) {
    write_file_atomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        if (!out) throw Error(std::string("cannot create the file: ") + std::strerror(errno));
        out.write(content.data(), std::streamsize(content.size()));
        out.close();
        if (!out) throw Error(std::string("write failed: ") + std::strerror(errno));
    });
}

} // namespace penumbra
