// The contributions of all (s, t) strategies for one camera subpath and one light subpath (Veach 1997,
// §10.2): s = 0 (the camera subpath reaches an emitter), s = 1 (a fresh emitter sample: next-event
// estimation), t = 1 (a light subpath vertex connected to the sensor: light tracing, splatted through the
// film's filter), and general connections through media and null surfaces (segment_transmittance), each
// MIS-weighted.
#pragma once
#include "render/bdpt_subpaths.h"

namespace penumbra {

// Returns the radiance estimate for the camera subpath's pixel (t >= 2) and adds the light tracing
// contributions (t = 1) to `splats` (unnormalized: the caller scales by image pixels / light paths; unused,
// and may be null, when ctx.sensor_connects is false).
Color3f connect_subpaths(BDPTContext& ctx, const std::vector<PathVertex>& camera,
                         const std::vector<PathVertex>& light, Image* splats);

} // namespace penumbra
