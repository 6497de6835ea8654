// The bodies of the fuzz harnesses: one per parser, each fed arbitrary bytes. libFuzzer calls them through
// libfuzzer_main.cpp (the PENUMBRA_FUZZ build); the normal test build replays the committed seeds and crash
// inputs through the same functions (tests/test_fuzz_regressions.cpp).
//
// Contract: a loader rejects bad input by throwing a std::exception (penumbra::Error and its kin), which the
// body swallows. Anything else -- a crash, an abort, a sanitizer report, a leak, a hang, an unbounded
// allocation -- is a bug in the loader.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

namespace penumbra::fuzz {

void fuzz_xml(const uint8_t* data, size_t size);             // Mitsuba XML scene (with <include>, meshes)
void fuzz_obj(const uint8_t* data, size_t size);             // Wavefront OBJ mesh
void fuzz_ply(const uint8_t* data, size_t size);             // PLY mesh (ascii and binary)
void fuzz_serialized(const uint8_t* data, size_t size);      // Mitsuba .serialized mesh (zlib)
void fuzz_exr(const uint8_t* data, size_t size);             // OpenEXR texture
void fuzz_png(const uint8_t* data, size_t size);             // PNG (and whatever else stb_image sniffs)
void fuzz_vol(const uint8_t* data, size_t size);             // Mitsuba .vol grid
void fuzz_vdb(const uint8_t* data, size_t size);             // OpenVDB .vdb grid
void fuzz_optimize_config(const uint8_t* data, size_t size); // `penumbra optimize` JSON configuration

// The image size the texture harnesses accept (read_image's max_pixels): 2^22 pixels, 48 MB as float RGB, so
// that a header stating a large size is refused within libFuzzer's memory limit rather than decoded.
constexpr int64_t FuzzMaxImagePixels = int64_t(1) << 22;
// The same for read_vdb_file's dense grid (16 MiB of floats, against its 1 GiB default).
constexpr uint64_t FuzzMaxVoxels = uint64_t(1) << 22;

// A directory of this process's own (created on first use, removed at exit) for the files that file-only
// loaders are given; the path is reused from one input to the next.
const std::string& scratch_dir();
// Writes the bytes to scratch_dir()/name, replacing the previous input, and returns the file's path.
std::string write_input(const std::string& name, const uint8_t* data, size_t size);
// A directory holding small valid files for inputs to refer to (include.xml, part.xml, mesh.obj, mesh.ply,
// mesh_binary.ply, mesh.serialized, tex.png, tex.exr, grid.vol, grid.vdb, spectrum.spd, curves.txt); written
// once per process.
const std::string& fixture_dir();

// Whether PENUMBRA_FUZZ_VERBOSE is set: then rejected inputs print their error (to check what a seed
// reaches).
bool verbose();

// Runs `fn`, swallowing the std::exceptions with which loaders reject input.
template <typename Fn> void reject_with_exceptions(Fn&& fn) {
    try {
        fn();
    } catch (const std::exception& e) {
        if (verbose()) std::fprintf(stderr, "rejected: %s\n", e.what());
    }
}

} // namespace penumbra::fuzz
