// Mesh file readers: PLY (ascii / binary both endians), OBJ, Mitsuba .serialized, and their error messages.
#include "core/error.h"
#include "scene/mesh.h"

#include "mesh_test_util.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>

using namespace penumbra;
using penumbra::test::error_of;
using penumbra::test::ScratchDir;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
    static const ScratchDir dir("penumbra_test_mesh_");
    return dir.path;
}

std::string write_file(const std::string& name, const std::string& contents) {
    return test::write_file(temp_dir(), name, contents);
}

// Appends the bytes of v in the requested byte order.
template <typename V> void put(std::string& out, V v, bool little) {
    unsigned char b[sizeof(V)];
    std::memcpy(b, &v, sizeof(V));
    if (little != (std::endian::native == std::endian::little))
        for (size_t i = 0; i < sizeof(V) / 2; ++i)
            std::swap(b[i], b[sizeof(V) - 1 - i]);
    out.append(reinterpret_cast<const char*>(b), sizeof(V));
}

// Corners of the unit square of the ascii test.
const float quad_pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};

void expect_vec(const Vec3f& a, const Vec3f& b) {
    EXPECT_FLOAT_EQ(a.x, b.x);
    EXPECT_FLOAT_EQ(a.y, b.y);
    EXPECT_FLOAT_EQ(a.z, b.z);
}

} // namespace

TEST(MeshPly, AsciiQuadWithNormalsUvsAndExtraProperties) {
    const std::string path =
        write_file("ascii.ply", "ply\r\n"
                                "format ascii 1.0\n"
                                "comment made by hand\n"
                                "element vertex 4\n"
                                "property float x\nproperty float y\nproperty float z\n"
                                "property uchar red\n"
                                "property float nx\nproperty float ny\nproperty float nz\n"
                                "property float s\nproperty float t\n"
                                "element face 1\n"
                                "property list uchar int vertex_indices\n"
                                "property int flags\n"
                                "element edge 1\n"
                                "property list uchar uint vertex\n"
                                "end_header\n"
                                "0 0 0 255 0 0 1 0 0\n"
                                "1 0 0 255 0 0 1 1 0\n"
                                "1 1 0 255 0 0 1 1 1\n"
                                "0 1 0 255 0 0 1 0 1\n"
                                "4 0 1 2 3 7\n"
                                "2 0 1\n");
    const TriangleMesh m = load_ply(path);
    ASSERT_EQ(m.vertex_count(), 4u);
    ASSERT_EQ(m.face_count(), 2u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
    ASSERT_EQ(m.normals.size(), 4u);
    ASSERT_EQ(m.uvs.size(), 4u);
    for (int i = 0; i < 4; ++i)
        expect_vec(m.positions[i], Vec3f(quad_pos[i][0], quad_pos[i][1], quad_pos[i][2]));
    expect_vec(m.normals[2], Vec3f(0, 0, 1));
    EXPECT_FLOAT_EQ(m.uvs[2].x, 1.f);
    EXPECT_FLOAT_EQ(m.uvs[3].y, 1.f);
}

// The same content (quad + pentagon, double normals, an unknown list property) in both binary byte orders.
class MeshPlyBinary : public ::testing::TestWithParam<bool> {};

TEST_P(MeshPlyBinary, QuadAndPentagon) {
    const bool little = GetParam();
    std::string data = std::string("ply\nformat ") + (little ? "binary_little_endian" : "binary_big_endian") +
                       " 1.0\n"
                       "element vertex 6\n"
                       "property float x\nproperty float y\nproperty float z\n"
                       "property list uchar short junk\n"
                       "property double nx\nproperty double ny\nproperty double nz\n"
                       "element face 2\n"
                       "property list uchar ushort vertex_index\n"
                       "end_header\n";
    for (int i = 0; i < 6; ++i) {
        put<float>(data, float(i), little);
        put<float>(data, float(i % 2), little);
        put<float>(data, 0.f, little);
        put<uint8_t>(data, 2, little);
        put<int16_t>(data, -7, little);
        put<int16_t>(data, 300, little);
        put<double>(data, 0.0, little);
        put<double>(data, 0.0, little);
        put<double>(data, -1.0, little);
    }
    put<uint8_t>(data, 4, little);
    for (uint16_t v : {0, 1, 2, 3})
        put<uint16_t>(data, v, little);
    put<uint8_t>(data, 5, little);
    for (uint16_t v : {1, 2, 3, 4, 5})
        put<uint16_t>(data, v, little);
    const TriangleMesh m = load_ply(write_file(little ? "le.ply" : "be.ply", data));
    ASSERT_EQ(m.vertex_count(), 6u);
    // Fan triangulation (v0, v[k-1], v[k]): quad -> 2 triangles, pentagon -> 3.
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 1, 2, 3, 1, 3, 4, 1, 4, 5}));
    expect_vec(m.positions[5], Vec3f(5, 1, 0));
    expect_vec(m.normals[3], Vec3f(0, 0, -1));
    EXPECT_TRUE(m.uvs.empty());
}

