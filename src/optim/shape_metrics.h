// Errors of a recovered mesh against a known target, and mesh files as parameter values, for shape
// optimizations through <shape>.vertex_positions (docs/optimize.md, "Multi-view shape optimization").
// Positions are flat arrays, 3 values per vertex (the vertex_positions layout).
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace penumbra {

// The vertex positions of a mesh file (.ply, .obj), in file order, as stored (no transform applied).
std::vector<float> load_vertex_positions(const std::string& path);

// (1/n) Σ_i ‖x_i − x*_i‖ over corresponding vertices (same connectivity).
double mean_vertex_error(std::span<const double> x, std::span<const double> truth);

// The symmetric Chamfer distance between the vertex sets, ½ (mean_a min_b ‖a − b‖ + mean_b min_a ‖b − a‖)
// (no correspondence needed: tangential sliding of vertices along the surface costs little).
double chamfer_distance(std::span<const double> a, std::span<const double> b);

// Writes a binary PLY mesh (positions, 3 indices per triangle). Throws Error if the file cannot be written.
void write_ply_mesh(const std::string& path, std::span<const double> positions,
                    std::span<const uint32_t> indices);

} // namespace penumbra
