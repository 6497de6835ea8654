// Loading grids: gridvolume lookups (trilinear, nearest, wrap modes, placement, single-channel RGB, Var),
// Mitsuba's docs data (albedo.vol), an OpenVDB fixture written with the OpenVDB API, and one clear LoadError
// line with the XML file:line for every malformed .vol/.vdb file.
#include "scene/volumes/gridvolume.h"

#include "scene/factory.h"
#include "scene/media_loading.h"

#include "media_test_util.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

using namespace penumbra;
using namespace penumbra::test;

namespace {

// A linear field (trilinear interpolation reproduces it exactly between the first and last voxel centres).
float linear_field(int x, int y, int z, int c) {
    return float(x) + 10.f * float(y) + 100.f * float(z) + 1000.f * float(c);
}

VolumeGridData linear_grid(int channels) {
    VolumeGridData g;
    g.res = {4, 3, 5};
    g.channels = channels;
    for (int z = 0; z < 5; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x)
                for (int c = 0; c < channels; ++c)
                    g.values.push_back(linear_field(x, y, z, c));
    return g;
}

// The texture-space point of voxel coordinates (x, y, z) (voxel i centred at (i + 1/2) / res).
Vec3f at_voxel(float x, float y, float z) { return {(x + 0.5f) / 4.f, (y + 0.5f) / 3.f, (z + 0.5f) / 5.f}; }

void expect_color(const Color3f& a, const Color3f& b, float tol, const std::string& what) {
    EXPECT_NEAR(a.x, b.x, tol) << what;
    EXPECT_NEAR(a.y, b.y, tol) << what;
    EXPECT_NEAR(a.z, b.z, tol) << what;
}

// The message of the LoadError thrown while loading `dir/scene.xml` (tests/xml_test_util.h).
std::string load_error(const std::string& dir) {
    return load_error_of([&] { load_scene(dir + "/scene.xml"); });
}

// A scene whose sigma_t grid reads `filename`; the filename parameter is on line 5.
void write_grid_scene(const TempDir& dir, const std::string& filename, const std::string& extra = "") {
    dir.write(
        "scene.xml",
        "<scene version=\"3.0.0\">\n<shape type=\"cube\">\n"
        "<medium type=\"heterogeneous\" name=\"interior\">\n<volume type=\"gridvolume\" name=\"sigma_t\">\n"
        "<string name=\"filename\" value=\"" +
            filename + "\"/>\n" + extra + "</volume>\n</medium>\n</shape>\n</scene>\n");
}

#define EXPECT_CONTAINS(haystack, needle) EXPECT_NE((haystack).find(needle), std::string::npos) << (haystack)

std::string valid_vol() {
    return vol_bytes({3, 2, 4}, 1, Vec3f(0.f), Vec3f(1.f),
                     [](int x, int y, int z, int) { return 0.1f * float(x + y + z); });
}

} // namespace

TEST(MediaLoading, TrilinearReproducesVoxelsAndLinearFields) {
    const GridVolume grid(linear_grid(3), Transform(), GridVolume::Filter::Trilinear,
                          GridVolume::Wrap::Clamp);
    EXPECT_EQ(grid.channel_count(), 3);
    EXPECT_EQ(grid.max(), linear_field(3, 2, 4, 2));
    EXPECT_EQ(grid.min(), 0.f);
    for (int z = 0; z < 5; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x)
                expect_color(grid.eval(at_voxel(float(x), float(y), float(z))),
                             {linear_field(x, y, z, 0), linear_field(x, y, z, 1), linear_field(x, y, z, 2)},
                             1e-3f, "voxel centre");
    PCG32 rng(1);
    for (int i = 0; i < 200; ++i) {
        const float x = 3.f * rng.next_float(), y = 2.f * rng.next_float(), z = 4.f * rng.next_float();
        const float v = x + 10.f * y + 100.f * z;
        expect_color(grid.eval(at_voxel(x, y, z)), {v, v + 1000.f, v + 2000.f}, 2e-3f, "between centres");
    }
    // Clamp: beyond the last centre the boundary voxels' value.
    expect_color(grid.eval(Vec3f(-0.4f, 1.3f, 0.5f)),
                 Color3f(linear_field(0, 2, 2, 0), linear_field(0, 2, 2, 1), linear_field(0, 2, 2, 2)), 1e-3f,
                 "clamp");
}

