// `gridvolume`: a dense voxel grid (Mitsuba's .vol or an OpenVDB .vdb float grid) looked up at world points,
// with a coarse grid of maxima that bounds it along rays (majorants for delta and ratio tracking).
#pragma once
#include "scene/volumes/volume_grid.h"

#include <algorithm>
#include <cmath>

namespace penumbra {

class GridVolume final : public VolumeBase<GridVolume> {
  public:
    enum class Filter { Trilinear, Nearest };
    enum class Wrap { Clamp, Repeat, Mirror };
    // Voxels per side of a block of the coarse grid of maxima.
    static constexpr int BlockSize = 8;

    // `unit_to_world` maps the grid's unit cube to world space. `max_value` (> 0) replaces the maximum of
    // the data as the global bound max() (Mitsuba's `max_value`); it must not be below it.
    GridVolume(VolumeGridData grid, const Transform& unit_to_world, Filter filter, Wrap wrap,
               float max_value = -1.f);

    // Texture lookup at world point p: p -> unit cube (inverse of unit_to_world) -> voxel coordinates, voxel
    // (i, j, k) centred at ((i, j, k) + 1/2) / res (Mitsuba's convention). Trilinear: the 8 voxels around
    // u res - 1/2 weighted by their distance; nearest: the voxel containing u res. Indices outside the grid
    // follow the wrap mode. Derivatives flow through the interpolation weights and, when `data` is
    // differentiated, through the voxel values.
    template <typename T> Color3<T> eval_t(const Vec3<T>& p) const {
        const Vec3<T> u = to_local_.apply_point(p);
        if (filter_ == Filter::Nearest) {
            int idx[3];
            for (int a = 0; a < 3; ++a)
                idx[a] = wrap(cell_of(detach(u[a]) * float(res_[a])), res_[a]);
            return voxel<T>(idx[0], idx[1], idx[2]);
        }
        int lo[3], hi[3];
        T w[3];
        for (int a = 0; a < 3; ++a) {
            const T x = u[a] * float(res_[a]) - T(0.5f);
            const int i = cell_of(detach(x));
            lo[a] = wrap(i, res_[a]);
            hi[a] = wrap(i + 1, res_[a]);
            w[a] = x - T(float(i));
        }
        Color3<T> result(T(0.f));
        for (int corner = 0; corner < 8; ++corner) {
            const int cx = corner & 1, cy = (corner >> 1) & 1, cz = corner >> 2;
            const T weight =
                (cx ? w[0] : T(1.f) - w[0]) * (cy ? w[1] : T(1.f) - w[1]) * (cz ? w[2] : T(1.f) - w[2]);
            result += voxel<T>(cx ? hi[0] : lo[0], cy ? hi[1] : lo[1], cz ? hi[2] : lo[2]) * weight;
        }
        return result;
    }

    float max() const override { return max_; }
    float min() const override { return min_; }
    float max_along(const Vec3f& o, const Vec3f& d, float t0, float t1) const override;
    void max_segments(const Vec3f& o, const Vec3f& d, float t0, float t1,
                      const BoundVisitor& f) const override;
    BoundingBox3f bbox() const override { return bbox_; }
    int channel_count() const override { return channels_; }
    Vec3i resolution() const { return res_; }
    std::string to_string() const override;
    // `data` (Mitsuba's key): the voxel values, shape {z, y, x, channels}.
    void traverse(ParamVisitor& v) override {
        v.put_array("data", values_.data(), {res_.z, res_.y, res_.x, channels_}, &data_index_);
    }
    // New voxel values: the bounds (majorants) follow them; negative or non-finite values are an Error.
    void parameters_changed() override;

  private:
    // floor(x) as an int, finite and far enough from overflow for the wrap modes.
    static int cell_of(float x) {
        if (!(std::abs(x) < 1e8f)) x = std::isnan(x) ? 0.f : std::copysign(1e8f, x);
        return int(std::floor(x));
    }
    int wrap(int i, int n) const {
        switch (wrap_) {
        case Wrap::Clamp:
            return std::clamp(i, 0, n - 1);
        case Wrap::Repeat:
            return ((i % n) + n) % n;
        case Wrap::Mirror: {
            const int r = ((i % (2 * n)) + 2 * n) % (2 * n);
            return r < n ? r : 2 * n - 1 - r;
        }
        }
        return 0;
    }
    template <typename T> Color3<T> voxel(int x, int y, int z) const {
        const size_t i =
            ((size_t(z) * size_t(res_.y) + size_t(y)) * size_t(res_.x) + size_t(x)) * size_t(channels_);
        const auto at = [&](size_t k) { return param_value<T>(values_[k], data_index_ < 0 ? -1 : data_index_ + int(k)); };
        return channels_ == 1 ? Color3<T>(at(i)) : Color3<T>(at(i), at(i + 1), at(i + 2));
    }
    void build_block_maxima();
    float block_max(int bx, int by, int bz) const {
        return block_max_[(size_t(bz) * size_t(blocks_.y) + size_t(by)) * size_t(blocks_.x) + size_t(bx)];
    }

    Vec3i res_;
    int channels_;
    std::vector<float> values_;
    Transform to_local_; // world -> unit cube
    Filter filter_;
    Wrap wrap_;
    BoundingBox3f bbox_; // world-space bounds of the unit cube
    float max_ = 0.f, min_ = 0.f;
    float max_value_ = -1.f; // Mitsuba's `max_value` override (negative: none)
    int data_index_ = -1;    // first parameter index of `data` when differentiated
    Vec3i blocks_;
    std::vector<float> block_max_;
};

} // namespace penumbra
