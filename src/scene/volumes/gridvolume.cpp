// Mitsuba 3 `gridvolume` (alias `grid`).
//
// Parameters:
//   filename       string     (required)  Mitsuba .vol file, or an OpenVDB file when the name ends with .vdb
//   grid           string     see right   .vdb only: the float grid's name (default "density" if present,
//                                         else the first float grid)
//   filter_type    string     trilinear   trilinear | nearest
//   wrap_mode      string     clamp       clamp | repeat | mirror: lookups outside the unit cube
//   to_world       transform  identity    places the grid's unit cube [0, 1]^3 in the world
//   use_grid_bbox  boolean    false       .vol: the unit cube is first mapped to the bounding box stored in
//                                         the file, then by to_world. .vdb grids are always placed by their
//                                         own index-to-world transform (then to_world); the flag changes
//                                         nothing
//   raw            boolean    false       accepted: penumbra renders in RGB, so 3-channel values are used as
//                                         stored in either case (Mitsuba's flag only disables the spectral
//                                         upsampling of its spectral variants)
//   accel          boolean    true        accepted: it selects CUDA texture hardware in Mitsuba
//   max_value      float      data max    the bound max() reported to media (Mitsuba's override); it may not
//                                         be below the data's maximum, which would make it no majorant
//
// Single-channel grids repeat their value over RGB. Values must be finite (a file with NaN or infinity is a
// load error); media check the sign of their extinction.
#include "scene/volumes/gridvolume.h"

#include "scene/media_loading.h"

#include <sstream>

namespace penumbra {

GridVolume::GridVolume(VolumeGridData grid, const Transform& unit_to_world, Filter filter, Wrap wrap,
                       float max_value)
    : res_(grid.res), channels_(grid.channels), values_(std::move(grid.values)),
      to_local_(unit_to_world.inverse()), filter_(filter), wrap_(wrap), max_value_(max_value) {
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3f p =
            unit_to_world.apply_point(Vec3f(float(corner & 1), float((corner >> 1) & 1), float(corner >> 2)));
        bbox_.lo = penumbra::min(bbox_.lo, p);
        bbox_.hi = penumbra::max(bbox_.hi, p);
    }
    const auto [lo, hi] = std::minmax_element(values_.begin(), values_.end());
    min_ = *lo;
    max_ = *hi;
    build_block_maxima();
    if (max_value >= 0.f) max_ = max_value;
}

void GridVolume::parameters_changed() {
    for (const float v : values_)
        if (!std::isfinite(v) || v < 0.f)
            throw Error("gridvolume" + (id.empty() ? std::string() : " '" + id + "'") +
                        ": data must be finite and non-negative (got " + std::to_string(v) + ")");
    const auto [lo, hi] = std::minmax_element(values_.begin(), values_.end());
    min_ = *lo;
    max_ = std::max(*hi, max_value_);
    build_block_maxima();
}

// Block (bx, by, bz) covers voxel coordinates [b B, (b + 1) B) per axis. Lookups there read voxels
// floor(x - 1/2) and floor(x - 1/2) + 1 (trilinear) or floor(x) (nearest), all within [b B - 1, (b + 1) B]
// after wrapping: the maximum over that range bounds every lookup in the block, with half a voxel to spare
// on each side against rounding in the ray traversal.
void GridVolume::build_block_maxima() {
    for (int a = 0; a < 3; ++a)
        blocks_[a] = (res_[a] + BlockSize - 1) / BlockSize;
    // Maxima over x-ranges first, then y, then z (separable).
    auto range_max = [&](const std::vector<float>& in, Vec3i in_res, int axis, Vec3i out_res) {
        std::vector<float> out(size_t(out_res.x) * size_t(out_res.y) * size_t(out_res.z), 0.f);
        for (int z = 0; z < out_res.z; ++z)
            for (int y = 0; y < out_res.y; ++y)
                for (int x = 0; x < out_res.x; ++x) {
                    Vec3i c(x, y, z);
                    const int b = c[axis];
                    float m = -Infinity;
                    for (int i = b * BlockSize - 1; i <= (b + 1) * BlockSize; ++i) {
                        c[axis] = wrap(i, res_[axis]);
                        m = std::max(m, in[(size_t(c.z) * size_t(in_res.y) + size_t(c.y)) * size_t(in_res.x) +
                                           size_t(c.x)]);
                    }
                    out[(size_t(z) * size_t(out_res.y) + size_t(y)) * size_t(out_res.x) + size_t(x)] = m;
                }
        return out;
    };
    std::vector<float> voxel_max(size_t(res_.x) * size_t(res_.y) * size_t(res_.z));
    for (size_t i = 0; i < voxel_max.size(); ++i)
        voxel_max[i] = *std::max_element(values_.begin() + ptrdiff_t(i * size_t(channels_)),
                                         values_.begin() + ptrdiff_t((i + 1) * size_t(channels_)));
    const Vec3i rx(blocks_.x, res_.y, res_.z), ry(blocks_.x, blocks_.y, res_.z);
    // Every pass reads the full-resolution extent along its axis (wrap() uses res_), and the already reduced
    // extents along the others.
    std::vector<float> mx = range_max(voxel_max, res_, 0, rx);
    std::vector<float> my = range_max(mx, rx, 1, ry);
    block_max_ = range_max(my, ry, 2, blocks_);
}

float GridVolume::max_along(const Vec3f& o, const Vec3f& d, float t0, float t1) const {
    float m = 0.f;
    max_segments(o, d, t0, t1, [&](float, float, float bound) {
        m = std::max(m, bound);
        return true;
    });
    return m;
}