TEST(MediaLoading, NearestWrapModesAndSingleChannel) {
    const GridVolume nearest(linear_grid(1), Transform(), GridVolume::Filter::Nearest,
                             GridVolume::Wrap::Clamp);
    EXPECT_EQ(nearest.channel_count(), 1);
    // Anywhere inside voxel (2, 1, 3): its value, repeated over RGB.
    expect_color(nearest.eval(at_voxel(2.3f, 0.6f, 2.55f)), Color3f(linear_field(2, 1, 3, 0)), 0.f,
                 "nearest");
    expect_color(nearest.eval(at_voxel(1.51f, 1.49f, 3.4f)), Color3f(linear_field(2, 1, 3, 0)), 0.f,
                 "nearest");

    const GridVolume repeat(linear_grid(1), Transform(), GridVolume::Filter::Trilinear,
                            GridVolume::Wrap::Repeat);
    const GridVolume mirror(linear_grid(1), Transform(), GridVolume::Filter::Trilinear,
                            GridVolume::Wrap::Mirror);
    PCG32 rng(2);
    for (int i = 0; i < 100; ++i) {
        const Vec3f p(rng.next_float(), rng.next_float(), rng.next_float());
        expect_color(repeat.eval(p + Vec3f(1.f, -2.f, 3.f)), repeat.eval(p), 2e-2f, "repeat is periodic");
        expect_color(mirror.eval(Vec3f(-p.x, p.y, p.z)), mirror.eval(p), 1e-3f, "mirror about 0");
        expect_color(mirror.eval(Vec3f(p.x, 2.f - p.y, p.z)), mirror.eval(p), 2e-2f, "mirror about 1");
    }
    // Repeat blends the last and first voxels across the boundary (at u = 0 halfway between them).
    EXPECT_NEAR(repeat.eval(Vec3f(0.f, at_voxel(0, 1, 2).y, at_voxel(0, 1, 2).z)).x,
                0.5f * (linear_field(0, 1, 2, 0) + linear_field(3, 1, 2, 0)), 1e-3f);
}

// Var lookups give the float values, and derivatives flow through the weights: d/dx of the linear field is
// res.x / (to_world scale) per world unit.
TEST(MediaLoading, VarLookupMatchesFloatAndDifferentiates) {
    const Transform to_world =
        Transform::translate(Vec3f(1.f, 0.f, 0.f)) * Transform::scale(Vec3f(2.f, 1.f, 1.f));
    const GridVolume grid(linear_grid(3), to_world, GridVolume::Filter::Trilinear, GridVolume::Wrap::Clamp);
    const Vec3f p(1.9f, 0.4f, 0.55f);
    Tape::current().clear();
    const Vec3<Var> pv(Var::parameter(p.x, 0), Var(p.y), Var(p.z));
    const Color3<Var> v = grid.eval(pv);
    const Color3f f = grid.eval(p);
    EXPECT_EQ(detach(v.x), f.x);
    EXPECT_EQ(detach(v.z), f.z);
    double gradient[1] = {0.0};
    std::vector<float> adjoint;
    Tape::current().backward({{v.y.id, 1.f}}, gradient, adjoint);
    EXPECT_NEAR(gradient[0], 4.0 / 2.0, 1e-4) << "d value / d world x";
    Tape::current().clear();
}

