// 4x4 affine/projective transforms (float: scene set-up, not differentiated directly).
#pragma once
#include "core/vector.h"

#include <array>
#include <string>

namespace penumbra {

struct Matrix4 {
    std::array<std::array<float, 4>, 4> m{}; // row-major: m[row][col]
    static Matrix4 identity();
    Matrix4 operator*(const Matrix4& o) const;
    Matrix4 inverse() const; // throws std::runtime_error if singular
    Matrix4 transpose() const;
    bool operator==(const Matrix4& o) const { return m == o.m; }
};

struct Transform {
    Matrix4 matrix = Matrix4::identity();
    Matrix4 inverse_matrix = Matrix4::identity();

    Transform() = default;
    explicit Transform(const Matrix4& m);
    Transform(const Matrix4& m, const Matrix4& inv) : matrix(m), inverse_matrix(inv) {}

    Transform operator*(const Transform& o) const; // this ∘ o (o applied first)
    Transform inverse() const { return {inverse_matrix, matrix}; }
    bool is_identity() const { return matrix == Matrix4::identity(); }

    template <typename T> Vec3<T> apply_point(const Vec3<T>& p) const {
        const auto& a = matrix.m;
        Vec3<T> r(p.x * a[0][0] + p.y * a[0][1] + p.z * a[0][2] + T(a[0][3]),
                  p.x * a[1][0] + p.y * a[1][1] + p.z * a[1][2] + T(a[1][3]),
                  p.x * a[2][0] + p.y * a[2][1] + p.z * a[2][2] + T(a[2][3]));
        T w = p.x * a[3][0] + p.y * a[3][1] + p.z * a[3][2] + T(a[3][3]);
        return w == T(1) ? r : r / w;
    }
    template <typename T> Vec3<T> apply_vector(const Vec3<T>& v) const {
        const auto& a = matrix.m;
        return {v.x * a[0][0] + v.y * a[0][1] + v.z * a[0][2], v.x * a[1][0] + v.y * a[1][1] + v.z * a[1][2],
                v.x * a[2][0] + v.y * a[2][1] + v.z * a[2][2]};
    }
    // Normals transform with the inverse transpose (not normalized).
    template <typename T> Vec3<T> apply_normal(const Vec3<T>& n) const {
        const auto& a = inverse_matrix.m;
        return {n.x * a[0][0] + n.y * a[1][0] + n.z * a[2][0], n.x * a[0][1] + n.y * a[1][1] + n.z * a[2][1],
                n.x * a[0][2] + n.y * a[1][2] + n.z * a[2][2]};
    }

    static Transform translate(const Vec3f& t);
    static Transform scale(const Vec3f& s);
    static Transform rotate(const Vec3f& axis, float angle_deg);
    // Mitsuba's look_at: local x = left, y = up, z = forward.
    static Transform look_at(const Vec3f& origin, const Vec3f& target, const Vec3f& up);
    static Transform perspective(float fov_deg, float near_clip, float far_clip);
    std::string to_string() const;
};

} // namespace penumbra
