// Discontinuities seen only through chains of delta lobes: a silhouette or a shadow reflected in a smooth
// mirror, an edge behind smooth glass. The interior estimators follow delta lobes (docs/design.md, "Delta
// lobes"), but the boundary terms reach the camera from an edge point by next-event connections, which cannot
// pass a delta lobe, so such a discontinuity that moves has no boundary term: its derivative would be
// silently missing. It is refused instead, found by a pre-pass: camera rays through a grid over the film
// follow every delta lobe (up to four deep) to the first other surface; two neighbouring rays whose chains
// agree (the same delta surfaces and lobes) but end on different shapes (or one escapes), or whose end points
// differ in what they see of a light, straddle such a discontinuity, and it moves when a shape of either
// chain, an end, the light, or the shadow's blocker moves. Limits: a feature smaller than the grid's spacing
// can pass unseen, and so can a crease of one shape; the boundaries of light arriving at an end point from
// other surfaces (a moving object's interreflection seen in a mirror) are not probed.
#pragma once
#include "diff/parameters.h"

#include <string>

namespace penumbra {

// Throws Error naming `method` when a discontinuity seen only through delta lobes moves with the parameters.
void require_no_moving_edges_behind_delta_lobes(const Scene& scene, const Parameters& params,
                                                const std::string& method);

} // namespace penumbra