TEST(MediaLoading, PlacementToWorldAndGridBoundingBox) {
    TempDir dir;
    write_bytes(dir.str() + "/g.vol",
                vol_bytes({4, 3, 5}, 3, Vec3f(1.f, 2.f, 3.f), Vec3f(2.f, 4.f, 7.f), linear_field));
    auto load = [&](const std::string& extra) {
        Properties props("gridvolume", SourceLocation{"x.xml", 1});
        props.set("filename", std::string("g.vol"), SourceLocation{"x.xml", 2});
        if (extra == "bbox" || extra == "both") props.set("use_grid_bbox", true, SourceLocation{"x.xml", 3});
        if (extra == "both")
            props.set("to_world", Transform::translate(Vec3f(10.f, 0.f, 0.f)), SourceLocation{"x.xml", 4});
        LoadContext ctx;
        ctx.search_paths = {dir.str()};
        return std::static_pointer_cast<GridVolume>(make_volume(props, ctx));
    };
    const auto unit = load(""), boxed = load("bbox"), moved = load("both");
    EXPECT_EQ(unit->bbox().lo, Vec3f(0.f));
    EXPECT_EQ(unit->bbox().hi, Vec3f(1.f));
    EXPECT_EQ(boxed->bbox().lo, Vec3f(1.f, 2.f, 3.f));
    EXPECT_EQ(boxed->bbox().hi, Vec3f(2.f, 4.f, 7.f));
    EXPECT_EQ(moved->bbox().lo, Vec3f(11.f, 2.f, 3.f));
    // The same voxel centre in each frame.
    const Vec3f u = at_voxel(2, 1, 3);
    const Vec3f in_box = Vec3f(1.f, 2.f, 3.f) + u * Vec3f(1.f, 2.f, 4.f);
    expect_color(unit->eval(u),
                 Color3f(linear_field(2, 1, 3, 0), linear_field(2, 1, 3, 1), linear_field(2, 1, 3, 2)), 1e-3f,
                 "unit");
    expect_color(boxed->eval(in_box), unit->eval(u), 1e-3f, "use_grid_bbox");
    expect_color(moved->eval(in_box + Vec3f(10.f, 0.f, 0.f)), unit->eval(u), 1e-3f,
                 "use_grid_bbox + to_world");
}

// A heterogeneous medium's extinction is zero outside its grid's box (the albedo grid clamps).
TEST(MediaLoading, HeterogeneousSigmaTVanishesOutsideTheGrid) {
    TempDir dir;
    write_bytes(dir.str() + "/g.vol", valid_vol());
    const auto medium =
        load_medium("<medium type=\"heterogeneous\" name=\"interior\"><volume type=\"gridvolume\" "
                    "name=\"sigma_t\"><string name=\"filename\" value=\"g.vol\"/></volume>"
                    "<float name=\"scale\" value=\"2\"/></medium>",
                    dir.str());
    EXPECT_FALSE(medium->is_homogeneous());
    EXPECT_EQ(medium->sigma_t(Vec3f(1.2f, 0.5f, 0.5f)), Color3f(0.f));
    // Voxel (2, 1, 3) of the 3 x 2 x 4 grid: 0.1 * 6, times scale 2.
    EXPECT_NEAR(medium->sigma_t(Vec3f(2.5f / 3.f, 1.5f / 2.f, 3.5f / 4.f)).x, 1.2f, 1e-5f);
    EXPECT_EQ(medium->albedo(Vec3f(1.2f, 0.5f, 0.5f)), Color3f(0.75f));
}

