// One run reports every error it can find, each located, in order: the parser skips to the next
// directive after a bad one, and scene building goes on past a bad texture, material, shape or
// light.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/scene.h"

using namespace cmam;

namespace {
std::string error_of(const std::string& text) {
    try {
        render::build_scene(pbrt::parse_string(text, "t.pbrt"), {}, {});
    } catch (const pbrt::SceneError& e) {
        return e.what();
    }
    return "";
}
const std::string kHead = "Camera \"perspective\"\nWorldBegin\n";
}  // namespace

TEST(Errors, TheParserReportsEveryBadDirective) {
    const std::string text = kHead +
                             "Translate 1 2\n"
                             "Shape \"sphere\" \"float radius\" \"x\"\n"
                             "Frobnicate 3\n"
                             "Rotate 1 2 3 4\n"
                             "Scale 1\n"
                             "WorldEnd\n";
    const std::string e = error_of(text);
    // Translate stops at the Shape on line 4, which is then parsed (its radius "x" is an
    // error of its own); Scale stops at WorldEnd.
    const auto l4 = e.find("t.pbrt:4:1: error: Translate expects a number, got Shape"),
               l5 = e.find("t.pbrt:5:1: error: unknown directive Frobnicate"),
               l8 = e.find("t.pbrt:8:1: error: Scale expects a number, got WorldEnd");
    EXPECT_NE(l4, std::string::npos) << e;
    EXPECT_NE(l5, std::string::npos) << e;
    const auto radius = e.find("t.pbrt:4:31: error: float parameter \"radius\" expects a number");
    EXPECT_NE(l8, std::string::npos) << e;
    EXPECT_TRUE(l4 < radius && radius < l5 && l5 < l8) << e;
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 3) << e;  // four lines, nothing more
}

TEST(Errors, BuildingReportsEveryBadTextureShapeAndLight) {
    const std::string text = kHead +
                             "Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" "
                             "\"missing-a.png\"\n"                                      // line 3
                             "Shape \"plymesh\" \"string filename\" \"missing.ply\"\n"  // line 4
                             "Shape \"sphere\" \"float radius\" -1\n"                   // line 5
                             "LightSource \"laser\"\n"                                  // line 6
                             "WorldEnd\n";
    const std::string e = error_of(text);
    for (const char* want : {"t.pbrt:3:", "missing-a.png", "t.pbrt:4:", "missing.ply",
                             "t.pbrt:5:", "t.pbrt:6:", "unsupported light \"laser\""})
        EXPECT_NE(e.find(want), std::string::npos) << want << " in " << e;
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 3) << e;
}

// Image, mesh and light map files are read ahead, side by side, before the directives are
// built: each file's error still comes from its own directive, in the order the directives are
// built (textures, shapes, lights), and the files that read are used; one thread or all give
// the same.
TEST(Errors, FilesReadAheadReportTheirErrorsFromTheirDirectives) {
    const std::string scenes = CMAM_SCENES_DIR;
    const std::string text =
        kHead + "Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" \"missing-1.png\"\n" +
        "Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"" + scenes +
        "/textures/bricks.png\"\n" +                                   // line 4
        "Shape \"plymesh\" \"string filename\" \"missing-2.ply\"\n" +  // line 5
        "Texture \"c\" \"float\" \"imagemap\" \"string filename\" \"missing-3.png\"\n" +
        "Shape \"plymesh\" \"string filename\" \"" + scenes + "/meshes/torus.ply\"\n" +
        "LightSource \"infinite\" \"string mapname\" \"missing-4.exr\"\n" +  // line 8
        "LightSource \"infinite\" \"string mapname\" \"" + scenes + "/textures/grass.png\"\n" +
        "WorldEnd\n";
    auto build = [&](int threads) {
        render::BuildOptions o;
        o.threads = threads;
        try {
            render::build_scene(pbrt::parse_string(text, "t.pbrt"), o, {});
        } catch (const pbrt::SceneError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    const std::string e = build(0);
    const auto l3 = e.find("t.pbrt:3:"), l6 = e.find("t.pbrt:6:"), l5 = e.find("t.pbrt:5:"),
               l8 = e.find("t.pbrt:8:");
    ASSERT_NE(l3, std::string::npos) << e;
    ASSERT_NE(l6, std::string::npos) << e;
    ASSERT_NE(l5, std::string::npos) << e;
    ASSERT_NE(l8, std::string::npos) << e;
    EXPECT_TRUE(l3 < l6 && l6 < l5 && l5 < l8) << e;
    EXPECT_NE(e.find("missing-1.png"), std::string::npos) << e;
    EXPECT_NE(e.find("missing-2.ply"), std::string::npos) << e;
    EXPECT_NE(e.find("missing-3.png"), std::string::npos) << e;
    EXPECT_NE(e.find("missing-4.exr"), std::string::npos) << e;
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 3) << e;  // the files that exist read
    EXPECT_EQ(build(1), e);
    // Without the missing files, the scene builds with the image, the mesh and the map read
    // ahead.
    std::string good = text;
    for (const char* line :
         {"Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" \"missing-1.png\"\n",
          "Shape \"plymesh\" \"string filename\" \"missing-2.ply\"\n",
          "Texture \"c\" \"float\" \"imagemap\" \"string filename\" \"missing-3.png\"\n",
          "LightSource \"infinite\" \"string mapname\" \"missing-4.exr\"\n"})
        good.erase(good.find(line), std::string(line).size());
    const auto scene = render::build_scene(pbrt::parse_string(good, "t.pbrt"), {}, {});
    EXPECT_EQ(scene->images.size(), 1u);
    ASSERT_EQ(scene->primitives.size(), 1u);
    EXPECT_GT(scene->primitives[0]->indices.size(), 0u);
    ASSERT_EQ(scene->lights.size(), 1u);
    ASSERT_TRUE(scene->lights[0].env);
    EXPECT_EQ(scene->lights[0].env->image().image().width(), 512);
}

TEST(Errors, OneErrorIsReportedAlone) {
    EXPECT_EQ(error_of(kHead + "Scale 1\nWorldEnd\n").find('\n'), std::string::npos);
}
