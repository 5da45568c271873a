// PLY reader: ASCII and binary, uv property names, quads, bad input.
#include "pbrt/ply.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "expect_throw.h"

using namespace cmam::pbrt;
namespace fs = std::filesystem;

namespace {
// Every file the tests write, removed when the test program ends.
struct Written {
    std::vector<fs::path> paths;
    ~Written() {
        for (const fs::path& p : paths) fs::remove(p);
    }
} g_written;

std::string write_temp(const std::string& name, const std::string& bytes) {
    fs::path p =
        fs::temp_directory_path() / ("cmam_ply_" + std::to_string(::getpid()) + "_" + name);
    std::ofstream(p, std::ios::binary) << bytes;
    g_written.paths.push_back(p);
    return p.string();
}

// A file the reader rejects, and the message it gives after the file's name.
struct BadFile {
    const char* name;
    std::string text;
    std::string expected;
};

void expect_rejected(const std::vector<BadFile>& files) {
    for (const BadFile& f : files) {
        const std::string path = write_temp(f.name, f.text);
        EXPECT_THROW_MSG(read_ply(path), SceneError, "error: " + path + ": " + f.expected)
            << f.name;
    }
}
}  // namespace

TEST(Ply, AsciiQuadWithTextureUV) {
    std::string path =
        write_temp("a.ply",
                   "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\n"
                   "property float x\nproperty float y\nproperty float z\n"
                   "property float texture_u\nproperty float texture_v\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n");
    PlyMesh m = read_ply(path);
    EXPECT_EQ(m.positions.size(), 12u);
    EXPECT_TRUE(m.normals.empty());
    ASSERT_EQ(m.uvs.size(), 8u);
    EXPECT_EQ(m.uvs[5], 1.0f);
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 0, 2, 3}));
}

// Faces with other than three or four vertices are skipped and counted, as pbrt-v3 skips them
// with a warning (the scene builder gives it, located at the Shape's filename).
TEST(Ply, FacesOtherThanTrianglesAndQuadsAreSkippedAndCounted) {
    std::string path = write_temp(
        "pentagon.ply",
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
        "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 2 0\n5 0 1 2 3 4\n3 0 1 2\n2 0 1\n4 0 1 2 3\n");
    PlyMesh m = read_ply(path);
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 0, 1, 2, 0, 2, 3}));
    EXPECT_EQ(m.skipped_faces, 2u);
    EXPECT_EQ(m.first_skipped_size, 5u);
}

TEST(Ply, BinaryLittleEndianWithNormalsAndExtraElement) {
    std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float "
        "y\n"
        "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float "
        "u\n"
        "property float v\nelement face 1\nproperty list uchar int vertex_indices\n"
        "element material 1\nproperty list uchar float stuff\nend_header\n";
    std::string body;
    auto put = [&](const void* p, size_t n) { body.append(static_cast<const char*>(p), n); };
    for (int i = 0; i < 3; ++i) {
        float v[8] = {float(i), float(i * 2), 0, 0, 0, 1, 0.5f * i, 0.25f};
        put(v, sizeof v);
    }
    unsigned char three = 3;
    int idx[3] = {2, 1, 0};
    put(&three, 1);
    put(idx, sizeof idx);
    unsigned char two = 2;
    float stuff[2] = {1, 2};
    put(&two, 1);
    put(stuff, sizeof stuff);
    PlyMesh m = read_ply(write_temp("b.ply", header + body));
    EXPECT_EQ(m.positions[3 * 2 + 1], 4.0f);
    EXPECT_EQ(m.normals[2], 1.0f);
    EXPECT_EQ(m.uvs[2], 0.5f);
    EXPECT_EQ(m.indices, (std::vector<int>{2, 1, 0}));
}

