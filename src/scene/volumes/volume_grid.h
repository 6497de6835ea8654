// Dense voxel grids read from disk for the `gridvolume` plugin: Mitsuba's binary .vol format and OpenVDB
// .vdb files (one float grid, densified over its active voxels). Both give the same in-memory layout, so
// that gridvolume has one lookup code path.
#pragma once
#include "core/transform.h"
#include "scene/volume.h"

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace penumbra {

// What is wrong with a volume file (without the file's name or the XML location: the caller adds them).
class VolumeFileError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

struct VolumeGridData {
    Vec3i res{0, 0, 0}; // cells along x, y, z
    int channels = 1;   // 1 or 3
    // values[((z * res.y + y) * res.x + x) * channels + c]: Mitsuba's .vol order.
    std::vector<float> values;
    // Maps the unit cube [0, 1]^3 (the grid's texture space, voxel (i, j, k) centred at ((i, j, k) + 1/2) /
    // res) to the file's own frame: the .vol header's bounding box, or the .vdb grid's index-to-world
    // transform of its active voxels. Absent (false) when a .vol bounding box is degenerate or non-finite.
    Transform unit_to_file;
    bool has_placement = false;
};

// Mitsuba's .vol (version 3, float32 encoding, 1 or 3 channels). Throws VolumeFileError for a file that is
// unreadable, truncated or longer than its header says, has a bad magic, version, encoding, channel count
// or resolution, or holds a non-finite value.
VolumeGridData read_vol_file(const std::string& path);

// The float grid `grid_name` of an OpenVDB file (empty: "density" if present, else the first float grid),
// densified over its active voxel bounding box (inactive voxels hold their values, or the background). Read
// by penumbra's own reader (vdb_layout.h). Throws VolumeFileError for an unreadable or corrupt file, a format
// version other than 222-224, a missing or non-float grid, an empty or too large grid, a non-linear or
// singular transform or a non-finite value.
// `max_voxels` caps the dense grid (1 GiB of floats by default; the fuzz harness passes less).
constexpr uint64_t MaxDenseVoxels = uint64_t(1) << 28;
VolumeGridData read_vdb_file(const std::string& path, const std::string& grid_name,
                             uint64_t max_voxels = MaxDenseVoxels);

} // namespace penumbra
