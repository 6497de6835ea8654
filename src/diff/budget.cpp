#include "diff/budget.h"

#include <algorithm>

namespace penumbra {

PsdrOptions psdr_budget(const Scene&, const Parameters&, const PsdrOptions& base, int spp) {
    PsdrOptions o = base;
    const int per_batch = std::max(1, spp / std::max(1, base.interior.batches));
    o.interior.spp = per_batch;
    o.primary_spp = o.direct_spp = o.indirect_spp = o.pixel_spp = per_batch;
    return o;
}

} // namespace penumbra