TEST(Ply, ErrorsNameTheFile) {
    std::string path =
        write_temp("c.ply",
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                   "end_header\n0 0 0\n3 0 1 2\n");
    EXPECT_THROW_MSG(read_ply(path), SceneError,
                     "error: " + path + ": face index 1 out of range (1 vertices)");
    std::string trunc =
        write_temp("d.ply",
                   "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                   "property float z\nend_header\n0 0 0\n1 1\n");
    EXPECT_THROW_MSG(read_ply(trunc), SceneError,
                     "error: " + trunc + ": unexpected end of data or malformed number");
    const std::string headless = write_temp("e.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
    EXPECT_THROW_MSG(read_ply(headless), SceneError,
                     "error: " + headless + ": PLY header has no end_header");
}

// Numbers that do not fit what they are read into are errors naming the file and the value,
// never a conversion out of range (the asan preset traps those).
TEST(Ply, OutOfRangeCountsIndicesAndCoordinatesAreErrors) {
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
        "property double z\n";
    const std::string verts = "0 0 0\n1 0 0\n0 1 0\n";
    expect_rejected({
        {"f.ply",
         head + "element face 1\nproperty list double int vertex_indices\nend_header\n" + verts +
             "1e30 0 1 2\n",
         "invalid list length 1e+30 (at most 1048576)"},
        {"g.ply",
         head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n" + verts +
             "3 0 1 2.5\n",
         "vertex index 2.5 is not a whole number in int's range"},
        {"h.ply",
         head + "element face 1\nproperty list uchar uint vertex_indices\nend_header\n" + verts +
             "3 0 1 4294967295\n",
         "vertex index 4294967295 is not a whole number in int's range"},
        {"i.ply", head + "end_header\n0 0 0\n1e300 0 0\n0 1 0\n",
         "vertex 1 property \"x\" is 1e+300, not a finite single-precision number"},
        {"k.ply",
         head +
             "element face 1\nproperty list uchar float texcoord\n"
             "property list uchar int vertex_indices\nend_header\n" +
             verts + "2 0.5 0.25 3 0 1 7\n",
         "face index 7 out of range (3 vertices)"},
        {"l.ply",
         "ply\nformat ascii 1.0\nelement vertex 99999999999999999999\nproperty float x\n"
         "end_header\n",
         "malformed element line \"element vertex 99999999999999999999\""},
        {"j.ply",
         head + "element extra 1\nproperty list float uchar junk\nend_header\n" + verts +
             "-2 1 2\n",
         "invalid list length -2 (at most 2147483647)"},
    });
    // An element without properties has nothing to read, whatever its count says (the count
    // once drove an empty loop of 2^63 steps).
    const PlyMesh m = read_ply(
        write_temp("m.ply", head + "element face 9223372036854775807\nend_header\n" + verts));
    EXPECT_EQ(m.positions.size(), 9u);
    EXPECT_TRUE(m.indices.empty());
}

// Two vertex elements, only one with normals or texture coordinates: the mesh would have fewer
// of them than vertices (and the scene builder read past their end), so the file is an error.
TEST(Ply, AttributesGivenForSomeVertexElementsOnlyAreErrors) {
    const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
    const std::string plain = "element vertex 2\n" + xyz;
    const std::string end = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    expect_rejected({
        {"uv_first.ply",
         "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz +
             "property float u\nproperty float v\n" + plain + end +
             "0 0 0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
         "texture coordinates (u v) given for 1 of 3 vertices (give them for every vertex or "
         "none)"},
        {"n_second.ply",
         "ply\nformat ascii 1.0\n" + plain + "element vertex 1\n" + xyz +
             "property float nx\nproperty float ny\nproperty float nz\n" + end +
             "0 0 0\n1 0 0\n0 1 0 0 0 1\n3 0 1 2\n",
         "normals (nx ny nz) given for 1 of 3 vertices (give them for every vertex or none)"},
    });
}

// Each way a header or a body can be wrong has its own message, after the file's name.
TEST(Ply, EveryMalformationHasItsMessage) {
    const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
    const std::string faces = "element face 1\nproperty list uchar int vertex_indices\n";
    expect_rejected({
        {"magic.ply", "plx\n", "not a PLY file (missing \"ply\" magic)"},
        {"format.ply", "ply\nformat binary 1.0\n", "unknown PLY format \"binary\""},
        {"orphan.ply", "ply\nformat ascii 1.0\nproperty float x\n", "property before any element"},
        {"list.ply", "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar quad v\n",
         "unknown property type in \"property list uchar quad v\""},
        {"type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\n",
         "unknown property type \"real\""},
        {"line.ply", "ply\nformat ascii 1.0\nvertices 3\n",
         "unexpected PLY header line \"vertices 3\""},
        {"noformat.ply", "ply\nelement vertex 0\nend_header\n", "PLY header has no format line"},
        {"novertex.ply", "ply\nformat ascii 1.0\nend_header\n", "PLY file has no vertex element"},
        {"noxyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
         "vertex element lacks x, y, z properties"},
        {"short.ply",
         "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + xyz + "end_header\n\x01\x02",
         "unexpected end of data"},
    });
    const std::string dir = fs::temp_directory_path().string();
    EXPECT_THROW_MSG(read_ply(dir), SceneError,
                     "error: " + dir + ": cannot read PLY file: it is a directory");
    const std::string missing = dir + "/cmam_ply_missing_" + std::to_string(::getpid()) + ".ply";
    EXPECT_THROW_MSG(read_ply(missing), SceneError,
                     "error: " + missing + ": cannot open PLY file: No such file or directory");
}
