// Reader of OpenVDB .vdb files for `gridvolume`: one float grid, densified over its active voxel bounding box
// into the .vol layout (one channel). OpenVDB's voxel (i, j, k) is centred at index-space point (i, j, k) and
// placed in the world by the grid's (linear) transform; the dense grid's unit cube therefore spans the index
// box [lo - 1/2, hi + 1/2] of the active voxels, mapped by that transform.
//
// File layout (io::Archive, format 222-224): magic, version, library version, a has-grid-offsets flag, a
// 36-character UUID, file metadata, a grid count, then per grid a descriptor (unique name, type, instance
// parent, three stream offsets) followed by the grid: compression flags, metadata, transform, and, unless the
// grid is an instance of another, its tree (vdb_layout.cpp).
#include "scene/volumes/vdb_layout.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>

namespace penumbra {

namespace {

constexpr int64_t Magic = 0x56444220;
constexpr uint32_t OldestVersion = 222, NewestVersion = 224;
constexpr const char* FloatTreeType = "Tree_float_5_4_3";
constexpr const char* HalfSuffix = "_HalfFloat";
constexpr char UniqueSuffixSeparator = '\x1e';

struct GridDescriptor {
    std::string unique_name, name, type, parent;
    bool half = false;
    uint64_t grid_pos = 0; // where the grid follows its descriptor
    uint64_t end_pos = 0;  // where it ends: its end offset, or the end of a file without offsets
    bool is_float() const { return type == FloatTreeType; }
    // "float" of Tree_float_5_4_3: the value type OpenVDB names in Grid::valueType().
    std::string value_type() const {
        std::string t = type.rfind("Tree_", 0) == 0 ? type.substr(5) : type;
        const size_t config = t.find("_5_4_3");
        return config == std::string::npos ? t : t.substr(0, config);
    }
};

// OpenVDB's row-vector affine map (world = index * M), or none for a frustum.
struct IndexToWorld {
    double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    bool linear = true;
};

struct ParsedGrid {
    IndexToWorld transform;
    std::optional<VdbFloatTree> tree; // absent for an instance
};

// A name from the file, fit for a message: at most 64 characters, non-printable ones as '?'.
std::string printable(const std::string& name) {
    std::string p;
    for (size_t i = 0; i < name.size() && i < 64; ++i)
        p += std::isprint(uint8_t(name[i])) ? name[i] : '?';
    return name.size() > 64 ? p + "..." : p;
}
std::string quoted(const std::string& name) { return "'" + printable(name) + "'"; }

void skip_metadata(VdbInput& in) {
    const uint32_t count = in.read<uint32_t>();
    for (uint32_t i = 0; i < count; ++i) {
        in.read_string(); // name
        in.read_string(); // type
        in.skip(in.read<uint32_t>());
    }
}

// Archive::readHeader; returns whether the grids carry their stream offsets.
bool read_header(VdbInput& in) {
    if (in.size() < 8 || in.read<int64_t>() != Magic) throw VdbCorrupt("no OpenVDB magic number");
    const uint32_t version = in.read<uint32_t>();
    if (version < OldestVersion || version > NewestVersion)
        throw VolumeFileError("file format version " + std::to_string(version) + " (penumbra reads " +
                              std::to_string(OldestVersion) + " to " + std::to_string(NewestVersion) +
                              ": files of OpenVDB 3.0 and later)");
    in.skip(8); // library major and minor version
    const bool has_offsets = in.read<uint8_t>() != 0;
    in.skip(36); // UUID
    skip_metadata(in);
    return has_offsets;
}

GridDescriptor read_descriptor(VdbInput& in) {
    GridDescriptor d;
    d.unique_name = in.read_string();
    d.name = d.unique_name.substr(0, d.unique_name.find(UniqueSuffixSeparator));
    d.type = in.read_string();
    const std::string suffix = HalfSuffix;
    if (d.type.size() > suffix.size() &&
        d.type.compare(d.type.size() - suffix.size(), suffix.size(), suffix) == 0) {
        d.half = true;
        d.type.resize(d.type.size() - suffix.size());
    }
    d.parent = in.read_string();
    in.skip(16);                              // grid and block positions
    d.end_pos = uint64_t(in.read<int64_t>()); // checked when the file has offsets
    d.grid_pos = in.tell();
    return d;
}

// Transform::read: a map type name, then the map (math/Maps.h), each vector 3 doubles, a matrix 16.
IndexToWorld read_transform(VdbInput& in, bool allow_frustum = true) {
    const std::string type = in.read_string();
    IndexToWorld t;
    auto vec3 = [&] {
        std::array<double, 3> v;
        in.read(v.data(), 24);
        return v;
    };
    if (type == "AffineMap" || type == "UnitaryMap") {
        in.read(t.m, 128);
    } else if (type == "ScaleMap" || type == "UniformScaleMap" || type == "ScaleTranslateMap" ||
               type == "UniformScaleTranslateMap") {
        const bool translates = type.find("Translate") != std::string::npos;
        const auto translation = translates ? vec3() : std::array<double, 3>{0, 0, 0};
        const auto scale = vec3();
        in.skip(4 * 24); // voxel size, inverse scale, inverse squared scale, inverse twice scale
        for (int a = 0; a < 3; ++a) {
            t.m[a][a] = scale[size_t(a)];
            t.m[3][a] = translation[size_t(a)];
        }
    } else if (type == "TranslationMap") {
        const auto translation = vec3();
        for (int a = 0; a < 3; ++a)
            t.m[3][a] = translation[size_t(a)];
    } else if (type == "NonlinearFrustumMap" && allow_frustum) {
        in.skip(8 * 8);            // bounding box, taper, depth
        read_transform(in, false); // its linear second map
        t.linear = false;
    } else {
        throw VdbCorrupt("an unknown transform map " + quoted(type));
    }
    return t;
}

// Archive::readGrid for a float grid.
ParsedGrid read_grid(VdbInput& in, const GridDescriptor& d, VdbBudget& budget) {
    VdbValueCodec codec;
    codec.compression = in.read<uint32_t>();
    codec.half = d.half;
    skip_metadata(in);
    ParsedGrid grid;
    grid.transform = read_transform(in);
    if (d.parent.empty()) grid.tree = read_vdb_float_tree(in, codec, budget);
    return grid;
}

// The first 16 grids, each with its value type.
std::string grid_list(const std::vector<GridDescriptor>& grids) {
    std::string names;
    for (size_t i = 0; i < grids.size() && i < 16; ++i) {
        names += (names.empty() ? "" : ", ") + quoted(grids[i].name) + " (" +
                 printable(grids[i].value_type()) + ")";
    }
    if (grids.size() > 16) names += ", and " + std::to_string(grids.size() - 16) + " more";
    return names.empty() ? std::string("no grids") : names;
}

// The grid to read: `wanted`, or "density" if it is a float grid, or the first float grid in file order.
size_t choose_grid(const std::vector<GridDescriptor>& grids, const std::string& wanted,
                   const std::string& unread) {
    if (!wanted.empty()) {
        for (size_t i = 0; i < grids.size(); ++i) {
            if (grids[i].name != wanted) continue;
            if (!grids[i].is_float())
                throw VolumeFileError("grid " + quoted(wanted) + " holds " +
                                      printable(grids[i].value_type()) + " values, not float");
            return i;
        }
        throw VolumeFileError("no grid named " + quoted(wanted) + " (the file holds " + grid_list(grids) +
                              unread + ")");
    }
    for (size_t i = 0; i < grids.size(); ++i)
        if (grids[i].name == "density" && grids[i].is_float()) return i;
    for (size_t i = 0; i < grids.size(); ++i)
        if (grids[i].is_float()) return i;
    throw VolumeFileError("no float grid (the file holds " + grid_list(grids) + unread + ")");
}

// The tree a grid uses: its own, or that of the grid it is an instance of (Archive::connectInstance).
const VdbFloatTree& instance_tree(VdbInput& in, const std::vector<GridDescriptor>& grids,
                                  std::map<std::string, ParsedGrid>& parsed, size_t index,
                                  VdbBudget& budget) {
    std::map<std::string, size_t> by_unique_name;
    for (size_t i = 0; i < grids.size(); ++i)
        by_unique_name.emplace(grids[i].unique_name, i);
    for (size_t hops = 0; hops <= grids.size(); ++hops) {
        const GridDescriptor& d = grids[index];
        auto it = parsed.find(d.unique_name);
        if (it == parsed.end()) {
            // Each grid is read within its own bytes, so that no file makes the reader pass over one twice.
            in.seek(d.grid_pos);
            in.set_limit(d.end_pos);
            it = parsed.emplace(d.unique_name, read_grid(in, d, budget)).first;
            in.set_limit(in.size());
        }
        if (it->second.tree) return *it->second.tree;
        const auto parent = by_unique_name.find(d.parent);
        if (parent == by_unique_name.end() || !grids[parent->second].is_float() ||
            grids[parent->second].half != d.half)
            throw VdbCorrupt("grid " + quoted(d.name) + " is an instance of a missing or different grid");
        index = parent->second;
    }
    throw VdbCorrupt("a cycle of grid instances");
}

// Column-vector 4x4 matrix of OpenVDB's row-vector affine map.
Transform index_to_world(const IndexToWorld& t, const std::string& name) {
    Matrix4 r = Matrix4::identity();
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col)
            r.m[row][col] = float(t.m[col][row]);
        r.m[row][3] = float(t.m[3][row]);
    }
    const double det = t.m[0][0] * (t.m[1][1] * t.m[2][2] - t.m[1][2] * t.m[2][1]) -
                       t.m[0][1] * (t.m[1][0] * t.m[2][2] - t.m[1][2] * t.m[2][0]) +
                       t.m[0][2] * (t.m[1][0] * t.m[2][1] - t.m[1][1] * t.m[2][0]);
    bool finite = std::isfinite(det) && det != 0.0;
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col)
            finite = finite && std::isfinite(r.m[row][col]);
    if (!finite) throw VolumeFileError("grid " + name + " has a singular or non-finite transform");
    return Transform(r);
}

