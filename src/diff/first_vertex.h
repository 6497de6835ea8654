// How the estimators parameterize the first path vertex x1 (the one the camera sees).
//   image space: the camera ray through a film position is fixed and x1(θ) slides along it on the moving
//                surface (its barycentrics depend on θ); the pixel filter does not move, so neither the
//                filter gradient nor pixel edges contribute, and the discontinuities of the image are the
//                edges that the camera sees move: silhouettes, creases of meshes shaded with face normals,
//                and the edges of smooth-shaded solids where light arrives between the two faces' planes
//                (each face hides the half-space below its own plane: diff/psdr/primary_boundary.cpp).
//   material:    x1 = X(p1, θ) at a fixed material point (paper 001 §4.1); the film position s(x1(θ)) moves,
//                so the filter's gradient (interior term) and, for a box filter, its jumps at pixel edges
//                (the pixel-boundary term) carry the image-space motion.
// Both give the same derivative (docs/design.md, "The first vertex"); image space has far less variance,
// material form is needed when the camera moves, and is kept where a moving surface's shading jumps inside a
// triangle (checkerboard or nearest-neighbour textures), which image space would have to sample as edges.
// With a finite lens aperture (thinlens) or a single measured ray (radiancemeter), a world point has no
// single film position (Sensor::projects_points() is false): s(x1) and the film Jacobian of the material form
// do not exist, while the ray fixed by the film and lens samples does, so the first vertex is in image space
// (the interior term is then exact), and the terms that connect points to the camera through film_position()
// (primary, direct and indirect boundary terms) are refused for parameters that move geometry.
#pragma once
#include "diff/parameters.h"

#include <string>

namespace penumbra {

enum class FirstVertex { Auto, ImageSpace, Material };

// "auto", "image" or "material"; throws Error otherwise.
FirstVertex parse_first_vertex(const std::string& name);

// Whether the estimators use the image-space first vertex for these parameters: Auto picks it unless the
// sensor moves, a moving shape has a texture that jumps inside its triangles, or a point or spot light moves
// in a scene with media. Requesting ImageSpace when the sensor moves is an Error; so is, for a sensor that
// does not project points, Material, a moving sensor, or a moving shape whose texture jumps inside its
// triangles.
bool image_space_first_vertex(const Scene& scene, const Parameters& params, FirstVertex choice);

// Whether the parameters move the sensor, a shape or a light (so that some discontinuity of the image moves).
bool moves_geometry(const Scene& scene, const Parameters& params);

// Throws Error when the sensor does not project points and the parameters move geometry: the boundary term
// `term` connects surface points to a single center of projection.
void require_pinhole(const Scene& scene, const Parameters& params, const std::string& term);

} // namespace penumbra