TEST(MediaLoading, MitsubaDocsAlbedoVol) {
    const std::string path =
        std::string(PENUMBRA_SHARED_DIR) + "/mitsuba-data/docs/scenes/textures/albedo.vol";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "Mitsuba docs data not found at " << path;
    Properties props("gridvolume", SourceLocation{"x.xml", 1});
    props.set("filename", path, SourceLocation{"x.xml", 2});
    const auto grid = std::static_pointer_cast<GridVolume>(make_volume(props, LoadContext{}));
    ASSERT_EQ(grid->resolution(), Vec3i(16, 16, 16));
    EXPECT_EQ(grid->channel_count(), 3);
    // Voxel values read independently from the file.
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_EQ(bytes.size(), 48u + 16u * 16u * 16u * 3u * 4u);
    for (const Vec3i v : {Vec3i(0, 0, 0), Vec3i(5, 9, 2), Vec3i(15, 15, 15), Vec3i(8, 3, 12)}) {
        Color3f expected;
        for (int c = 0; c < 3; ++c)
            std::memcpy(&expected[c], bytes.data() + 48 + 4 * (((v.z * 16 + v.y) * 16 + v.x) * 3 + c), 4);
        expect_color(grid->eval(Vec3f((float(v.x) + 0.5f) / 16.f, (float(v.y) + 0.5f) / 16.f,
                                      (float(v.z) + 0.5f) / 16.f)),
                     expected, 1e-6f, "albedo.vol voxel");
    }
}

TEST(MediaLoading, MalformedVolFilesGiveOneClearError) {
    const std::string good = valid_vol();
    auto with = [&](size_t offset, int32_t value) {
        std::string b = good;
        std::memcpy(b.data() + offset, &value, 4);
        return b;
    };
    std::string nan_voxel = good;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan_voxel.data() + 48 + 4 * ((2 * 2 + 0) * 3 + 1), &nan, 4); // voxel (1, 0, 2)
    std::string version = good;
    version[3] = 2;
    const std::pair<std::string, std::string> cases[] = {
        {"", "not a Mitsuba .vol file"},
        {"VOX" + good.substr(3), "not a Mitsuba .vol file"},
        {good.substr(0, 20), "truncated header (20 of 48 bytes)"},
        {version, "unsupported .vol version 2 (expected 3)"},
        {with(4, 2), "unsupported encoding 2 (only 1, float32, is supported)"},
        {with(20, 6), "6-channel grids are not supported"},
        {with(20, 2), "invalid channel count 2 (expected 1 or 3)"},
        {with(8, 0), "invalid resolution 0 x 2 x 4"},
        {with(12, -5), "invalid resolution 3 x -5 x 4"},
        {with(8, 1 << 30), "truncated: the header declares 1073741824 x 2 x 4 x 1 = 8589934592 values"},
        {with(12, 1 << 30)
             .replace(8, 4, with(8, 1 << 30).substr(8, 4))
             .replace(16, 4, with(16, 1 << 30).substr(16, 4)),
         "truncated: the header declares 1073741824 x 1073741824 x 1073741824 x 1 = "
         "1237940039285380274899124224 values"},
        {good.substr(0, good.size() - 4),
         "truncated: the header declares 3 x 2 x 4 x 1 = 24 values, the file holds 23"},
        {good + "abcd", "size mismatch: 4 bytes after the 3 x 2 x 4 x 1 values"},
        {nan_voxel, "non-finite value nan at voxel (1, 0, 2) channel 0"},
    };
    for (const auto& [bytes, expected] : cases) {
        TempDir dir;
        write_bytes(dir.str() + "/bad.vol", bytes);
        write_grid_scene(dir, "bad.vol");
        const std::string msg = load_error(dir.str());
        EXPECT_CONTAINS(msg, "scene.xml:5: gridvolume: 'bad.vol': " + expected);
    }
}

