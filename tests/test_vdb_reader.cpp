// penumbra's .vdb reader (src/scene/volumes/vdb_layout.h) against OpenVDB's own: files written by OpenVDB
// with every compression (none, zlib, Blosc, active-mask), half floats, each inactive-value encoding of a
// node, tiles at every level, negative coordinates, every linear transform map, instanced grids and
// stream-written files (no grid offsets) must densify to the values OpenVDB reads back, voxel for voxel;
// corrupt files (every byte of a small file changed, every truncation) end in a VolumeFileError.
#include "scene/volumes/volume_grid.h"

#include "xml_test_util.h"

#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <cstring>
#include <fstream>
#include <iterator>

using namespace penumbra;
using namespace penumbra::test;

namespace {

openvdb::FloatGrid::Ptr rich_grid(const std::string& name) {
    openvdb::initialize();
    const float background = 0.25f;
    auto grid = openvdb::FloatGrid::create(background);
    grid->setName(name);
    auto acc = grid->getAccessor();
    uint32_t state = 12345;
    auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 8; };
    // Active voxels around the origin, across eight root children (negative coordinates included).
    for (int n = 0; n < 3000; ++n) {
        const openvdb::Coord ijk(int(next() % 131) - 70, int(next() % 31) - 10, int(next() % 46) - 5);
        acc.setValue(ijk, float(next() % 1000) / 100.f);
    }
    // Leaves whose inactive voxels hold: -background; one other value; that value and the background; many.
    const openvdb::Coord leaves[] = {{-64, 0, 0}, {-56, 0, 0}, {-48, 0, 0}, {-40, 0, 0}};
    for (int l = 0; l < 4; ++l) {
        acc.setValue(leaves[l], 5.f);
        for (int v = 1; v < 512; ++v) {
            const openvdb::Coord ijk = leaves[l] + openvdb::Coord(v >> 6, (v >> 3) & 7, v & 7);
            const float inactive[] = {-background, 3.f, v % 3 ? 3.f : background, float(v)};
            acc.setValueOff(ijk, inactive[l]);
        }
    }
    // Tiles: an active 8^3 and an inactive non-background 8^3 in lower nodes, an active 128^3 in an upper
    // node, and an inactive root tile away from the active voxels.
    grid->tree().addTile(1, openvdb::Coord(24, 24, 24), 7.f, true);
    grid->tree().addTile(1, openvdb::Coord(-24, 8, 16), -2.f, false);
    grid->tree().addTile(2, openvdb::Coord(-128, -128, -128), 1.5f, true);
    grid->tree().addTile(3, openvdb::Coord(8192, 0, 0), 9.f, false);
    return grid;
}

std::string read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

// read_vdb_file's result equals OpenVDB's reading of the same file: box, values, placement.
void expect_same_as_openvdb(const std::string& path, const std::string& name) {
    SCOPED_TRACE(path + " grid " + name);
    std::ifstream in(path, std::ios::binary);
    openvdb::FloatGrid::Ptr grid;
    const openvdb::GridPtrVecPtr grids = openvdb::io::Stream(in).getGrids();
    for (const auto& g : *grids)
        if (!grid && g->getName() == name) grid = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    ASSERT_TRUE(grid) << "OpenVDB finds no float grid '" << name << "'";
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    const VolumeGridData ours = read_vdb_file(path, name);
    ASSERT_EQ(ours.res, Vec3i(box.dim().x(), box.dim().y(), box.dim().z()));
    const auto acc = grid->getConstAccessor();
    size_t i = 0, mismatches = 0;
    for (int z = box.min().z(); z <= box.max().z(); ++z)
        for (int y = box.min().y(); y <= box.max().y(); ++y)
            for (int x = box.min().x(); x <= box.max().x(); ++x, ++i)
                if (ours.values[i] != acc.getValue(openvdb::Coord(x, y, z)) && ++mismatches < 5)
                    ADD_FAILURE() << "voxel " << x << " " << y << " " << z << ": " << ours.values[i] << " vs "
                                  << acc.getValue(openvdb::Coord(x, y, z));
    EXPECT_EQ(mismatches, 0u);
    // The unit cube's corners land where OpenVDB puts the box's outer voxel faces.
    for (int corner = 0; corner < 8; ++corner) {
        const openvdb::Vec3d index(corner & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5,
                                   corner & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5,
                                   corner & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5);
        const openvdb::Vec3d world = grid->transform().indexToWorld(index);
        const Vec3f p = ours.unit_to_file.apply_point(
            Vec3f(float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1)));
        for (int a = 0; a < 3; ++a)
            EXPECT_NEAR(p[a], world[a], 1e-4 * (1.0 + std::abs(world[a])));
    }
}

} // namespace

