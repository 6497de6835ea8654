// Object-space triangle meshes of the shape plugins that have their own file in src/scene/shapes/. Each
// queries its plugin's own parameters; make_shape() then applies the parameters common to all shapes.
#pragma once
#include "scene/factory.h"
#include "scene/mesh.h"

namespace penumbra {

// cylinder: p0, p1, radius (cylinder.cpp).
TriangleMesh make_cylinder(const Properties& props);

} // namespace penumbra