TEST(MediaLoading, InvalidGridParametersGiveOneClearError) {
    TempDir dir;
    write_bytes(dir.str() + "/g.vol", valid_vol());
    write_bytes(dir.str() + "/flat.vol",
                vol_bytes({2, 2, 2}, 1, Vec3f(0.f), Vec3f(1.f, 0.f, 1.f), linear_field));
    write_bytes(dir.str() + "/negative.vol",
                vol_bytes({2, 2, 2}, 1, Vec3f(0.f), Vec3f(1.f),
                          [](int x, int, int, int) { return x == 1 ? -0.5f : 1.f; }));
    write_grid_scene(dir, "missing.vol");
    EXPECT_CONTAINS(load_error(dir.str()), "scene.xml:5: file 'missing.vol' not found");
    write_grid_scene(dir, "g.vol", "<string name=\"filter_type\" value=\"cubic\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()), "scene.xml:6: gridvolume: invalid filter_type 'cubic'");
    write_grid_scene(dir, "g.vol", "<string name=\"wrap_mode\" value=\"border\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()), "scene.xml:6: gridvolume: invalid wrap_mode 'border'");
    write_grid_scene(dir, "g.vol", "<float name=\"max_value\" value=\"0.5\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()), "scene.xml:6: gridvolume: 'max_value' (0.500000) must be finite "
                                           "and at least the grid's maximum (0.600000)");
    write_grid_scene(dir, "g.vol", "<string name=\"grid\" value=\"density\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()),
                    "scene.xml:6: gridvolume: 'grid' names a grid of an OpenVDB (.vdb) file only");
    write_grid_scene(dir, "flat.vol", "<boolean name=\"use_grid_bbox\" value=\"true\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()),
                    "scene.xml:6: gridvolume: 'flat.vol': the bounding box stored in the file is degenerate");
    write_grid_scene(dir, "negative.vol");
    EXPECT_CONTAINS(load_error(dir.str()), "scene.xml:4: heterogeneous: the extinction must be non-negative "
                                           "(the sigma_t volume's minimum is -0.5");
    // A max_value above the data is accepted and becomes the bound.
    write_grid_scene(dir, "g.vol", "<float name=\"max_value\" value=\"3\"/>\n");
    const auto scene = load_scene(dir.str() + "/scene.xml");
    float bound = 0.f;
    scene->shapes[0]->interior->majorants(Vec3f(-1.f, 0.5f, 0.5f), Vec3f(1.f, 0.f, 0.f), 0.f, 3.f,
                                          [&](float, float, float m) {
                                              bound = std::max(bound, m);
                                              return true;
                                          });
    EXPECT_GT(bound, 0.f);
    EXPECT_LE(bound, 3.f);
}

namespace {

// index (i, j, k) -> 1 + i + 2 j + 3 k over [-2, 3] x [0, 4] x [1, 3]: linear, so trilinear lookups anywhere
// between voxel centres give the formula at the point's index-space coordinates.
float vdb_field(const openvdb::Vec3d& ijk) {
    return float(1.0 + ijk.x() + 2.0 * ijk.y() + 3.0 * ijk.z()) + 10.f;
}

openvdb::math::Transform::Ptr vdb_transform() {
    auto xf = openvdb::math::Transform::createLinearTransform(0.1);
    xf->postRotate(0.3, openvdb::math::Y_AXIS);
    xf->postTranslate(openvdb::Vec3d(0.5, -0.2, 0.3));
    return xf;
}

void write_vdb_fixture(const std::string& path) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.f);
    density->setName("density");
    density->setTransform(vdb_transform());
    auto acc = density->getAccessor();
    for (int i = -2; i <= 3; ++i)
        for (int j = 0; j <= 4; ++j)
            for (int k = 1; k <= 3; ++k)
                acc.setValue(openvdb::Coord(i, j, k), vdb_field(openvdb::Vec3d(i, j, k)));
    auto temperature = openvdb::FloatGrid::create(0.f);
    temperature->setName("temperature");
    temperature->setTransform(vdb_transform());
    temperature->fill(openvdb::CoordBBox(openvdb::Coord(0, 0, 0), openvdb::Coord(1, 1, 1)), 7.f, true);
    auto velocity = openvdb::Vec3SGrid::create();
    velocity->setName("velocity");
    velocity->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1.f, 0.f, 0.f));
    auto empty = openvdb::FloatGrid::create(0.f);
    empty->setName("empty");
    openvdb::io::File(path).write({velocity, density, temperature, empty});
}

} // namespace

