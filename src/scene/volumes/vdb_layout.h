// OpenVDB's binary layout (file format versions 222-224, written by OpenVDB 3.0 and later), read with every
// size and count a file states checked against the bytes left before anything is allocated or copied.
// penumbra reads .vdb files itself rather than through OpenVDB 10 (Debian's), whose reader copies a chunk of
// a stated size into a buffer of the expected size before comparing the two (docs/fuzzing.md, "OpenVDB").
#pragma once
#include "scene/volumes/volume_grid.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace penumbra {

// The file is not a well-formed .vdb file; read_vdb_file reports it as "not a readable OpenVDB file (...)".
class VdbCorrupt : public VolumeFileError {
  public:
    using VolumeFileError::VolumeFileError;
};

// A little-endian file read sequentially; a read past the end throws VdbCorrupt.
class VdbInput {
  public:
    explicit VdbInput(const std::string& path);

    uint64_t size() const { return size_; }
    uint64_t tell() const { return pos_; }
    uint64_t remaining() const { return limit_ - pos_; }
    // Reads and seeks end at `limit` (a grid's end offset) instead of the end of the file.
    void set_limit(uint64_t limit) { limit_ = std::min(std::max(limit, pos_), size_); }
    void seek(uint64_t pos);
    void skip(uint64_t bytes) { seek(pos_ + std::min(bytes, remaining() + 1)); }
    void read(void* dst, uint64_t bytes);
    template <typename T> T read() {
        T v;
        read(&v, sizeof(T));
        return v;
    }
    // A uint32 length, then that many bytes.
    std::string read_string();

  private:
    std::ifstream in_;
    uint64_t size_ = 0, limit_ = 0, pos_ = 0;
};

// How a grid's node values are stored: the grid's compression flags (OpenVDB's io::COMPRESS_*) and whether
// float values are saved as 16-bit halves.
struct VdbValueCodec {
    static constexpr uint32_t Zip = 0x1, ActiveMask = 0x2, Blosc = 0x4;
    uint32_t compression = 0;
    bool half = false;
};

// An 8^3 leaf of a float tree: voxel n = (x << 6) | (y << 3) | z of the leaf, x slowest.
struct VdbLeaf {
    std::array<int32_t, 3> origin;
    std::array<uint64_t, 8> active;
    std::array<float, 512> values;
};

// A constant cube of `size`^3 voxels at a root or internal node slot (only tiles that are active or differ
// from the background are kept).
struct VdbTile {
    std::array<int32_t, 3> origin;
    int32_t size;
    float value;
    bool active;
};

// A float tree of OpenVDB's standard configuration (Tree_float_5_4_3): root -> 32^3 -> 16^3 -> 8^3 leaves.
struct VdbFloatTree {
    float background = 0.f;
    std::vector<VdbTile> tiles;
    std::vector<VdbLeaf> leaves;
};

// Caps on what a file may make the reader hold, shared by all the trees of one file: as many leaves as the
// dense grid's voxel cap fills, and 2^22 kept tiles.
struct VdbBudget {
    explicit VdbBudget(uint64_t max_voxels)
        : max_leaves(std::max<uint64_t>(max_voxels / 512, 1)), leaves(max_leaves) {}
    uint64_t max_leaves, leaves;
    uint64_t tiles = uint64_t(1) << 22;
};

// A grid's tree: its topology (Tree::readTopology: buffer count, root, then nodes depth first) and then its
// buffers (Tree::readBuffers: leaf values, root children in coordinate order).
VdbFloatTree read_vdb_float_tree(VdbInput& in, const VdbValueCodec& codec, VdbBudget& budget);

} // namespace penumbra
