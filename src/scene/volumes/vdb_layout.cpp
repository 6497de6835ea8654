// Reading of a float tree in OpenVDB's layout (see vdb_layout.h). Node values go through
// read_node_values (OpenVDB's io::readCompressedValues): a metadata byte saying which inactive values were
// dropped, then the kept values in one chunk, raw, zlib- or Blosc-compressed, as floats or halves.
#include "scene/volumes/vdb_layout.h"

#include <Imath/half.h>
#include <blosc.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>

namespace penumbra {

static_assert(std::endian::native == std::endian::little, "the .vdb reader assumes a little-endian host");

VdbInput::VdbInput(const std::string& path) : in_(path, std::ios::binary | std::ios::ate) {
    const std::streamoff end = in_ ? std::streamoff(in_.tellg()) : -1;
    if (end < 0) throw VolumeFileError("cannot open the file");
    size_ = limit_ = uint64_t(end);
    in_.seekg(0);
}

void VdbInput::seek(uint64_t pos) {
    if (pos > limit_) throw VdbCorrupt("a size in it reaches past its end");
    in_.seekg(std::streamoff(pos));
    pos_ = pos;
}

void VdbInput::read(void* dst, uint64_t bytes) {
    if (bytes > remaining()) throw VdbCorrupt("it ends early, or a size in it reaches past its end");
    if (bytes == 0) return;
    in_.read(static_cast<char*>(dst), std::streamsize(bytes));
    if (!in_) throw VolumeFileError("a read error");
    pos_ += bytes;
}

std::string VdbInput::read_string() {
    const uint32_t length = read<uint32_t>();
    if (length > remaining()) throw VdbCorrupt("a string's length reaches past its end");
    std::string s(length, '\0');
    read(s.data(), length);
    return s;
}

namespace {

// Node sizes of the 5-4-3 tree: log2 of the slots per axis, and log2 of the voxels a slot spans per axis.
struct NodeLevel {
    int log2_dim;
    int child_log2;
    int slots() const { return 1 << (3 * log2_dim); }
    int words() const { return slots() / 64; }
};
constexpr NodeLevel Upper{5, 7}, Lower{4, 3}, Leaf{3, 0};
constexpr int RootChildSize = 1 << 12;

enum ValueMetadata : int8_t { // OpenVDB's io::NO_MASK_OR_INACTIVE_VALS ... NO_MASK_AND_ALL_VALS
    NoMaskOrInactiveVals,
    NoMaskAndMinusBg,
    NoMaskAndOneInactiveVal,
    MaskAndNoInactiveVals,
    MaskAndOneInactiveVal,
    MaskAndTwoInactiveVals,
    NoMaskAndAllVals
};

bool bit(const uint64_t* mask, int n) { return (mask[n >> 6] >> (n & 63)) & 1; }

std::vector<uint64_t> read_mask(VdbInput& in, int words) {
    std::vector<uint64_t> mask(size_t(words), 0);
    in.read(mask.data(), uint64_t(words) * 8);
    return mask;
}

// Origin of slot n of a node at `origin` whose slots span 2^child_log2 voxels.
std::array<int32_t, 3> slot_origin(const std::array<int32_t, 3>& origin, const NodeLevel& level, int n) {
    const int dim = (1 << level.log2_dim) - 1;
    const int local[3] = {n >> (2 * level.log2_dim), (n >> level.log2_dim) & dim, n & dim};
    std::array<int32_t, 3> o;
    for (int a = 0; a < 3; ++a)
        o[a] = origin[a] + (local[a] << level.child_log2);
    return o;
}

std::string byte_count(uint64_t n) { return std::to_string(n) + (n == 1 ? " byte" : " bytes"); }

// One chunk of `bytes` bytes (io::readData): an int64 size, negative for stored bytes, positive for a zlib
// or Blosc stream of that size which must expand to exactly `bytes`.
void read_chunk(VdbInput& in, uint32_t compression, char* dst, uint64_t bytes) {
    if (!(compression & (VdbValueCodec::Zip | VdbValueCodec::Blosc))) return in.read(dst, bytes);
    const int64_t stated = in.read<int64_t>();
    if (stated <= 0) {
        const uint64_t stored = uint64_t(0) - uint64_t(stated);
        if (stored != bytes)
            throw VdbCorrupt("a stored chunk of " + byte_count(stored) + " where " + byte_count(bytes) +
                             " are expected");
        return in.read(dst, bytes);
    }
    if (uint64_t(stated) > in.remaining()) throw VdbCorrupt("a chunk's size reaches past its end");
    std::vector<char> packed(size_t(stated), 0);
    in.read(packed.data(), packed.size());
    if (bytes == 0) return;
    if (compression & VdbValueCodec::Blosc) {
        size_t expands_to = 0;
        if (blosc_cbuffer_validate(packed.data(), packed.size(), &expands_to) < 0 || expands_to != bytes ||
            blosc_decompress_ctx(packed.data(), dst, bytes, 1) != int(bytes))
            throw VdbCorrupt("a Blosc chunk that does not expand to " + byte_count(bytes));
        return;
    }
    uLongf unpacked = uLongf(bytes);
    if (uncompress(reinterpret_cast<Bytef*>(dst), &unpacked, reinterpret_cast<const Bytef*>(packed.data()),
                   uLong(packed.size())) != Z_OK ||
        unpacked != bytes)
        throw VdbCorrupt("a zlib chunk that does not expand to " + byte_count(bytes));
}

// `count` float values, stored as floats or as halves (io::HalfReader: nothing at all for none).
void read_floats(VdbInput& in, const VdbValueCodec& codec, float* dst, int count) {
    if (!codec.half)
        return read_chunk(in, codec.compression, reinterpret_cast<char*>(dst), uint64_t(count) * 4);
    if (count < 1) return;
    std::vector<uint16_t> halves(size_t(count), 0);
    read_chunk(in, codec.compression, reinterpret_cast<char*>(halves.data()), uint64_t(count) * 2);
    for (int i = 0; i < count; ++i)
        dst[i] = imath_half_to_float(halves[i]);
}

// The `level.slots()` values of a node, into `values` (io::readCompressedValues). With active-mask
// compression only the active values are stored; the inactive ones are the background, its negative, or one
// or two values stored once, chosen per voxel by a selection mask.
void read_node_values(VdbInput& in, const VdbValueCodec& codec, const NodeLevel& level,
                      const uint64_t* active, float background, float* values) {
    const int8_t metadata = in.read<int8_t>();
    if (metadata < NoMaskOrInactiveVals || metadata > NoMaskAndAllVals)
        throw VdbCorrupt("a node's value metadata " + std::to_string(int(metadata)) + " (0 to 6 expected)");
    float inactive[2] = {metadata == NoMaskOrInactiveVals ? background : -background, background};
    if (metadata == NoMaskAndOneInactiveVal || metadata == MaskAndOneInactiveVal ||
        metadata == MaskAndTwoInactiveVals) {
        inactive[0] = in.read<float>();
        if (metadata == MaskAndTwoInactiveVals) inactive[1] = in.read<float>();
    }
    std::vector<uint64_t> selection(size_t(level.words()), 0);
    if (metadata == MaskAndNoInactiveVals || metadata == MaskAndOneInactiveVal ||
        metadata == MaskAndTwoInactiveVals)
        selection = read_mask(in, level.words());

    const int slots = level.slots();
    int stored = slots;
    if ((codec.compression & VdbValueCodec::ActiveMask) && metadata != NoMaskAndAllVals) {
        stored = 0;
        for (int w = 0; w < level.words(); ++w)
            stored += std::popcount(active[w]);
    }
    if (stored == slots) return read_floats(in, codec, values, slots);
    std::vector<float> kept(size_t(stored), 0.f);
    read_floats(in, codec, kept.data(), stored);
    for (int n = 0, k = 0; n < slots; ++n)
        values[n] = bit(active, n) ? kept[size_t(k++)] : inactive[bit(selection.data(), n)];
}

class TreeReader {
  public:
    TreeReader(VdbInput& in, const VdbValueCodec& codec, VdbBudget& budget)
        : in_(in), codec_(codec), budget_(budget) {}