INSTANTIATE_TEST_SUITE_P(ByteOrder, MeshPlyBinary, ::testing::Values(true, false));

TEST(MeshPly, MalformedHeaderNamesFileLineAndType) {
    const std::string path =
        write_file("bad_type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\n"
                                   "end_header\n0\n");
    const std::string msg = error_of([&] { load_ply(path); });
    EXPECT_NE(msg.find(path + ":4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("unknown property type 'flot'"), std::string::npos) << msg;
}

TEST(MeshPly, BadAsciiNumberNamesLine) {
    const std::string path =
        write_file("bad_number.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"
                                     "property float x\nproperty float y\nproperty float z\n"
                                     "element face 1\nproperty list uchar int vertex_indices\n"
                                     "end_header\n0 0 0\n1 0 0\n0 1x 0\n3 0 1 2\n");
    const std::string msg = error_of([&] { load_ply(path); });
    EXPECT_NE(msg.find(path + ":12"), std::string::npos) << msg;
    EXPECT_NE(msg.find("invalid number '1x'"), std::string::npos) << msg;
}

TEST(MeshPly, TruncatedBinaryIsReported) {
    std::string data = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                       "property float x\nproperty float y\nproperty float z\n"
                       "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (int i = 0; i < 9; ++i)
        put<float>(data, 0.5f, true);
    put<uint8_t>(data, 3, true);
    put<int32_t>(data, 0, true); // the two remaining indices are missing
    const std::string path = write_file("truncated.ply", data);
    const std::string msg = error_of([&] { load_ply(path); });
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
    EXPECT_NE(msg.find("element 'face' 0 of 1"), std::string::npos) << msg;
}

TEST(MeshPly, IndexOutOfRangeAndNonFiniteAndMissingFile) {
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::string bad_index = write_file("bad_index.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    std::string msg = error_of([&] { load_ply(bad_index); });
    EXPECT_NE(msg.find(bad_index), std::string::npos) << msg;
    EXPECT_NE(msg.find("references vertex 7"), std::string::npos) << msg;

    const std::string nan = write_file("nan.ply", header + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    msg = error_of([&] { load_ply(nan); });
    EXPECT_NE(msg.find(nan), std::string::npos) << msg;
    EXPECT_NE(msg.find("vertex 1 has a non-finite position"), std::string::npos) << msg;

    const std::string missing = (temp_dir() / "does_not_exist.ply").string();
    msg = error_of([&] { load_ply(missing); });
    EXPECT_NE(msg.find(missing), std::string::npos) << msg;
}

TEST(MeshObj, UvsNormalsPolygonAndVertexSharing) {
    const std::string path = write_file("poly.obj", "mtllib missing.mtl\n"
                                                    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\n"
                                                    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
                                                    "vn 0 0 1\n"
                                                    "g group\nusemtl whatever\n"
                                                    "f 1/1/1 2/2/1 3/3/1 4/4/1 5/5/1\n"
                                                    "f 1/1/1 3/3/1 4/4/1\n");
    const TriangleMesh m = load_obj(path);
    // The second face reuses the (v, vt, vn) triples of the first: no new vertices.
    ASSERT_EQ(m.vertex_count(), 5u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 2, 3}));
    ASSERT_EQ(m.uvs.size(), 5u);
    ASSERT_EQ(m.normals.size(), 5u);
    EXPECT_FLOAT_EQ(m.uvs[4].x, 0.5f); // stored as in the file; flip_tex_coords is the factory's job
    expect_vec(m.normals[4], Vec3f(0, 0, 1));
    expect_vec(m.positions[4], Vec3f(-1, 0.5f, 0));
}

TEST(MeshObj, DistinctTexcoordsSplitVertices) {
    const std::string path = write_file("split.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                                     "vt 0 0\nvt 1 0\nvt 0 1\nvt 0.25 0.75\n"
                                                     "f 1/1 2/2 3/3\nf 2/2 4/4 3/4\n");
    const TriangleMesh m = load_obj(path);
    EXPECT_EQ(m.vertex_count(), 5u); // vertex 3 appears with two texture coordinates
    EXPECT_TRUE(m.normals.empty());
}

TEST(MeshObj, BadIndexAndMissingFile) {
    const std::string path = write_file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    std::string msg = error_of([&] { load_obj(path); });
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("vertex 9"), std::string::npos) << msg;
    const std::string missing = (temp_dir() / "none.obj").string();
    msg = error_of([&] { load_obj(missing); });
    EXPECT_NE(msg.find(missing), std::string::npos) << msg;
}

namespace {

// One .serialized record (header + zlib stream) with a single triangle; double precision with normals and uvs
// when `full`, otherwise float positions only.
std::string serialized_record(bool full, float offset) {
    std::string raw;
    put<uint32_t>(raw, full ? (0x0001u | 0x0002u | 0x2000u) : 0x1000u, true);
    raw += std::string("mesh") + '\0';
    put<uint64_t>(raw, 3, true);
    put<uint64_t>(raw, 1, true);
    const float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (const auto& v : p)
        for (float c : v)
            full ? put<double>(raw, double(c + offset), true) : put<float>(raw, c + offset, true);
    if (full) {
        for (int i = 0; i < 3; ++i)
            for (double c : {0.0, 0.0, 1.0})
                put<double>(raw, c, true);
        for (int i = 0; i < 3; ++i)
            for (double c : {0.25 * i, 0.5})
                put<double>(raw, c, true);
    }
    for (uint32_t i : {0u, 1u, 2u})
        put<uint32_t>(raw, i, true);
    uLongf size = compressBound(uLong(raw.size()));
    std::string packed(size, '\0');
    EXPECT_EQ(compress(reinterpret_cast<Bytef*>(packed.data()), &size,
                       reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size())),
              Z_OK);
    packed.resize(size);
    std::string record;
    put<uint16_t>(record, 0x041C, true);
    put<uint16_t>(record, 4, true);
    return record + packed;
}

} // namespace