TEST(VdbReader, MatchesOpenVdbForEveryCompressionAndHalfFloats) {
    TempDir dir;
    const std::pair<const char*, uint32_t> compressions[] = {
        {"none", openvdb::io::COMPRESS_NONE},
        {"zip", openvdb::io::COMPRESS_ZIP},
        {"blosc", openvdb::io::COMPRESS_BLOSC},
        {"mask", openvdb::io::COMPRESS_ACTIVE_MASK},
        {"zip_mask", openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK},
        {"blosc_mask", openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK}};
    for (const auto& [label, flags] : compressions)
        for (bool half : {false, true}) {
            auto grid = rich_grid("density");
            grid->setSaveFloatAsHalf(half);
            const std::string path = dir.str() + "/" + label + (half ? "_half" : "") + ".vdb";
            openvdb::io::File file(path);
            file.setCompression(flags);
            file.write({grid});
            expect_same_as_openvdb(path, "density");
        }
}

TEST(VdbReader, MatchesOpenVdbForEveryLinearTransformMap) {
    TempDir dir;
    using namespace openvdb::math;
    // OpenVDB's Transform simplifies a linear map to the simplest type that holds it, the type it writes.
    const std::pair<const char*, MapBase::Ptr> maps[] = {
        {"UniformScaleMap", MapBase::Ptr(new UniformScaleMap(0.1))},
        {"UniformScaleTranslateMap",
         MapBase::Ptr(new UniformScaleTranslateMap(0.1, openvdb::Vec3d(1, -2, 3)))},
        {"ScaleMap", MapBase::Ptr(new ScaleMap(openvdb::Vec3d(0.1, 0.2, 0.3)))},
        {"ScaleTranslateMap",
         MapBase::Ptr(new ScaleTranslateMap(openvdb::Vec3d(0.1, 0.2, 0.3), openvdb::Vec3d(1, 2, 3)))},
        {"AffineMap", MapBase::Ptr(new AffineMap(openvdb::Mat4d(0.1, 0.02, 0.0, 0.0, 0.0, 0.2, 0.01, 0.0,
                                                                0.03, 0.0, 0.3, 0.0, 1.0, 2.0, 3.0, 1.0)))}};
    for (const auto& [type, map] : maps) {
        auto grid = rich_grid("density");
        grid->setTransform(std::make_shared<openvdb::math::Transform>(map));
        const std::string path = dir.str() + "/" + type + ".vdb";
        openvdb::io::File(path).write({grid});
        const uint32_t length = uint32_t(std::strlen(type));
        const std::string stored = std::string(reinterpret_cast<const char*>(&length), 4) + type;
        ASSERT_NE(read_bytes(path).find(stored), std::string::npos) << type << " not written";
        expect_same_as_openvdb(path, "density");
    }
    // The two maps that Transform never writes (it simplifies them), patched into stream-written files (no
    // offsets to move): a TranslationMap for a unit-scale UniformScaleTranslateMap (a name and one vector
    // for the name and six vectors), a UnitaryMap for the AffineMap of a rotation (the same matrix).
    auto patched = [&](const std::string& file, MapBase::Ptr map, const std::string& from,
                       const std::string& to, size_t keep_bytes, size_t drop_bytes) {
        auto grid = rich_grid("density");
        grid->setTransform(std::make_shared<openvdb::math::Transform>(map));
        const std::string path = dir.str() + "/" + file;
        {
            std::ofstream out(path, std::ios::binary);
            openvdb::io::Stream(out).write({grid});
        }
        std::string bytes = read_bytes(path);
        const size_t at = bytes.find(from);
        ASSERT_NE(at, std::string::npos) << from << " not written";
        const uint32_t length = uint32_t(to.size());
        const std::string kept = bytes.substr(at + from.size(), keep_bytes);
        bytes = bytes.substr(0, at - 4) + std::string(reinterpret_cast<const char*>(&length), 4) + to + kept +
                bytes.substr(at + from.size() + keep_bytes + drop_bytes);
        write_bytes(path, bytes);
        expect_same_as_openvdb(path, "density");
    };
    patched("translation.vdb", MapBase::Ptr(new UniformScaleTranslateMap(1.0, openvdb::Vec3d(4, 5, -6))),
            "UniformScaleTranslateMap", "TranslationMap", 24, 5 * 24);
    patched("unitary.vdb", MapBase::Ptr(new UnitaryMap(openvdb::Vec3d(1, 2, 3), 0.7)), "AffineMap",
            "UnitaryMap", 128, 0);
    auto frustum = rich_grid("density");
    frustum->setTransform(openvdb::math::Transform::createFrustumTransform(
        openvdb::BBoxd(openvdb::Vec3d(0), openvdb::Vec3d(10)), 0.5, 2.0, 0.1));
    openvdb::io::File(dir.str() + "/frustum.vdb").write({frustum});
    try {
        read_vdb_file(dir.str() + "/frustum.vdb", "");
        FAIL() << "a frustum transform was accepted";
    } catch (const VolumeFileError& e) {
        EXPECT_STREQ(e.what(), "grid 'density' has a non-linear (frustum) transform, which is not supported");
    }
}