TEST(MediaLoading, OpenVdbFixtureRoundTrip) {
    TempDir dir;
    write_vdb_fixture(dir.str() + "/fixture.vdb");
    write_grid_scene(dir, "fixture.vdb", "<transform name=\"to_world\"><scale value=\"2\"/></transform>\n");
    const auto medium = load_scene(dir.str() + "/scene.xml")->shapes[0]->interior;
    const auto xf = vdb_transform();
    PCG32 rng(4);
    for (int n = 0; n < 100; ++n) {
        // Index-space points between the first and last voxel centres, and voxel centres themselves.
        openvdb::Vec3d ijk(-2.0 + 5.0 * rng.next_float(), 4.0 * rng.next_float(),
                           1.0 + 2.0 * rng.next_float());
        if (n % 4 == 0) ijk = openvdb::Vec3d(std::round(ijk.x()), std::round(ijk.y()), std::round(ijk.z()));
        const openvdb::Vec3d w = xf->indexToWorld(ijk) * 2.0;
        const Color3f sigma = medium->sigma_t(Vec3f(float(w.x()), float(w.y()), float(w.z())));
        expect_color(sigma, Color3f(vdb_field(ijk)), 2e-4f * vdb_field(ijk), "vdb density");
    }
    // Outside the active voxels' box (grown by half a voxel): no extinction.
    const openvdb::Vec3d outside = xf->indexToWorld(openvdb::Vec3d(-3.0, 2.0, 2.0)) * 2.0;
    EXPECT_EQ(medium->sigma_t(Vec3f(float(outside.x()), float(outside.y()), float(outside.z()))),
              Color3f(0.f));

    // `grid` selects another float grid.
    write_grid_scene(dir, "fixture.vdb", "<string name=\"grid\" value=\"temperature\"/>\n");
    const auto temperature = load_scene(dir.str() + "/scene.xml")->shapes[0]->interior;
    const openvdb::Vec3d c = xf->indexToWorld(openvdb::Vec3d(0.5, 0.5, 0.5));
    EXPECT_EQ(temperature->sigma_t(Vec3f(float(c.x()), float(c.y()), float(c.z()))), Color3f(7.f));
}

TEST(MediaLoading, MalformedVdbFilesGiveOneClearError) {
    TempDir dir;
    write_vdb_fixture(dir.str() + "/fixture.vdb");
    std::ifstream in(dir.str() + "/fixture.vdb", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    write_bytes(dir.str() + "/garbage.vdb", "this is not an OpenVDB file");
    write_bytes(dir.str() + "/truncated.vdb", bytes.substr(0, bytes.size() / 2));
    write_bytes(dir.str() + "/header_only.vdb", bytes.substr(0, 64));
    openvdb::io::File(dir.str() + "/vectors.vdb").write({openvdb::Vec3SGrid::create()});

    const std::pair<std::string, std::string> cases[] = {
        {"garbage.vdb", "'garbage.vdb': not a readable OpenVDB file"},
        {"truncated.vdb", "'truncated.vdb': not a readable OpenVDB file"},
        {"header_only.vdb", "'header_only.vdb': not a readable OpenVDB file"},
        {"vectors.vdb", "'vectors.vdb': no float grid (the file holds '' (vec3s))"},
    };
    for (const auto& [file, expected] : cases) {
        write_grid_scene(dir, file);
        EXPECT_CONTAINS(load_error(dir.str()), "scene.xml:5: gridvolume: " + expected);
    }
    write_grid_scene(dir, "fixture.vdb", "<string name=\"grid\" value=\"smoke\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()),
                    "scene.xml:5: gridvolume: 'fixture.vdb': no grid named 'smoke' (the file "
                    "holds 'velocity' (vec3s), 'density' (float), 'temperature' (float), 'empty' (float))"); // file order
    write_grid_scene(dir, "fixture.vdb", "<string name=\"grid\" value=\"velocity\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()), "'fixture.vdb': grid 'velocity' holds vec3s values, not float");
    write_grid_scene(dir, "fixture.vdb", "<string name=\"grid\" value=\"empty\"/>\n");
    EXPECT_CONTAINS(load_error(dir.str()), "'fixture.vdb': grid 'empty' has no active voxels");
}
