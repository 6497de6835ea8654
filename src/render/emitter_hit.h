// Emission found by a traced ray (an emitter surface, or each infinite emitter for an escaped ray) as seen
// from a previous vertex, with the solid-angle density with which emitter sampling (Scene's uniform emitter
// selection, then the emitter's own sampling) produces the same direction. MIS weights are per emitter.
#pragma once
#include "scene/scene.h"

namespace penumbra {

// Calls visit(emitter, radiance, emitter_pdf) for every emitter the ray sees; `si` may be invalid (escaped ray).
template <typename Visit>
void for_each_emitter_hit(const Scene& scene, const Interaction3f& from, const Vec3f& d,
                          const SurfaceInteraction3f& si, Visit&& visit) {
    DirectionSample3f ds;
    ds.d = d;
    if (!si.is_valid()) {
        ds.dist = Infinity;
        for (const auto& e : scene.emitters) {
            if (!e->is_infinite()) continue;
            const Color3f Le = e->eval_environment(d);
            if (is_black(Le)) continue;
            ds.emitter = e.get();
            visit(e.get(), Le, scene.pdf_emitter_direction(from, ds));
        }
        return;
    }
    const Emitter* emitter = si.emitter();
    if (!emitter) return;
    ds.p = si.p;
    ds.n = si.n;
    ds.uv = si.uv;
    ds.dist = si.t;
    ds.emitter = emitter;
    const Color3f Le = emitter->eval(si);
    if (!is_black(Le)) visit(emitter, Le, scene.pdf_emitter_direction(from, ds));
}

} // namespace penumbra