TEST(VdbReader, InstancedGridsAndStreamsWithoutGridOffsets) {
    TempDir dir;
    // A grid sharing another's tree is written as an instance (its metadata and transform only).
    auto density = rich_grid("density");
    auto copy = density->copyGrid();
    copy->setName("moved");
    copy->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
    const std::string instanced = dir.str() + "/instanced.vdb";
    openvdb::io::File(instanced).write({density, copy});
    expect_same_as_openvdb(instanced, "moved");
    expect_same_as_openvdb(instanced, "density");

    // io::Stream writes no grid offsets: float grids are read in sequence.
    auto velocity = openvdb::Vec3SGrid::create();
    velocity->setName("velocity");
    velocity->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1.f, 0.f, 0.f));
    auto temperature = rich_grid("temperature");
    {
        std::ofstream out(dir.str() + "/stream.vdb", std::ios::binary);
        openvdb::io::Stream(out).write({temperature, density, velocity});
    }
    const VolumeGridData streamed = read_vdb_file(dir.str() + "/stream.vdb", "");
    const VolumeGridData from_file = read_vdb_file(instanced, "density");
    EXPECT_EQ(streamed.res, from_file.res);
    EXPECT_EQ(streamed.values, from_file.values); // "density" preferred over the first float grid
    {
        std::ofstream out(dir.str() + "/stream_vector_first.vdb", std::ios::binary);
        openvdb::io::Stream(out).write({velocity, density});
    }
    try {
        read_vdb_file(dir.str() + "/stream_vector_first.vdb", "");
        FAIL() << "a grid after an unskippable one was read";
    } catch (const VolumeFileError& e) {
        EXPECT_STREQ(e.what(),
                     "no float grid (the file holds 'velocity' (vec3s); grids after 'velocity' cannot "
                     "be reached in a file without grid offsets)");
    }
}

