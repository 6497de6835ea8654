#include "scene/tet_mesh.h"

#include "core/error.h"

#define TETLIBRARY
#include <tetgen.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <tuple>

namespace penumbra {

namespace {

// TetGen's exit codes (terminatetetgen) in words.
std::string tetgen_reason(int code) {
    switch (code) {
    case 1:
        return "out of memory";
    case 2:
        return "TetGen's internal error";
    case 3:
        return "the surface intersects itself (or triangles overlap)";
    case 4:
        return "an input feature is too small for TetGen's tolerance";
    case 5:
        return "two input facets are too close to each other";
    case 10:
        return "TetGen rejected the input";
    default:
        return "TetGen's exit code " + std::to_string(code);
    }
}

double det3(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return dot(a, cross(b, c)); }

} // namespace

double TetMesh::volume(size_t t) const {
    const auto& v = tets[t];
    const Vec3d d(vertices[v[3]]);
    return det3(Vec3d(vertices[v[0]]) - d, Vec3d(vertices[v[1]]) - d, Vec3d(vertices[v[2]]) - d) / 6.0;
}

TetMesh tetrahedralize(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices,
                       const std::string& name, double max_volume) {
    TetMesh mesh;
    // Coincident input vertices (seams of split normals or uvs) become one PLC vertex.
    std::map<std::tuple<float, float, float>, uint32_t> welded;
    mesh.input_vertex.resize(positions.size());
    for (size_t i = 0; i < positions.size(); ++i) {
        const Vec3f& p = positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw Error("cannot tetrahedralize " + name + ": vertex " + std::to_string(i) + " is not finite");
        const auto [it, added] = welded.try_emplace({p.x, p.y, p.z}, uint32_t(mesh.vertices.size()));
        if (added) mesh.vertices.push_back(p);
        mesh.input_vertex[i] = it->second;
    }
    std::set<std::array<uint32_t, 3>> seen;
    std::vector<std::array<uint32_t, 3>> triangles;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        std::array<uint32_t, 3> tri = {mesh.input_vertex[indices[t]], mesh.input_vertex[indices[t + 1]],
                                       mesh.input_vertex[indices[t + 2]]};
        std::array<uint32_t, 3> key = tri;
        std::sort(key.begin(), key.end());
        if (key[0] == key[1] || key[1] == key[2] || !seen.insert(key).second) continue;
        triangles.push_back(tri);
    }
    if (triangles.size() < 4) throw Error("cannot tetrahedralize " + name + ": fewer than 4 triangles");