// 3D-DDA over the blocks (Amanatides & Woo 1987) in the grid's unit-cube frame, where the ray keeps its
// parameter t (to_local is affine). Outside the unit cube the wrap mode repeats grid values: bounded by
// max().
void GridVolume::max_segments(const Vec3f& o, const Vec3f& d, float t0, float t1,
                              const BoundVisitor& f) const {
    if (!(t0 < t1)) return;
    const Vec3f ol = to_local_.apply_point(o), dl = to_local_.apply_vector(d);
    const BoundingBox3f unit{Vec3f(0.f), Vec3f(1.f)};
    float a, b;
    if (!unit.intersect(ol, dl, a, b) || !(std::max(a, t0) < std::min(b, t1))) {
        f(t0, t1, max_);
        return;
    }
    a = std::max(a, t0);
    b = std::min(b, t1);
    if (t0 < a && !f(t0, a, max_)) return;

    // Block coordinates g(t) = (ol + t dl) res / B; block boundaries are the integer planes.
    Vec3f go, gd;
    Vec3i cell, step;
    Vec3f t_next;
    for (int k = 0; k < 3; ++k) {
        const float s = float(res_[k]) / float(BlockSize);
        go[k] = ol[k] * s;
        gd[k] = dl[k] * s;
        cell[k] = std::clamp(int(std::floor(go[k] + gd[k] * a)), 0, blocks_[k] - 1);
        step[k] = gd[k] > 0.f ? 1 : (gd[k] < 0.f ? -1 : 0);
        t_next[k] = step[k] == 0 ? Infinity : (float(cell[k] + (step[k] > 0 ? 1 : 0)) - go[k]) / gd[k];
    }
    float t = a;
    for (;;) {
        const int axis =
            t_next.x <= t_next.y ? (t_next.x <= t_next.z ? 0 : 2) : (t_next.y <= t_next.z ? 1 : 2);
        const float t_end = std::min(t_next[axis], b);
        if (t_end > t) {
            if (!f(t, t_end, block_max(cell.x, cell.y, cell.z))) return;
            t = t_end;
        }
        if (t >= b) break;
        cell[axis] += step[axis];
        if (cell[axis] < 0 || cell[axis] >= blocks_[axis]) { // rounding: left the grid before t reached b
            if (!f(t, b, max_)) return;
            break;
        }
        t_next[axis] = (float(cell[axis] + (step[axis] > 0 ? 1 : 0)) - go[axis]) / gd[axis];
    }
    if (b < t1) f(b, t1, max_);
}

std::string GridVolume::to_string() const {
    std::ostringstream os;
    os << "GridVolume[res = " << res_.x << " x " << res_.y << " x " << res_.z << ", channels = " << channels_
       << ", max = " << max_ << ", bbox = " << bbox_.lo << " - " << bbox_.hi << "]";
    return os.str();
}

std::shared_ptr<Object> make_gridvolume(const Properties& props, const LoadContext& ctx) {
    const std::string filter = props.get_string("filter_type", "trilinear");
    if (filter != "trilinear" && filter != "nearest")
        props.raise("filter_type",
                    "invalid filter_type '" + filter + "' (expected 'trilinear' or 'nearest')");
    const std::string wrap = props.get_string("wrap_mode", "clamp");
    if (wrap != "clamp" && wrap != "repeat" && wrap != "mirror")
        props.raise("wrap_mode", "invalid wrap_mode '" + wrap + "' (expected 'clamp', 'repeat' or 'mirror')");
    const Transform to_world = props.get_transform("to_world");
    const bool use_grid_bbox = props.get_bool("use_grid_bbox", false);
    props.get_bool("raw", false);
    props.get_bool("accel", true);

    const std::string filename = props.get_string("filename");
    const std::string path = ctx.resolve(filename, props.location("filename"));
    const bool vdb = filename.size() >= 4 && filename.compare(filename.size() - 4, 4, ".vdb") == 0;
    const std::string grid_name = vdb ? props.get_string("grid", "") : "";
    if (!vdb && props.has("grid")) props.raise("grid", "'grid' names a grid of an OpenVDB (.vdb) file only");
    VolumeGridData grid;
    try {
        grid = vdb ? read_vdb_file(path, grid_name) : read_vol_file(path);
    } catch (const std::exception& e) {
        props.raise("filename", "'" + filename + "': " + e.what());
    }
    if (use_grid_bbox && !grid.has_placement)
        props.raise("use_grid_bbox",
                    "'" + filename + "': the bounding box stored in the file is degenerate or not finite");

    const Transform unit_to_world = (vdb || use_grid_bbox) ? to_world * grid.unit_to_file : to_world;
    float max_value = -1.f;
    if (props.has("max_value")) {
        max_value = props.get_float("max_value");
        const float data_max = *std::max_element(grid.values.begin(), grid.values.end());
        if (!(max_value >= data_max) || !std::isfinite(max_value))
            props.raise("max_value", "'max_value' (" + std::to_string(max_value) +
                                         ") must be finite and at least the grid's maximum (" +
                                         std::to_string(data_max) + ")");
    }
    return std::make_shared<GridVolume>(
        std::move(grid), unit_to_world,
        filter == "nearest" ? GridVolume::Filter::Nearest : GridVolume::Filter::Trilinear,
        wrap == "repeat" ? GridVolume::Wrap::Repeat
                         : (wrap == "mirror" ? GridVolume::Wrap::Mirror : GridVolume::Wrap::Clamp),
        max_value);
}

} // namespace penumbra
