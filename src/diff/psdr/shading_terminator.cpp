#include "diff/psdr/shading_terminator.h"

#include <cmath>

namespace penumbra {

namespace {

struct TriangleData {
    Vec3<double> p[3], n[3];
};

TriangleData triangle_data(const TriangleMesh& mesh, uint32_t prim) {
    TriangleData t;
    const uint32_t* i = &mesh.indices[3 * size_t(prim)];
    for (int k = 0; k < 3; ++k) {
        const Vec3f p = mesh.positions[i[k]], n = mesh.normals[i[k]];
        t.p[k] = Vec3<double>(p.x, p.y, p.z);
        t.n[k] = Vec3<double>(n.x, n.y, n.z);
    }
    return t;
}

} // namespace

bool crosses_shading_terminator(const TriangleMesh& mesh, uint32_t prim, const Vec3f& eye) {
    const TriangleData t = triangle_data(mesh, prim);
    const Vec3<double> c(eye.x, eye.y, eye.z);
    bool negative = false, positive = false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double m = dot(t.n[i], c - t.p[j]);
            negative |= m < 0.0;
            positive |= m > 0.0;
        }
    return negative && positive;
}

// Along the line b(w) = β + w v of sweep k, G(w) = (N0 + w Nv) · (W0 − w Ev) is a quadratic in w, with
// N0 = n(β), Nv = v1 dn1 + v2 dn2, W0 = c − x(β), Ev = v1 e1 + v2 e2.
int shading_terminator_points(const TriangleMesh& mesh, uint32_t prim, const Vec3f& eye, int sweep, float u,
                              TerminatorPoint out[2]) {
    const TriangleData t = triangle_data(mesh, prim);
    const Vec3<double> c(eye.x, eye.y, eye.z);
    const Vec3<double> e1 = t.p[1] - t.p[0], e2 = t.p[2] - t.p[0], dn1 = t.n[1] - t.n[0],
                       dn2 = t.n[2] - t.n[0];
    // Sweep 1: b = (u, w); sweep 2: b = (w, u); sweep 0: b = (w, 1 − u − w); w in [0, 1 − u].
    const double uu = u;
    const double beta1 = sweep == 1 ? uu : 0.0, beta2 = sweep == 0 ? 1.0 - uu : sweep == 2 ? uu : 0.0;
    const double v1 = sweep == 1 ? 0.0 : 1.0, v2 = sweep == 1 ? 1.0 : sweep == 0 ? -1.0 : 0.0;
    const Vec3<double> N0 = t.n[0] + dn1 * beta1 + dn2 * beta2, Nv = dn1 * v1 + dn2 * v2;
    const Vec3<double> W0 = c - t.p[0] - e1 * beta1 - e2 * beta2, Ev = e1 * v1 + e2 * v2;
    const double qa = -dot(Nv, Ev), qb = dot(Nv, W0) - dot(N0, Ev), qc = dot(N0, W0);
    double roots[2];
    int found = 0;
    if (std::abs(qa) < 1e-12 * (std::abs(qb) + std::abs(qc))) {
        if (qb != 0.0) roots[found++] = -qc / qb;
    } else {
        const double disc = qb * qb - 4.0 * qa * qc;
        if (!(disc > 0.0)) return 0; // no crossing, or a tangency (measure zero)
        // Numerically stable roots: q = −(b + sign(b) √disc) / 2, r = q / a and c / q.
        const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
        if (q != 0.0) roots[found++] = qc / q;
        roots[found++] = q / qa;
    }
    int n = 0;
    for (int k = 0; k < found; ++k) {
        const double w = roots[k];
        if (!(w >= 0.0 && w <= 1.0 - uu)) continue;
        const double b1 = beta1 + w * v1, b2 = beta2 + w * v2;
        const Vec3<double> normal = t.n[0] + dn1 * b1 + dn2 * b2, to_eye = c - t.p[0] - e1 * b1 - e2 * b2;
        const double length = norm(normal);
        if (!(length > 0.0)) continue;
        // On the curve G = 0, so the partials of G / |n| are those of G over |n|.
        out[n++] = {Vec2f(float(b1), float(b2)), float((dot(dn1, to_eye) - dot(normal, e1)) / length),
                    float((dot(dn2, to_eye) - dot(normal, e2)) / length)};
    }
    return n;
}

} // namespace penumbra