TEST(MeshSerialized, TwoMeshesWithDictionary) {
    const std::string first = serialized_record(true, 0.f), second = serialized_record(false, 10.f);
    std::string data = first + second;
    put<uint64_t>(data, 0, true);
    put<uint64_t>(data, first.size(), true);
    put<uint32_t>(data, 2, true);
    const std::string path = write_file("two.serialized", data);

    const TriangleMesh a = load_serialized(path, 0);
    ASSERT_EQ(a.face_count(), 1u);
    ASSERT_EQ(a.normals.size(), 3u);
    ASSERT_EQ(a.uvs.size(), 3u);
    EXPECT_FLOAT_EQ(a.uvs[2].x, 0.5f);
    expect_vec(a.normals[1], Vec3f(0, 0, 1));

    const TriangleMesh b = load_serialized(path, 1);
    ASSERT_EQ(b.face_count(), 1u);
    EXPECT_TRUE(b.normals.empty());
    expect_vec(b.positions[1], Vec3f(11, 10, 10));

    const std::string msg = error_of([&] { load_serialized(path, 2); });
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("out of range"), std::string::npos) << msg;

    std::string cut = data.substr(0, first.size() / 2);
    put<uint64_t>(cut, 0, true);
    put<uint32_t>(cut, 1, true);
    const std::string cut_path = write_file("cut.serialized", cut);
    EXPECT_NE(error_of([&] { load_serialized(cut_path, 0); }).find(cut_path), std::string::npos);
}

