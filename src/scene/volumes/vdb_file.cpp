// Reader of OpenVDB .vdb files for `gridvolume`: one float grid, densified over its active voxel bounding box
// into the .vol layout (one channel). OpenVDB's voxel (i, j, k) is centred at index-space point (i, j, k) and
// placed in the world by the grid's (linear) transform; the dense grid's unit cube therefore spans the index
// box [lo - 1/2, hi + 1/2] of the active voxels, mapped by that transform.
#include "scene/volumes/volume_grid.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <fstream>
#include <mutex>

namespace penumbra {

namespace {

// Larger grids would take more than 1 GiB once dense.
constexpr uint64_t MaxDenseVoxels = uint64_t(1) << 28;

std::string grid_list(const openvdb::GridPtrVec& grids) {
    std::string names;
    for (const auto& g : grids)
        names += (names.empty() ? "" : ", ") + ("'" + g->getName() + "' (" + g->valueType() + ")");
    return names.empty() ? std::string("no grids") : names;
}

// The grid to read: `wanted`, or "density" if it is a float grid, or the first float grid in file order.
std::string choose_grid(const openvdb::GridPtrVec& grids, const std::string& wanted) {
    if (!wanted.empty()) {
        for (const auto& g : grids) {
            if (g->getName() != wanted) continue;
            if (!g->isType<openvdb::FloatGrid>())
                throw VolumeFileError("grid '" + wanted + "' holds " + g->valueType() + " values, not float");
            return wanted;
        }
        throw VolumeFileError("no grid named '" + wanted + "' (the file holds " + grid_list(grids) + ")");
    }
    for (const auto& g : grids)
        if (g->getName() == "density" && g->isType<openvdb::FloatGrid>()) return "density";
    for (const auto& g : grids)
        if (g->isType<openvdb::FloatGrid>()) return g->getName();
    throw VolumeFileError("no float grid (the file holds " + grid_list(grids) + ")");
}

// Column-vector 4x4 matrix of OpenVDB's row-vector affine map (world = index * M).
Transform index_to_world(const openvdb::math::Transform& transform) {
    const openvdb::Mat4d m = transform.baseMap()->getAffineMap()->getMat4();
    Matrix4 r = Matrix4::identity();
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col)
            r.m[row][col] = float(m(col, row));
        r.m[row][3] = float(m(3, row));
    }
    return Transform(r);
}

} // namespace

VolumeGridData read_vdb_file(const std::string& path, const std::string& grid_name) {
    static std::once_flag initialized;
    std::call_once(initialized, [] { openvdb::initialize(); });
    openvdb::FloatGrid::Ptr grid;
    std::string name;
    try {
        // OpenVDB's reader takes the counts in a file on trust (a corrupt tile count loops for minutes), but
        // not past the end of the file when the stream throws there: we read through io::Stream from an
        // ifstream that does (docs/fuzzing.md, "OpenVDB"). io::Stream reads every grid of the file.
        std::ifstream in(path, std::ios::binary);
        if (!in) throw VolumeFileError("cannot open the file");
        in.exceptions(std::ios::failbit | std::ios::badbit | std::ios::eofbit);
        openvdb::io::Stream stream(in, false);
        const openvdb::GridPtrVecPtr grids = stream.getGrids();
        name = choose_grid(*grids, grid_name);
        for (const auto& g : *grids)
            if (!grid && g->getName() == name) grid = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    } catch (const VolumeFileError&) {
        throw;
    } catch (const std::ios_base::failure&) {
        throw VolumeFileError("not a readable OpenVDB file (it ends early, or a size in it reaches past its end)");
    } catch (const std::exception& e) {
        throw VolumeFileError(std::string("not a readable OpenVDB file (") + e.what() + ")");
    }
    if (!grid) throw VolumeFileError("grid '" + name + "' could not be read as a float grid");
    if (!grid->transform().isLinear())
        throw VolumeFileError("grid '" + name +
                              "' has a non-linear (frustum) transform, which is not supported");
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    if (box.empty()) throw VolumeFileError("grid '" + name + "' has no active voxels");
    const openvdb::Coord dim = box.dim();
    const uint64_t count = uint64_t(dim.x()) * uint64_t(dim.y()) * uint64_t(dim.z());
    if (count > MaxDenseVoxels)
        throw VolumeFileError("grid '" + name + "' spans " + std::to_string(dim.x()) + " x " +
                              std::to_string(dim.y()) + " x " + std::to_string(dim.z()) +
                              " voxels, too many to store densely");

    VolumeGridData out;
    out.res = Vec3i(dim.x(), dim.y(), dim.z());
    out.channels = 1;
    out.values.resize(count);
    const auto accessor = grid->getConstAccessor();
    size_t i = 0;
    for (int z = 0; z < dim.z(); ++z)
        for (int y = 0; y < dim.y(); ++y)
            for (int x = 0; x < dim.x(); ++x, ++i) {
                const openvdb::Coord ijk = box.min() + openvdb::Coord(x, y, z);
                const float v = accessor.getValue(ijk);
                if (!std::isfinite(v))
                    throw VolumeFileError("grid '" + name + "' has a non-finite value at voxel (" +
                                          std::to_string(ijk.x()) + ", " + std::to_string(ijk.y()) + ", " +
                                          std::to_string(ijk.z()) + ")");
                out.values[i] = v;
            }
    const Vec3f lo(float(box.min().x()) - 0.5f, float(box.min().y()) - 0.5f, float(box.min().z()) - 0.5f);
    out.unit_to_file = index_to_world(grid->transform()) * Transform::translate(lo) *
                       Transform::scale(Vec3f(float(dim.x()), float(dim.y()), float(dim.z())));
    out.has_placement = true;
    return out;
}

} // namespace penumbra
