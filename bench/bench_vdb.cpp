// penumbra's .vdb reader against OpenVDB's, measured in one run: a smoke-like fog volume (a noisy ball of
// `res`^3 voxels, inactive zeros outside) written by OpenVDB with its default compression (Blosc + active
// mask) and with half floats and zlib, then read and densified `runs` times by read_vdb_file and by what
// penumbra did before it had its own reader (io::Stream, then one accessor lookup per voxel of the active
// box). Prints seconds per read and the ratio (above 1: penumbra's reader is faster).
//
// Usage: build/penumbra_bench_vdb [--runs N] [--res N]   (defaults 5, 160)
#include "scene/volumes/volume_grid.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

using namespace penumbra;

namespace {

openvdb::FloatGrid::Ptr smoke(int res) {
    auto grid = openvdb::FloatGrid::create(0.f);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto acc = grid->getAccessor();
    const float r = 0.5f * float(res);
    for (int x = 0; x < res; ++x)
        for (int y = 0; y < res; ++y)
            for (int z = 0; z < res; ++z) {
                const float dx = float(x) - r, dy = float(y) - r, dz = float(z) - r;
                const float d = std::sqrt(dx * dx + dy * dy + dz * dz) / r;
                if (d < 1.f)
                    acc.setValue(openvdb::Coord(x, y, z),
                                 (1.f - d) * (1.f + 0.3f * std::sin(0.7f * float(x + 2 * y + 3 * z))));
            }
    return grid;
}

// penumbra's reader before stop 32: OpenVDB's, then a dense copy through an accessor.
size_t read_with_openvdb(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    const openvdb::GridPtrVecPtr grids = openvdb::io::Stream(in).getGrids();
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>((*grids)[0]);
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    std::vector<float> values;
    values.reserve(box.volume());
    const auto acc = grid->getConstAccessor();
    for (int z = box.min().z(); z <= box.max().z(); ++z)
        for (int y = box.min().y(); y <= box.max().y(); ++y)
            for (int x = box.min().x(); x <= box.max().x(); ++x)
                values.push_back(acc.getValue(openvdb::Coord(x, y, z)));
    return values.size();
}

template <typename F> double seconds_per_run(int runs, F&& f) {
    const auto start = std::chrono::steady_clock::now();
    size_t sink = 0;
    for (int i = 0; i < runs; ++i)
        sink += f();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / runs;
    if (sink == 0) std::printf("(empty grid)\n");
    return s;
}

} // namespace

int main(int argc, char** argv) {
    int runs = 5, res = 160;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--runs")) runs = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--res")) res = std::atoi(argv[i + 1]);
    }
    openvdb::initialize();
    const auto dir = std::filesystem::temp_directory_path() / "penumbra_bench_vdb";
    std::filesystem::create_directories(dir);
    std::printf("fog ball of %d^3 voxels, %d runs each\n", res, runs);
    std::printf("%-22s %10s %14s %14s %8s\n", "file", "MB", "penumbra s", "OpenVDB s", "ratio");
    const std::pair<const char*, uint32_t> variants[] = {
        {"blosc+mask (default)", openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK},
        {"zip+mask, half", openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK},
        {"uncompressed", openvdb::io::COMPRESS_NONE}};
    for (const auto& [label, flags] : variants) {
        auto grid = smoke(res);
        grid->setGridClass(openvdb::GRID_UNKNOWN); // fog volumes drop zlib
        grid->setSaveFloatAsHalf(flags & openvdb::io::COMPRESS_ZIP);
        const std::string path = (dir / "smoke.vdb").string();
        openvdb::io::File file(path);
        file.setCompression(flags);
        file.write({grid});
        const double ours = seconds_per_run(runs, [&] { return read_vdb_file(path, "").values.size(); });
        const double theirs = seconds_per_run(runs, [&] { return read_with_openvdb(path); });
        std::printf("%-22s %10.2f %14.4f %14.4f %8.2f\n", label,
                    double(std::filesystem::file_size(path)) / 1e6, ours, theirs, theirs / ours);
    }
    std::filesystem::remove_all(dir);
}