// ---- real meshes shipped with the Mitsuba test data (skipped when absent)
// ----------------------------------
namespace {

const std::string mesh_dir = PENUMBRA_SHARED_DIR "/mitsuba-data/common/meshes/";

double total_area(const TriangleMesh& m) {
    double a = 0;
    for (size_t f = 0; f < m.face_count(); ++f) {
        const Vec3f p0 = m.positions[m.indices[3 * f]], p1 = m.positions[m.indices[3 * f + 1]],
                    p2 = m.positions[m.indices[3 * f + 2]];
        a += 0.5 * norm(cross(p1 - p0, p2 - p0));
    }
    return a;
}

void check_real_mesh(const TriangleMesh& m, size_t min_faces) {
    EXPECT_GE(m.face_count(), min_faces);
    const double area = total_area(m);
    EXPECT_TRUE(std::isfinite(area));
    EXPECT_GT(area, 0.0);
}

} // namespace

TEST(MeshRealFiles, PlyFiles) {
    if (!fs::exists(mesh_dir + "bunny.ply")) GTEST_SKIP() << "Mitsuba test meshes not present";
    // Face counts from the files' headers (all triangles): binary, ascii, and ascii with extra properties.
    const TriangleMesh bunny = load_ply(mesh_dir + "bunny.ply");
    EXPECT_EQ(bunny.vertex_count(), 35947u);
    check_real_mesh(bunny, 69451);
    check_real_mesh(load_ply(mesh_dir + "teapot.ply"), 2256);
    check_real_mesh(load_ply(mesh_dir + "bunny_lowres.ply"), 948);
    check_real_mesh(load_ply(mesh_dir + "sphere.ply"), 840);
}

TEST(MeshRealFiles, ObjFiles) {
    if (!fs::exists(mesh_dir + "sphere.obj")) GTEST_SKIP() << "Mitsuba test meshes not present";
    const TriangleMesh sphere = load_obj(mesh_dir + "sphere.obj");
    check_real_mesh(sphere, 32512); // 32512 'f' lines, each at least one triangle
    size_t cbox_files = 0;
    for (const auto& entry : fs::directory_iterator(mesh_dir + "cbox"))
        if (entry.path().extension() == ".obj") {
            SCOPED_TRACE(entry.path().string());
            check_real_mesh(load_obj(entry.path().string()), 2);
            ++cbox_files;
        }
    EXPECT_GT(cbox_files, 0u);
}

TEST(MeshRealFiles, SerializedFile) {
    const std::string path = mesh_dir + "matpreview.serialized";
    if (!fs::exists(path)) GTEST_SKIP() << "Mitsuba test meshes not present";
    std::ifstream in(path, std::ios::binary);
    in.seekg(-4, std::ios::end);
    uint32_t count = 0;
    in.read(reinterpret_cast<char*>(&count), 4);
    ASSERT_GT(count, 0u);
    ASSERT_LT(count, 100u);
    for (uint32_t i = 0; i < count; ++i) {
        SCOPED_TRACE(i);
        check_real_mesh(load_serialized(path, int(i)), 1);
    }
    EXPECT_NE(error_of([&] { load_serialized(path, int(count)); }).find("out of range"), std::string::npos);
}