    VdbFloatTree read() {
        in_.read<int32_t>(); // buffer count: 1 since OpenVDB 3
        tree_.background = in_.read<float>();
        const uint32_t tiles = in_.read<uint32_t>(), children = in_.read<uint32_t>();
        if (uint64_t(tiles) * 17 > in_.remaining()) throw VdbCorrupt("a root tile count beyond its end");
        std::set<std::array<int32_t, 3>> root_entries;                             // tiles and children
        std::map<std::array<int32_t, 3>, std::pair<size_t, size_t>> root_children; // origin -> leaf range
        auto read_root_origin = [&] {
            std::array<int32_t, 3> origin;
            in_.read(origin.data(), 12);
            for (int32_t c : origin)
                if (c % RootChildSize != 0) throw VdbCorrupt("a root entry's origin off the 4096-voxel grid");
            if (!root_entries.insert(origin).second) throw VdbCorrupt("two root entries at one origin");
            return origin;
        };
        for (uint32_t t = 0; t < tiles; ++t) {
            const auto origin = read_root_origin();
            const float value = in_.read<float>();
            const bool active = in_.read<uint8_t>() != 0;
            keep_tile(origin, RootChildSize, value, active);
        }
        for (uint32_t c = 0; c < children; ++c) {
            const auto origin = read_root_origin();
            const size_t first = tree_.leaves.size();
            read_node_topology(Upper, origin);
            root_children[origin] = {first, tree_.leaves.size()};
        }
        // Tree::readBuffers: leaves in the root's coordinate order, depth first within a child.
        for (const auto& [origin, range] : root_children)
            for (size_t l = range.first; l < range.second; ++l)
                read_leaf_buffer(tree_.leaves[l]);
        return std::move(tree_);
    }