    tetgenio in, out;
    in.firstnumber = 0;
    in.numberofpoints = int(mesh.vertices.size());
    in.pointlist = new REAL[3 * mesh.vertices.size()];
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k)
            in.pointlist[3 * i + k] = REAL(mesh.vertices[i][k]);
    in.numberoffacets = int(triangles.size());
    in.facetlist = new tetgenio::facet[triangles.size()];
    for (size_t t = 0; t < triangles.size(); ++t) {
        tetgenio::facet& f = in.facetlist[t];
        tetgenio::init(&f);
        f.numberofpolygons = 1;
        f.polygonlist = new tetgenio::polygon[1];
        tetgenio::init(&f.polygonlist[0]);
        f.polygonlist[0].numberofvertices = 3;
        f.polygonlist[0].vertexlist = new int[3];
        for (int k = 0; k < 3; ++k)
            f.polygonlist[0].vertexlist[k] = int(triangles[t][k]);
    }
    // Debian's TetGen crashes on intersecting facets instead of reporting them: its detection pass (-d)
    // first, which lists the intersecting faces.
    const auto run = [&](std::string switches, tetgenio& result) {
        try {
            ::tetrahedralize(switches.data(), &in, &result);
        } catch (int code) {
            throw Error("cannot tetrahedralize " + name + ": " + tetgen_reason(code));
        }
    };
    {
        tetgenio intersections;
        run("pdzMQ", intersections);
        if (intersections.numberoftrifaces > 0)
            throw Error("cannot tetrahedralize " + name + ": the surface intersects itself (" +
                        std::to_string(intersections.numberoftrifaces) + " triangles meet others)");
    }
    // Each input triangle is its own facet, marked t + 1: the output faces on it carry the mark.
    in.facetmarkerlist = new int[triangles.size()];
    for (size_t t = 0; t < triangles.size(); ++t)
        in.facetmarkerlist[t] = int(t + 1);
    // Refinement keeps the surface (-Y: otherwise it refines the surface's thin triangles too, 10x slower);
    // without it, -Y would be the slow part.
    char switches[64] = "pzMQ";
    if (max_volume > 0.0) std::snprintf(switches, sizeof(switches), "pYzMQqa%.12f", max_volume);
    run(switches, out);
    if (out.numberoftetrahedra <= 0 || out.numberofpoints < in.numberofpoints)
        throw Error("cannot tetrahedralize " + name +
                    ": TetGen produced no tetrahedra (is the surface closed?)");
    mesh.surface_vertex_count = mesh.vertices.size();
    for (int i = in.numberofpoints; i < out.numberofpoints; ++i)
        mesh.vertices.emplace_back(float(out.pointlist[3 * i]), float(out.pointlist[3 * i + 1]),
                                   float(out.pointlist[3 * i + 2]));
    std::vector<bool> listed(mesh.vertices.size(), false);
    for (int f = 0; f < out.numberoftrifaces; ++f) {
        const int mark = out.trifacemarkerlist ? out.trifacemarkerlist[f] : 0;
        for (int k = 0; k < 3; ++k) {
            const int v = out.trifacelist[3 * f + k];
            if (v < in.numberofpoints || listed[size_t(v)]) continue;
            if (mark < 1 || mark > int(triangles.size()))
                throw Error("cannot tetrahedralize " + name +
                            ": TetGen split the surface without saying where");
            listed[size_t(v)] = true;
            const std::array<uint32_t, 3>& tri = triangles[size_t(mark - 1)];
            // Barycentrics of the point in the plane of the triangle (least squares).
            const Vec3d a(mesh.vertices[tri[0]]), e1 = Vec3d(mesh.vertices[tri[1]]) - a,
                                                  e2 = Vec3d(mesh.vertices[tri[2]]) - a;
            const Vec3d q =
                Vec3d(out.pointlist[3 * v], out.pointlist[3 * v + 1], out.pointlist[3 * v + 2]) - a;
            const double d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2),
                         inv = 1.0 / (d11 * d22 - d12 * d12);
            const double b1 = (d22 * dot(q, e1) - d12 * dot(q, e2)) * inv,
                         b2 = (d11 * dot(q, e2) - d12 * dot(q, e1)) * inv;
            mesh.surface_points.push_back({uint32_t(v), tri, {float(1.0 - b1 - b2), float(b1), float(b2)}});
        }
    }
    mesh.tets.resize(size_t(out.numberoftetrahedra));
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
        for (int k = 0; k < 4; ++k)
            mesh.tets[t][k] = uint32_t(out.tetrahedronlist[4 * t + k]);
        // Positive orientation, whatever TetGen's convention.
        if (mesh.volume(t) < 0.0) std::swap(mesh.tets[t][0], mesh.tets[t][1]);
    }
    return mesh;
}

