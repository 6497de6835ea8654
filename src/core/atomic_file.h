// Atomic output: every file penumbra writes (images, EXR layers, JSON, CSV, meshes, reports) is produced
// under a temporary name in the target's directory and renamed into place, so that a reader, a failed write
// or an interrupted run (Ctrl-C, SIGTERM) never leaves a partial file: the target holds its old content or
// the new one.
#pragma once
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

namespace penumbra {

// The temporary name write_file_atomically uses for `path`: `<path>.tmp.<pid>.<n>`, unique per process and
// call, in the same directory (rename(2) is atomic only within one file system).
std::string atomic_temp_path(const std::string& path);

// write(tmp) writes the whole file at `tmp`; it is then renamed to `path`. If write throws or the rename
// fails, the temporary file is removed and `path` is left as it was; the error is rethrown as an Error
// naming `path` ("cannot write '<path>': <reason>"), except Interrupted, which is rethrown as is.
void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& tmp_path)>& write);

// `content` (text or bytes, written verbatim) as the whole content of `path`, atomically.
void write_text_atomically(const std::string& path, std::string_view content);

// How many files this process has written (renamed into place) so far: what an interrupted run reports.
size_t files_written_atomically();

} // namespace penumbra
