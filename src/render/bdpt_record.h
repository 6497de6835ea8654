// What the bidirectional path tracer's walks and connections drew, kept for the differentiable estimator
// (diff/psdr/bdpt_interior.h): the chain of straight pieces (media, null-surface crossings) of every sampled
// segment and connection, and each (s, t) strategy's MIS-weighted contribution. The renderer records nothing
// (BDPTContext::record is null), so its results and speed are unchanged.
#pragma once
#include "render/path_vertex.h"
#include "render/flight_record.h"

#include <vector>

namespace penumbra {

// One strategy of one sample: its contribution f w / p (camera subpath's pixel), the emitter sample of
// next-event estimation (s = 1) and the chain of the connecting segment (s >= 1).
struct StrategyRecord {
    int s = 0, t = 0;
    Color3f value;
    DirectionSample3f light_sample;
    LegChain connection;
};

struct BDPTRecord {
    std::vector<LegChain> camera, light; // [i]: the chain arriving at subpath vertex i (i >= 1)
    std::vector<StrategyRecord> strategies;
    int count = 0;

    StrategyRecord& next(int s, int t) {
        if (count == int(strategies.size())) strategies.emplace_back();
        StrategyRecord& r = strategies[size_t(count++)];
        r.s = s, r.t = t;
        r.value = Color3f(0.f);
        r.connection.clear();
        return r;
    }
    void clear() { count = 0; }
};

} // namespace penumbra
