#include "render/photon_map.h"

#include "core/error.h"

#include <bit>

namespace penumbra {

// A stable counting sort of the photons by bucket.
void PhotonMap::build(std::vector<Photon> photons, float cell_size) {
    if (!(cell_size > 0.f) || !std::isfinite(cell_size))
        throw Error("photon map: the cell size must be positive and finite");
    inv_cell_ = 1.f / cell_size;
    const size_t n_buckets = std::bit_ceil(std::max<size_t>(2 * photons.size(), 64));
    mask_ = uint32_t(n_buckets - 1);
    start_.assign(n_buckets + 1, 0);
    std::vector<uint32_t> buckets(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
        buckets[i] = bucket(cell_of(photons[i].p));
        ++start_[buckets[i] + 1];
    }
    for (size_t b = 0; b < n_buckets; ++b)
        start_[b + 1] += start_[b];
    std::vector<uint32_t> next(start_.begin(), start_.end() - 1);
    photons_.resize(photons.size());
    positions_.resize(photons.size());
    cells_.resize(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
        const uint32_t j = next[buckets[i]]++;
        photons_[j] = photons[i];
        positions_[j] = photons[i].p;
        cells_[j] = cell_key(cell_of(photons[i].p));
    }
}

} // namespace penumbra
