// The memory a render will take is known before it starts, and a render over the limit is
// refused with its sizes.
#include "render/memory.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "expect_throw.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "temp_dir.h"

using namespace cmam::render;

namespace {

std::unique_ptr<Scene> textured_plane(const std::string& filter, int res) {
    const std::string text =
        R"(LookAt 0 1 3  0 0 0  0 1 0
Camera "perspective" "float fov" 45
Film "image" "integer xresolution" )" +
        std::to_string(res) + R"( "integer yresolution" )" + std::to_string(res) + R"(
WorldBegin
LightSource "distant" "point from" [0 1 1] "point to" [0 0 0]
Texture "t" "spectrum" "imagemap" "string filename" ")" +
        std::string(CMAM_SCENES_DIR) + R"(/textures/bricks.png" "string filter" ")" + filter + R"("
Material "matte" "texture Kd" "t"
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-1 0 -1 1 0 -1 1 0 1 -1 0 1]
WorldEnd
)";
    return build_scene(cmam::pbrt::parse_string(text, "t.pbrt"), {}, {});
}

}  // namespace

TEST(Memory, NeedCountsTheFilmAndTheTablesEachFilterBuilds) {
    const auto point = textured_plane("bilinear", 100);
    EXPECT_EQ(render_memory_need(*point).film, 100u * 100 * 3 * 4);
    EXPECT_EQ(render_memory_need(*point).textures, 0u);  // bilinear reads level 0 only
    const auto tri = textured_plane("trilinear", 100), area = textured_plane("area", 100),
               sat = textured_plane("sat", 100);
    const auto& im = tri->images.begin()->second->image();
    const double w = im.width(), h = im.height(), c = im.channels();
    EXPECT_NEAR(double(render_memory_need(*tri).textures), w * h * c * 4 / 3, 1);
    EXPECT_NEAR(double(render_memory_need(*area).textures),
                w * h * c * 4 / 3 + (w + 1) * h * c * 4 * 4 / 3, 2);
    EXPECT_NEAR(double(render_memory_need(*sat).textures),
                w * h * c * 4 / 3 + (w + 1) * (h + 1) * c * 8 * 4 / 3, 2);
    // Once built, the pyramid is no longer needed: it is counted in what the process has.
    tri->images.begin()->second->pyramid();
    EXPECT_EQ(render_memory_need(*tri).textures, 0u);
}

TEST(Memory, ARenderOverTheLimitIsRefusedWithItsSizes) {
    const auto s = textured_plane("area", 4096);
    const MemoryNeed need = render_memory_need(*s);
    EXPECT_EQ(need.film, 4096u * 4096 * 3 * 4);
    try {
        check_render_memory(*s, std::size_t(64) << 20);
        FAIL() << "not refused";
    } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("film 192 MiB"), std::string::npos) << m;
        EXPECT_NE(m.find("over the limit of 64 MiB set by --max-memory"), std::string::npos) << m;
        EXPECT_NE(m.find("--resolution"), std::string::npos) << m;  // the film is the larger
    }
    EXPECT_NO_THROW(check_render_memory(*s, resident_memory() + need.total() + (1 << 20)));
}

TEST(Memory, AMeshFileTooBigIsRefusedFromItsHeaderWithItsLocation) {
    // A header announcing a billion vertices and faces: refused at the shape's filename before
    // any vertex is read (the file holds none), naming the counts and the sizes.
    const cmam::test::TempDir d("cmam_memory_ply");
    const std::string ply = (d.path / "huge.ply").string();
    std::ofstream(ply) << "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
                          "property float x\nproperty float y\nproperty float z\n"
                          "element face 1000000000\nproperty list uchar int vertex_indices\n"
                          "end_header\n";
    const std::string text =
        "LookAt 0 0 3  0 0 0  0 1 0\nCamera \"perspective\"\n"
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"" +
        ply + "\"\nWorldEnd\n";
    BuildOptions bo;
    bo.max_memory = std::size_t(8) << 30;
    try {
        build_scene(cmam::pbrt::parse_string(text, "m.pbrt"), bo, {});
        FAIL() << "not refused";
    } catch (const cmam::pbrt::SceneError& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("m.pbrt:4:17: error: \"huge.ply\": 1000000000 vertices and "
                          "1000000000 faces need about 147.1 GiB, over the ",
                          0),
                  0u)
            << m;
        EXPECT_NE(m.find(" left of the limit of 8.0 GiB set by --max-memory"), std::string::npos)
            << m;
    }
    // The same header under a limit it fits: read, and then refused for its missing data.
    bo.max_memory = std::size_t(1) << 50;
    EXPECT_THROW_CONTAINS(build_scene(cmam::pbrt::parse_string(text, "m.pbrt"), bo, {}),
                          cmam::pbrt::SceneError, "huge.ply");
}

TEST(Memory, SizesParseInPowersOf1024) {
    EXPECT_EQ(parse_bytes("8G"), std::size_t(8) << 30);
    EXPECT_EQ(parse_bytes("512M"), std::size_t(512) << 20);
    EXPECT_EQ(parse_bytes("8 GiB"), std::size_t(8) << 30);
    EXPECT_EQ(parse_bytes("1.5gb"), std::size_t(3) << 29);
    EXPECT_EQ(parse_bytes("4096"), 4096u);
    for (const char* bad : {"", "G", "8x", "-1G", "0", "nanG", "1e30G"})
        EXPECT_FALSE(parse_bytes(bad).has_value()) << bad;
    EXPECT_EQ(format_bytes(std::size_t(3) << 29), "1.5 GiB");
    EXPECT_EQ(format_bytes(std::size_t(5) << 20), "5 MiB");
}
