// Object-space triangle meshes of the shape plugins that have their own file in src/scene/shapes/. Each
// queries its plugin's own parameters; make_shape() then applies the parameters common to all shapes.
#pragma once
#include "scene/factory.h"
#include "scene/mesh.h"

namespace penumbra {

// cylinder: p0, p1, radius (cylinder.cpp).
TriangleMesh make_cylinder(const Properties& props);
// linearcurve, bsplinecurve: filename, to_world (applied here: the radii stay untransformed),
// silhouette_sampling_weight. World-space meshes (linearcurve.cpp, bsplinecurve.cpp).
TriangleMesh make_linearcurve(const Properties& props, const LoadContext& ctx);
TriangleMesh make_bsplinecurve(const Properties& props, const LoadContext& ctx);

} // namespace penumbra