  private:
    void keep_tile(const std::array<int32_t, 3>& origin, int32_t size, float value, bool active) {
        if (!active && std::memcmp(&value, &tree_.background, sizeof(float)) == 0) return;
        if (budget_.tiles == 0)
            throw VolumeFileError("too many tiles (more than 2^22 active or non-background)");
        --budget_.tiles;
        tree_.tiles.push_back({origin, size, value, active});
    }

    // InternalNode::readTopology: child and value masks, the slots' values, then the children in slot order
    // (LeafNode::readTopology: a value mask, read again with the leaf's buffer).
    void read_node_topology(const NodeLevel& level, const std::array<int32_t, 3>& origin) {
        const auto child_mask = read_mask(in_, level.words());
        const auto value_mask = read_mask(in_, level.words());
        std::vector<float> values(size_t(level.slots()), 0.f);
        read_node_values(in_, codec_, level, value_mask.data(), tree_.background, values.data());
        for (int n = 0; n < level.slots(); ++n)
            if (!bit(child_mask.data(), n))
                keep_tile(slot_origin(origin, level, n), 1 << level.child_log2, values[size_t(n)],
                          bit(value_mask.data(), n));
        for (int n = 0; n < level.slots(); ++n) {
            if (!bit(child_mask.data(), n)) continue;
            const auto child = slot_origin(origin, level, n);
            if (level.log2_dim == Upper.log2_dim) {
                read_node_topology(Lower, child);
                continue;
            }
            if (budget_.leaves == 0)
                throw VolumeFileError("too many leaf nodes (more than " + std::to_string(budget_.max_leaves) +
                                      ")");
            --budget_.leaves;
            in_.skip(uint64_t(Leaf.words()) * 8);
            tree_.leaves.emplace_back();
            tree_.leaves.back().origin = child;
        }
    }

    // LeafNode::readBuffers: the value mask (which stands), then the voxel values.
    void read_leaf_buffer(VdbLeaf& leaf) {
        in_.read(leaf.active.data(), 64);
        read_node_values(in_, codec_, Leaf, leaf.active.data(), tree_.background, leaf.values.data());
    }

    VdbInput& in_;
    const VdbValueCodec& codec_;
    VdbBudget& budget_;
    VdbFloatTree tree_;
};

} // namespace

VdbFloatTree read_vdb_float_tree(VdbInput& in, const VdbValueCodec& codec, VdbBudget& budget) {
    return TreeReader(in, codec, budget).read();
}

} // namespace penumbra
