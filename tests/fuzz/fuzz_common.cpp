// The scratch directory of the fuzz harnesses and the small valid files that fuzzed inputs may refer to.
#include "fuzz_targets.h"

#include "../mesh_test_util.h"
#include "core/image.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <zlib.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace penumbra::fuzz {
namespace {

template <typename V> void put(std::string& out, V v) {
    char bytes[sizeof(V)];
    std::memcpy(bytes, &v, sizeof(V));
    out.append(bytes, sizeof(V));
}

// One triangle as a version 4 .serialized file (little-endian host): header, zlib record, offset table.
std::string serialized_triangle() {
    std::string record;
    put<uint32_t>(record, 0x0002); // texture coordinates
    record += std::string("tri") + '\0';
    put<uint64_t>(record, 3);
    put<uint64_t>(record, 1);
    for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})
        put(record, v);
    for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 1.f})
        put(record, v);
    for (uint32_t i : {0u, 1u, 2u})
        put(record, i);
    uLongf size = compressBound(uLong(record.size()));
    std::string compressed(size, '\0');
    compress(reinterpret_cast<Bytef*>(compressed.data()), &size,
             reinterpret_cast<const Bytef*>(record.data()), uLong(record.size()));
    compressed.resize(size);
    std::string file;
    put<uint16_t>(file, 0x041C);
    put<uint16_t>(file, 4);
    file += compressed;
    put<uint64_t>(file, 0);
    put<uint32_t>(file, 1);
    return file;
}

// A 2 x 2 x 2 one-channel grid in the unit cube.
std::string vol_grid() {
    std::string file = "VOL";
    file += char(3);
    for (int32_t v : {1, 2, 2, 2, 1})
        put(file, v);
    for (float v : {0.f, 0.f, 0.f, 1.f, 1.f, 1.f, 0.f, 0.5f, 1.f, 1.5f, 2.f, 2.5f, 3.f, 3.5f})
        put(file, v);
    return file;
}

void write_vdb_grid(const std::string& path) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.f);
    density->setName("density");
    density->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(1, 1, 1)), 1.f, true);
    openvdb::io::File(path).write({density});
}

void write_fixtures(const std::filesystem::path& dir) {
    auto write = [&](const char* name, const std::string& contents) {
        test::write_file(dir, name, contents);
    };
    write("include.xml", "<scene version=\"3.0.0\">\n  <bsdf type=\"diffuse\" id=\"included\"/>\n</scene>\n");
    write("part.xml", "<bsdf type=\"roughconductor\" id=\"part\"/>\n");
    write("mesh.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
                      "f 1/1/1 2/2/1 3/3/1 4/4/1\n");
    write("mesh.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nproperty float u\nproperty float v\nelement face 1\n"
                      "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n"
                      "3 0 1 2\n");
    std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nproperty float z\nelement face 1\n"
                         "property list uchar uint vertex_indices\nproperty float quality\nend_header\n";
    for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})
        put(binary, v);
    put<uint8_t>(binary, 3);
    for (uint32_t i : {0u, 1u, 2u})
        put(binary, i);
    put(binary, 0.5f);
    write("mesh_binary.ply", binary);
    write("mesh.serialized", serialized_triangle());
    write("grid.vol", vol_grid());
    write("spectrum.spd", "400 0.2\n550 0.5\n700 0.8\n");
    write("curves.txt",
          "0 0 0 0.1\n0 1 0 0.1\n1 1 0 0.05\n1 2 0 0.05\n\n2 0 0 0.2\n2 0 1 0.1\n3 0 1 0.1\n3 1 1 0\n");
    write_png((dir / "tex.png").string(), 2, 2, 3,
              {0.f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f, 1.f, 0.f});
    write_image((dir / "tex.exr").string(), Image(4, 4, Color3f(0.5f))); // an envmap needs 2 x 3
    write_vdb_grid((dir / "grid.vdb").string());
}

} // namespace

bool verbose() {
    static const bool on = std::getenv("PENUMBRA_FUZZ_VERBOSE") != nullptr;
    return on;
}

// In memory (/dev/shm) when available: rewriting a file on a disk file system every execution stalls now and
// then for seconds (ext4 flushes a truncated file's data on close), which libFuzzer reports as a timeout.
const std::string& scratch_dir() {
    struct Dir {
        std::filesystem::path path;
        Dir() {
            std::error_code ec;
            const std::filesystem::path shm = "/dev/shm";
            const std::filesystem::path base =
                std::filesystem::is_directory(shm, ec) ? shm : std::filesystem::temp_directory_path();
            path = base / ("penumbra_fuzz_" + std::to_string(::getpid()));
            std::filesystem::create_directories(path);
        }
        ~Dir() {
            std::error_code ignored;
            std::filesystem::remove_all(path, ignored);
        }
    };
    static const Dir dir;
    static const std::string path = dir.path.string();
    return path;
}

std::string write_input(const std::string& name, const uint8_t* data, size_t size) {
    const std::string path = scratch_dir() + "/" + name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path;
}

const std::string& fixture_dir() {
    static const bool written = (write_fixtures(scratch_dir()), true);
    (void)written;
    return scratch_dir();
}

} // namespace penumbra::fuzz