struct Box {
    int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
    bool empty() const { return lo[0] > hi[0]; }
    void extend(const std::array<int32_t, 3>& origin, int64_t size) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], int64_t(origin[size_t(a)]));
            hi[a] = std::max(hi[a], int64_t(origin[size_t(a)]) + size - 1);
        }
    }
};

// Tree::evalActiveVoxelBoundingBox: active tiles and active leaf voxels.
Box active_box(const VdbFloatTree& tree) {
    Box box;
    for (const VdbTile& t : tree.tiles)
        if (t.active) box.extend(t.origin, t.size);
    for (const VdbLeaf& leaf : tree.leaves)
        for (int n = 0; n < 512; ++n)
            if ((leaf.active[size_t(n >> 6)] >> (n & 63)) & 1)
                box.extend(
                    {leaf.origin[0] + (n >> 6), leaf.origin[1] + ((n >> 3) & 7), leaf.origin[2] + (n & 7)},
                    1);
    return box;
}

// The tree's value at every voxel of `box` (tiles and leaves never overlap; elsewhere the background).
std::vector<float> densify(const VdbFloatTree& tree, const Box& box, const int64_t dim[3]) {
    std::vector<float> values(size_t(dim[0] * dim[1] * dim[2]), tree.background);
    auto paint = [&](const std::array<int32_t, 3>& origin, int64_t size, auto&& value_at) {
        int64_t from[3], to[3];
        for (int a = 0; a < 3; ++a) {
            from[a] = std::max(box.lo[a], int64_t(origin[size_t(a)]));
            to[a] = std::min(box.hi[a], int64_t(origin[size_t(a)]) + size - 1);
            if (from[a] > to[a]) return;
        }
        for (int64_t z = from[2]; z <= to[2]; ++z)
            for (int64_t y = from[1]; y <= to[1]; ++y)
                for (int64_t x = from[0]; x <= to[0]; ++x)
                    values[size_t(((z - box.lo[2]) * dim[1] + (y - box.lo[1])) * dim[0] + (x - box.lo[0]))] =
                        value_at(x - origin[0], y - origin[1], z - origin[2]);
    };
    for (const VdbTile& t : tree.tiles)
        paint(t.origin, t.size, [&](int64_t, int64_t, int64_t) { return t.value; });
    for (const VdbLeaf& leaf : tree.leaves)
        paint(leaf.origin, 8,
              [&](int64_t x, int64_t y, int64_t z) { return leaf.values[size_t((x << 6) | (y << 3) | z)]; });
    return values;
}

} // namespace