// A version this reader does not know, and the inputs on which OpenVDB 10's reader misbehaves
// (docs/fuzzing.md, "OpenVDB"): one clear error each, at once.
TEST(VdbReader, RefusesOtherVersionsAndOpenVdbsKnownBadInputs) {
    TempDir dir;
    const std::string path = dir.str() + "/density.vdb";
    openvdb::io::File(path).write({rich_grid("density")});
    std::string bytes = read_bytes(path);
    bytes[8] = char(221);
    write_bytes(path, bytes);
    try {
        read_vdb_file(path, "");
        FAIL() << "version 221 was read";
    } catch (const VolumeFileError& e) {
        EXPECT_STREQ(e.what(),
                     "file format version 221 (penumbra reads 222 to 224: files of OpenVDB 3.0 and later)");
    }
    // A grid is read within its own bytes: an end offset short of them is an error, not read past.
    openvdb::io::File(path).write({rich_grid("density")});
    bytes = read_bytes(path);
    const size_t type_at = bytes.find("Tree_float_5_4_3");
    ASSERT_NE(type_at, std::string::npos);
    const size_t offsets_at = type_at + 16 + 4; // after the type and the empty instance parent name
    int64_t end = 0;
    std::memcpy(&end, bytes.data() + offsets_at, 8); // the grid's position
    end += 100;
    bytes.replace(offsets_at + 16, 8, reinterpret_cast<const char*>(&end), 8);
    write_bytes(path, bytes);
    try {
        read_vdb_file(path, "");
        FAIL() << "a grid was read past its end offset";
    } catch (const VolumeFileError& e) {
        EXPECT_STREQ(e.what(), "not a readable OpenVDB file (a string's length reaches past its end)");
    }

    // Names from the file appear in messages printable and at most 64 characters long.
    openvdb::io::File(path).write({rich_grid(std::string(70, 'n') + "\x07")});
    try {
        read_vdb_file(path, "missing");
        FAIL() << "a missing grid was read";
    } catch (const VolumeFileError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "no grid named 'missing' (the file holds '" + std::string(64, 'n') + "...' (float))");
    }

    const std::string regressions = std::string(PENUMBRA_SOURCE_DIR) + "/tests/fuzz/regressions/vdb/";
    const std::pair<const char*, const char*> known[] = {
        {"openvdb_unzip_uncompressed_chunk_overflows.vdb",
         "not a readable OpenVDB file (a stored chunk of 5353172790017673803 bytes where 0 bytes are "
         "expected)"},
        {"openvdb_metadata_strings_of_1gb.vdb",
         "not a readable OpenVDB file (a grid's end offset outside the file)"}};
    for (const auto& [file, expected] : known) {
        try {
            read_vdb_file(regressions + file, "");
            ADD_FAILURE() << file << " was read";
        } catch (const VolumeFileError& e) {
            EXPECT_STREQ(e.what(), expected) << file;
        }
    }
}

// What a file can make the reader hold follows the dense grid's voxel cap (read_vdb_file's max_voxels).
TEST(VdbReader, CapsLeavesAndTheDenseGridByTheVoxelLimit) {
    TempDir dir;
    const std::string path = dir.str() + "/density.vdb";
    openvdb::io::File(path).write({rich_grid("density")});
    auto error = [&](uint64_t max_voxels) {
        try {
            read_vdb_file(path, "", max_voxels);
        } catch (const VolumeFileError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(error(2048), "too many leaf nodes (more than 4)");
    EXPECT_EQ(error(uint64_t(1) << 22),
              "grid 'density' spans 189 x 160 x 169 voxels, too many to store densely");
    EXPECT_EQ(read_vdb_file(path, "", 189 * 160 * 169).values.size(), size_t(189 * 160 * 169));
}

// Bytes of small files (Blosc with active-mask compression, zlib with half floats) set to two other values
// (all of the first 1024: header, metadata, descriptor, transform, root; every 61st after), and truncations:
// each load gives a grid or a VolumeFileError (under the sanitizer preset, no memory error either).
TEST(VdbReader, EveryCorruptionOfASmallFileEndsInDataOrOneError) {
    TempDir dir;
    openvdb::initialize();
    const std::pair<const char*, uint32_t> variants[] = {
        {"blosc", openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK},
        {"zip", openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK}};
    size_t loads = 0, errors = 0;
    for (const auto& [label, flags] : variants) {
        auto grid = openvdb::FloatGrid::create(0.f);
        grid->setName("density");
        grid->setSaveFloatAsHalf(flags & openvdb::io::COMPRESS_ZIP);
        grid->tree().setValue(openvdb::Coord(1, 2, 3), 4.f);
        grid->tree().setValue(openvdb::Coord(9, 2, 3), 5.f);
        const std::string source = dir.str() + "/" + label + ".vdb", mutated = dir.str() + "/mutated.vdb";
        openvdb::io::File file(source);
        file.setCompression(flags);
        file.write({grid});
        const std::string bytes = read_bytes(source);
        auto load = [&](const std::string& content) {
            write_bytes(mutated, content);
            ++loads;
            try {
                read_vdb_file(mutated, "");
            } catch (const VolumeFileError&) {
                ++errors;
            }
        };
        for (size_t i = 0; i < bytes.size(); i += i < 1024 ? 1 : 61)
            for (int delta : {0x80, 0xff}) {
                std::string m = bytes;
                m[i] = char(uint8_t(m[i]) + delta);
                load(m);
            }
        for (size_t n = 0; n < bytes.size(); n += 97)
            load(bytes.substr(0, n));
    }
    EXPECT_GT(errors, loads / 10); // the mutations reach the checks (most bytes are values or names)
}