TetLocator::TetLocator(const TetMesh& mesh) {
    lo_ = Vec3f(Infinity);
    Vec3f hi(-Infinity);
    for (const Vec3f& p : mesh.vertices) {
        lo_ = min(lo_, p);
        hi = max(hi, p);
    }
    const Vec3f extent = max(hi - lo_, Vec3f(1e-6f));
    const float largest = std::max({extent.x, extent.y, extent.z});
    // About one tet per cell, the cells as cubic as the box allows.
    const float per_axis = std::cbrt(float(mesh.tets.size()));
    for (int k = 0; k < 3; ++k)
        res_[k] = std::clamp(int(std::ceil(per_axis * extent[k] / largest)), 1, 128);
    cell_size_ = extent / Vec3f(float(res_.x), float(res_.y), float(res_.z));
    const auto cell_of = [&](const Vec3f& p, int k) {
        return std::clamp(int((p[k] - lo_[k]) / cell_size_[k]), 0, res_[k] - 1);
    };
    std::vector<std::pair<uint32_t, uint32_t>> entries; // (cell, tet)
    frames_.resize(mesh.tets.size());
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
        const auto& v = mesh.tets[t];
        // Barycentrics (u, v, w) = [a-d, b-d, c-d]^-1 (p - d) (in double: slivers are ill-conditioned); the
        // 4th is 1 - u - v - w.
        const Vec3d d(mesh.vertices[v[3]]);
        const Vec3d e[3] = {Vec3d(mesh.vertices[v[0]]) - d, Vec3d(mesh.vertices[v[1]]) - d,
                            Vec3d(mesh.vertices[v[2]]) - d};
        const double inv_det = 1.0 / det3(e[0], e[1], e[2]);
        Frame& f = frames_[t];
        f.origin = d;
        f.inverse[0] = cross(e[1], e[2]) * inv_det;
        f.inverse[1] = cross(e[2], e[0]) * inv_det;
        f.inverse[2] = cross(e[0], e[1]) * inv_det;
        // The cells of the tet's bounding box that no face plane separates from it (long, thin tets span many
        // cells of their box but cross few).
        Vec3f a = mesh.vertices[v[0]], b = a;
        for (int j = 1; j < 4; ++j) {
            a = min(a, mesh.vertices[v[j]]);
            b = max(b, mesh.vertices[v[j]]);
        }
        const Vec3d gradient[4] = {f.inverse[0], f.inverse[1], f.inverse[2],
                                   -(f.inverse[0] + f.inverse[1] + f.inverse[2])};
        // Whether no face plane separates the cells [c0, c1] (inclusive) from the tet; slabs and rows of
        // cells first, so that the work follows the cells the tet crosses rather than its bounding box.
        const auto crosses = [&](const Vec3i& c0, const Vec3i& c1) {
            const Vec3d box_lo = Vec3d(lo_) + Vec3d(c0.x, c0.y, c0.z) * Vec3d(cell_size_);
            const Vec3d box_hi = Vec3d(lo_) + Vec3d(c1.x + 1, c1.y + 1, c1.z + 1) * Vec3d(cell_size_);
            const Vec3d q = (box_lo + box_hi) * 0.5 - d, half = (box_hi - box_lo) * 0.5;
            const double uvw = dot(gradient[0], q) + dot(gradient[1], q) + dot(gradient[2], q);
            for (int j = 0; j < 4; ++j) {
                const Vec3d& g = gradient[j];
                const double bary = j < 3 ? dot(g, q) : 1.0 - uvw;
                if (bary + std::abs(g.x) * half.x + std::abs(g.y) * half.y + std::abs(g.z) * half.z < -1e-4)
                    return false;
            }
            return true;
        };
        const Vec3i c0(cell_of(a, 0), cell_of(a, 1), cell_of(a, 2)),
            c1(cell_of(b, 0), cell_of(b, 1), cell_of(b, 2));
        for (int z = c0.z; z <= c1.z; ++z) {
            if (!crosses(Vec3i(c0.x, c0.y, z), Vec3i(c1.x, c1.y, z))) continue;
            for (int y = c0.y; y <= c1.y; ++y) {
                if (!crosses(Vec3i(c0.x, y, z), Vec3i(c1.x, y, z))) continue;
                for (int x = c0.x; x <= c1.x; ++x)
                    if (crosses(Vec3i(x, y, z), Vec3i(x, y, z)))
                        entries.emplace_back(uint32_t((z * res_.y + y) * res_.x + x), uint32_t(t));
            }
        }
    }
    std::sort(entries.begin(), entries.end());
    cell_start_.assign(size_t(res_.x) * res_.y * res_.z + 1, 0);
    cell_tets_.resize(entries.size());
    for (size_t i = 0; i < entries.size(); ++i) {
        ++cell_start_[entries[i].first + 1];
        cell_tets_[i] = entries[i].second;
    }
    for (size_t c = 1; c < cell_start_.size(); ++c)
        cell_start_[c] += cell_start_[c - 1];
}

std::optional<TetLocator::Location> TetLocator::locate(const Vec3f& p) const {
    int c[3];
    for (int k = 0; k < 3; ++k) {
        const float s = (p[k] - lo_[k]) / cell_size_[k];
        if (!(s >= -1e-4f && s <= float(res_[k]) + 1e-4f)) return std::nullopt;
        c[k] = std::clamp(int(s), 0, res_[k] - 1);
    }
    const size_t cell = size_t((c[2] * res_.y + c[1]) * res_.x + c[0]);
    // The tet whose smallest barycentric is largest: the containing one, or the nearest across a face when p
    // lies on it up to rounding.
    std::optional<Location> best;
    double best_min = -1e-4;
    const Vec3d pd(p);
    for (uint32_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
        const Frame& f = frames_[cell_tets_[i]];
        const Vec3d q = pd - f.origin;
        const double u = dot(f.inverse[0], q), v = dot(f.inverse[1], q), w = dot(f.inverse[2], q);
        const double smallest = std::min({u, v, w, 1.0 - u - v - w});
        if (smallest > best_min) {
            best_min = smallest;
            best = Location{cell_tets_[i], {float(u), float(v), float(w), float(1.0 - u - v - w)}};
            if (smallest >= 0.0) break;
        }
    }
    return best;
}

} // namespace penumbra
