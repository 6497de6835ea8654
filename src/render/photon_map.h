// Photons of one photon-tracing pass and the hash grid that finds those near a density-estimation point
// (a spatial hash of uniform cells, as Hachisuka & Jensen 2009 use). Photons are stored in cell-bucket order,
// in the order they were given within a bucket, so every query visits them in an order that depends on the
// photons alone: sums over a query are bit-identical whatever the thread count.
#pragma once
#include "core/vector.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace penumbra {

// A light-subpath vertex on a surface with a non-delta BSDF: a photon (paper 003 §5: a light subpath
// y_0 ... y_j ending at the photon y_j, which vertex merging joins to an eye subpath).
struct Photon {
    Vec3f p;        // position
    Vec3f n;        // geometric normal of the surface
    Vec3f wi;       // world direction toward the previous light-subpath vertex
    Color3f flux;   // throughput of the light subpath up to the photon (L_e / p, not yet / photon paths)
    uint32_t path;  // index of the photon path within its pass
    uint16_t depth; // segments of the light subpath (1: directly from the emitter)
};

// The photons of one pass: on surfaces with a non-delta BSDF, and at scattering events in media (volume
// photons, n = 0: their flux carries the scattering coefficient σ_s at the event).
struct PhotonSet {
    std::vector<Photon> surface, volume;
};

class PhotonMap {
  public:
    // Builds the grid with cells of side `cell_size` (> 0); queries should use radii <= cell_size.
    void build(std::vector<Photon> photons, float cell_size);
    const std::vector<Photon>& photons() const { return photons_; }

    // Calls visit(photon, squared distance) for every photon within `radius` of p.
    template <typename Visit> void for_each_within(const Vec3f& p, float radius, Visit&& visit) const {
        if (photons_.empty()) return;
        const float r2 = radius * radius;
        const Vec3i lo = cell_of(p - Vec3f(radius)), hi = cell_of(p + Vec3f(radius));
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    const Vec3i cell(x, y, z);
                    const uint32_t b = bucket(cell);
                    const uint64_t key = cell_key(cell);
                    for (uint32_t i = start_[b]; i < start_[b + 1]; ++i) {
                        // Other cells share the bucket: keep this cell's photons only (no double counting).
                        if (cells_[i] != key) continue;
                        const float d2 = squared_norm(positions_[i] - p);
                        if (d2 < r2) visit(photons_[i], d2);
                    }
                }
    }

  private:
    struct Vec3i {
        int x, y, z;
        Vec3i(int x_, int y_, int z_) : x(x_), y(y_), z(z_) {}
    };
    Vec3i cell_of(const Vec3f& p) const {
        return {int(std::floor(p.x * inv_cell_)), int(std::floor(p.y * inv_cell_)),
                int(std::floor(p.z * inv_cell_))};
    }
    // The cell's coordinates modulo 2^21, packed: distinct for the cells of one query, and a photon of a
    // far cell with the same key is rejected by its distance.
    static uint64_t cell_key(const Vec3i& c) {
        return (uint64_t(uint32_t(c.x) & 0x1fffffu) << 42) | (uint64_t(uint32_t(c.y) & 0x1fffffu) << 21) |
               uint64_t(uint32_t(c.z) & 0x1fffffu);
    }
    // Teschner et al. 2003's spatial hash.
    uint32_t bucket(const Vec3i& c) const {
        return ((uint32_t(c.x) * 73856093u) ^ (uint32_t(c.y) * 19349663u) ^ (uint32_t(c.z) * 83492791u)) &
               mask_;
    }

    std::vector<Photon> photons_; // sorted by bucket
    // photons_[i]'s position and the key of its cell, apart for a compact scan.
    std::vector<Vec3f> positions_;
    std::vector<uint64_t> cells_;
    std::vector<uint32_t> start_; // photons of bucket b: [start_[b], start_[b + 1])
    float inv_cell_ = 1.f;
    uint32_t mask_ = 0;
};

} // namespace penumbra
