#include "core/transform.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace penumbra {

Matrix4 Matrix4::identity() {
    Matrix4 r;
    for (int i = 0; i < 4; ++i) r.m[i][i] = 1.f;
    return r;
}

Matrix4 Matrix4::operator*(const Matrix4& o) const {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += double(m[i][k]) * o.m[k][j];
            r.m[i][j] = float(s);
        }
    return r;
}

Matrix4 Matrix4::transpose() const {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
    return r;
}

// Gauss-Jordan elimination with partial pivoting, in double precision.
Matrix4 Matrix4::inverse() const {
    double a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            a[i][j] = m[i][j];
            a[i][j + 4] = (i == j) ? 1.0 : 0.0;
        }
    for (int c = 0; c < 4; ++c) {
        int piv = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
        if (std::abs(a[piv][c]) < 1e-12) throw std::runtime_error("singular matrix cannot be inverted");
        if (piv != c)
            for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
        const double inv = 1.0 / a[c][c];
        for (int j = 0; j < 8; ++j) a[c][j] *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == c) continue;
            const double f = a[r][c];
            for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
        }
    }
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = float(a[i][j + 4]);
    return r;
}

Transform::Transform(const Matrix4& m) : matrix(m), inverse_matrix(m.inverse()) {}

Transform Transform::operator*(const Transform& o) const {
    return {matrix * o.matrix, o.inverse_matrix * inverse_matrix};
}

Transform Transform::translate(const Vec3f& t) {
    Matrix4 m = Matrix4::identity(), inv = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        m.m[i][3] = t[i];
        inv.m[i][3] = -t[i];
    }
    return {m, inv};
}

Transform Transform::scale(const Vec3f& s) {
    Matrix4 m = Matrix4::identity(), inv = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        m.m[i][i] = s[i];
        inv.m[i][i] = 1.f / s[i];
    }
    return {m, inv};
}

// Rodrigues' rotation about a (normalized) axis.
Transform Transform::rotate(const Vec3f& axis_in, float angle_deg) {
    const Vec3f a = normalize(axis_in);
    const double th = double(angle_deg) * 3.14159265358979323846 / 180.0;
    const double s = std::sin(th), c = std::cos(th), ic = 1.0 - c;
    Matrix4 m = Matrix4::identity();
    m.m[0][0] = float(a.x * a.x * ic + c);
    m.m[0][1] = float(a.x * a.y * ic - a.z * s);
    m.m[0][2] = float(a.x * a.z * ic + a.y * s);
    m.m[1][0] = float(a.x * a.y * ic + a.z * s);
    m.m[1][1] = float(a.y * a.y * ic + c);
    m.m[1][2] = float(a.y * a.z * ic - a.x * s);
    m.m[2][0] = float(a.x * a.z * ic - a.y * s);
    m.m[2][1] = float(a.y * a.z * ic + a.x * s);
    m.m[2][2] = float(a.z * a.z * ic + c);
    return {m, m.transpose()};
}

Transform Transform::look_at(const Vec3f& origin, const Vec3f& target, const Vec3f& up) {
    const Vec3f dir = normalize(target - origin);
    const Vec3f left_raw = cross(normalize(up), dir);
    if (squared_norm(left_raw) < 1e-12f) throw std::runtime_error("lookat: 'up' is parallel to the view direction");
    const Vec3f left = normalize(left_raw);
    const Vec3f new_up = cross(dir, left);
    Matrix4 m = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        m.m[i][0] = left[i];
        m.m[i][1] = new_up[i];
        m.m[i][2] = dir[i];
        m.m[i][3] = origin[i];
    }
    return Transform(m);
}

// Mitsuba's perspective(): maps camera space to clip space, x/y scaled by 1/tan(fov/2), z to [0,1].
Transform Transform::perspective(float fov_deg, float near_clip, float far_clip) {
    const float recip = 1.f / (far_clip - near_clip);
    const float cot = 1.f / std::tan(radians(fov_deg) * 0.5f);
    Matrix4 m = Matrix4::identity();
    m.m[0][0] = cot;
    m.m[1][1] = cot;
    m.m[2][2] = far_clip * recip;
    m.m[2][3] = -near_clip * far_clip * recip;
    m.m[3][2] = 1.f;
    m.m[3][3] = 0.f;
    return Transform(m);
}

std::string Transform::to_string() const {
    std::ostringstream os;
    for (int i = 0; i < 4; ++i) {
        os << (i == 0 ? "[[" : " [");
        for (int j = 0; j < 4; ++j) os << matrix.m[i][j] << (j < 3 ? ", " : "]");
        os << (i < 3 ? "\n" : "]");
    }
    return os.str();
}

} // namespace penumbra