VolumeGridData read_vdb_file(const std::string& path, const std::string& grid_name, uint64_t max_voxels) {
    VdbInput in(path);
    std::vector<GridDescriptor> grids;
    std::map<std::string, ParsedGrid> parsed; // by unique name
    VdbBudget budget(max_voxels);
    std::string unread;
    size_t chosen = 0;
    const VdbFloatTree* tree = nullptr;
    try {
        const bool has_offsets = read_header(in);
        const int32_t count = in.read<int32_t>();
        if (count < 0) throw VdbCorrupt("a negative grid count");
        for (int32_t g = 0; g < count; ++g) {
            grids.push_back(read_descriptor(in));
            GridDescriptor& d = grids.back();
            if (has_offsets) {
                // The end offset is the only one used: where the next descriptor starts.
                if (d.end_pos < d.grid_pos || d.end_pos > in.size())
                    throw VdbCorrupt("a grid's end offset outside the file");
                in.seek(d.end_pos);
            } else if (d.is_float()) {
                d.end_pos = in.size();
                parsed.emplace(d.unique_name, read_grid(in, d, budget));
            } else {
                // A grid of another type cannot be stepped over in a file written without offsets.
                unread =
                    "; grids after " + quoted(d.name) + " cannot be reached in a file without grid offsets";
                break;
            }
        }
        chosen = choose_grid(grids, grid_name, unread);
        tree = &instance_tree(in, grids, parsed, chosen, budget); // map nodes stay where they are
    } catch (const VdbCorrupt& e) {
        throw VolumeFileError(std::string("not a readable OpenVDB file (") + e.what() + ")");
    }
    const std::string name = quoted(grids[chosen].name);
    const ParsedGrid& grid = parsed.at(grids[chosen].unique_name);
    if (!grid.transform.linear)
        throw VolumeFileError("grid " + name +
                              " has a non-linear (frustum) transform, which is not supported");

    const Box box = active_box(*tree);
    if (box.empty()) throw VolumeFileError("grid " + name + " has no active voxels");
    const int64_t dim[3] = {box.hi[0] - box.lo[0] + 1, box.hi[1] - box.lo[1] + 1, box.hi[2] - box.lo[2] + 1};
    if (dim[0] > int64_t(max_voxels) || dim[1] > int64_t(max_voxels) || dim[2] > int64_t(max_voxels) ||
        uint64_t(dim[0] * dim[1]) > max_voxels || uint64_t(dim[0] * dim[1] * dim[2]) > max_voxels)
        throw VolumeFileError("grid " + name + " spans " + std::to_string(dim[0]) + " x " +
                              std::to_string(dim[1]) + " x " + std::to_string(dim[2]) +
                              " voxels, too many to store densely");

    VolumeGridData out;
    out.res = Vec3i(int(dim[0]), int(dim[1]), int(dim[2]));
    out.channels = 1;
    out.values = densify(*tree, box, dim);
    for (size_t i = 0; i < out.values.size(); ++i) {
        if (std::isfinite(out.values[i])) continue;
        const int64_t x = int64_t(i) % dim[0], y = int64_t(i) / dim[0] % dim[1],
                      z = int64_t(i) / (dim[0] * dim[1]);
        throw VolumeFileError("grid " + name + " has a non-finite value at voxel (" +
                              std::to_string(box.lo[0] + x) + ", " + std::to_string(box.lo[1] + y) + ", " +
                              std::to_string(box.lo[2] + z) + ")");
    }
    const Vec3f lo(float(box.lo[0]) - 0.5f, float(box.lo[1]) - 0.5f, float(box.lo[2]) - 0.5f);
    out.unit_to_file = index_to_world(grid.transform, name) * Transform::translate(lo) *
                       Transform::scale(Vec3f(float(dim[0]), float(dim[1]), float(dim[2])));
    out.has_placement = true;
    return out;
}

} // namespace penumbra
