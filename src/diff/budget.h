// The sample budget of the psdr estimator from one number: `--spp N` gives every term a share.
#pragma once
#include "diff/psdr.h"

namespace penumbra {

// Per-term sample counts (per batch, base.interior.batches batches) for a total of `spp` samples per pixel, the
// rest of the options (seed, threads, path settings, first vertex) taken from `base`.
PsdrOptions psdr_budget(const Scene& scene, const Parameters& params, const PsdrOptions& base, int spp);

} // namespace penumbra
