// Tetrahedral meshes of the regions that media fill, for the material-form motion X of paper 001 §6.1: TetGen
// (Si 2015) tetrahedralizes a piecewise-linear complex given as triangles, keeping the input surface vertices
// as mesh vertices (so that a deformation defined at them moves the surface exactly), and point location
// finds the tetrahedron and barycentrics of a point.
#pragma once
#include "core/vector.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace penumbra {

struct TetMesh {
    // The distinct input vertices in the order of their first appearance, then the Steiner points TetGen
    // added.
    std::vector<Vec3f> vertices;
    std::vector<std::array<uint32_t, 4>> tets;
    // The mesh vertex of each input vertex (coincident input vertices share one).
    std::vector<uint32_t> input_vertex;
    size_t surface_vertex_count = 0; // vertices[0 .. surface_vertex_count) are input vertices
    // Steiner points on the input surface (TetGen splits input triangles to recover them): the input
    // triangle (its mesh vertices) and the point's barycentrics in it, so that a field given at the input
    // vertices and interpolated linearly on the input triangles is reproduced exactly.
    struct SurfacePoint {
        uint32_t vertex;
        std::array<uint32_t, 3> triangle;
        std::array<float, 3> bary;
    };
    std::vector<SurfacePoint> surface_points;

    // The signed volume of tet t (positive for TetGen's orientation).
    double volume(size_t t) const;
};

// Tetrahedralizes the PLC of the triangles `indices` (3 per triangle, into `positions`): the interior of a
// closed mesh, or the region between an enclosing closed mesh and the open or closed meshes inside it.
// TetGen's switches "pzM" (a PLC, zero-based, coplanar input triangles kept apart so that each stays a union
// of tet faces); with `max_volume` > 0, "pYzMqa" (the surface kept whole, radius-edge ratio at most 2, no tet
// larger than max_volume). The input vertices are all kept; Steiner points on the surface (without -Y, which
// is slower there: 2.5 s instead of 0.4 s on 16k triangles) are listed in surface_points. Throws Error
// naming `name` when the input intersects itself or TetGen fails otherwise.
TetMesh tetrahedralize(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices,
                       const std::string& name, double max_volume = 0.0);

// Point location in a tet mesh: a uniform grid over the tets' bounding boxes.
class TetLocator {
  public:
    explicit TetLocator(const TetMesh& mesh);

    struct Location {
        uint32_t tet;
        std::array<float, 4> bary; // weights of the tet's vertices (sum 1)
    };
    // The tet containing p (within a relative tolerance of its faces), or none outside the mesh.
    std::optional<Location> locate(const Vec3f& p) const;
    // The (constant) gradients of tet t's four barycentric coordinates.
    std::array<Vec3f, 4> barycentric_gradients(uint32_t t) const {
        const Frame& f = frames_[t];
        return {Vec3f(f.inverse[0]), Vec3f(f.inverse[1]), Vec3f(f.inverse[2]),
                -Vec3f(f.inverse[0] + f.inverse[1] + f.inverse[2])};
    }

  private:
    struct Frame {
        Vec3d origin;     // the tet's 4th vertex
        Vec3d inverse[3]; // rows of [a-d, b-d, c-d]^-1
    };
    std::vector<Frame> frames_;
    Vec3f lo_, cell_size_;
    Vec3i res_;
    std::vector<uint32_t> cell_start_, cell_tets_;
};

} // namespace penumbra
