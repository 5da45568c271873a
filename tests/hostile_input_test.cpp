// Hostile and careless scenes: each is a located error or a located warning naming what is
// wrong and the value, never a crash, an out-of-range read or conversion, or unbounded work.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "pbrt/input_file.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/image_io.h"
#include "render/integrator.h"
#include "render/scene.h"

using namespace cmam;
namespace fs = std::filesystem;

namespace {
const char* kCamera = "Camera \"perspective\"\n";

// Parses `text` as the file t.pbrt and builds it: the error message, or "no error".
std::string error_of(const std::string& text) {
    try {
        render::build_scene(pbrt::parse_string(text, "t.pbrt"), {}, {});
    } catch (const pbrt::SceneError& e) {
        return e.what();
    }
    return "no error";
}
}  // namespace

// A sampled spectrum is interpolated between its samples: a NaN wavelength once sent the
// lookup before the start of the list.
TEST(HostileInput, SpectrumSamplesMustBeFiniteWithIncreasingWavelengths) {
    auto matte = [](const std::string& kd) {
        return std::string(kCamera) + "WorldBegin\nMaterial \"matte\" \"spectrum Kd\" [" + kd +
               "]\nShape \"sphere\"\nWorldEnd\n";
    };
    EXPECT_EQ(error_of(matte("nan 1 500 1")),
              "t.pbrt:3:18: error: spectrum \"Kd\" wavelengths must be finite numbers, got nan");
    EXPECT_EQ(error_of(matte("400 1 inf 1")),
              "t.pbrt:3:18: error: spectrum \"Kd\" wavelengths must be finite numbers, got inf");
    EXPECT_EQ(error_of(matte("400 1 500 nan")),
              "t.pbrt:3:18: error: spectrum \"Kd\" values must be finite numbers, got nan at "
              "500 nm");
    EXPECT_EQ(error_of(matte("600 1 500 1")),
              "t.pbrt:3:18: error: spectrum \"Kd\" wavelengths must increase, got 500 after 600");
    EXPECT_EQ(error_of(matte("400 1 400 0.5")),
              "t.pbrt:3:18: error: spectrum \"Kd\" wavelengths must increase, got 400 after 400");
    EXPECT_EQ(error_of(matte("400 0.5 500 0.5 700 0.5")), "no error");
}

// Specular recursion is on the stack: inside a closed mirror sphere a huge maxdepth once
// overflowed it. The depth is capped with a located warning and the render completes.
TEST(HostileInput, MaxDepthAboveTheLimitIsCappedWithALocatedWarning) {
    const std::string text =
        "Integrator \"whitted\" \"integer maxdepth\" 1000000000\n"
        "Film \"image\" \"integer xresolution\" 4 \"integer yresolution\" 4\n"
        "Camera \"perspective\"\nWorldBegin\nLightSource \"point\"\n"
        "Material \"mirror\" \"rgb Kr\" [1 1 1]\nShape \"sphere\" \"float radius\" 10\nWorldEnd\n";
    std::vector<std::string> warnings;
    auto sink = [&](const std::string& w) { warnings.push_back(w); };
    auto scene = render::build_scene(pbrt::parse_string(text, "t.pbrt"), {}, sink);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0],
              "t.pbrt:1:22: warning: maxdepth 1000000000 is above cmam's limit of 100, which is "
              "used instead");
    EXPECT_EQ(scene->max_depth, render::kMaxDepthLimit);
    render::RenderStats stats;
    render::BuildOptions one_spp;
    one_spp.spp_override = 1;
    scene = render::build_scene(pbrt::parse_string(text, "t.pbrt"), one_spp, {});
    render::render(*scene, {}, &stats);
    EXPECT_EQ(stats.secondary_rays, 16u * (render::kMaxDepthLimit - 1));
}

// Integers are read as numbers and must convert to int exactly; a crop window must be finite
// before it is scaled to pixels. Each was a float-to-int conversion out of range.
TEST(HostileInput, NumbersThatDoNotFitAnIntAreLocatedErrors) {
    const std::string not_int = "must be a whole number in int's range, got ";
    const std::pair<std::string, std::string> film_cases[] = {
        {"\"integer xresolution\" 1e10",
         "integer parameter \"xresolution\" " + not_int + "10000000000"},
        {"\"integer yresolution\" [-inf]", "integer parameter \"yresolution\" " + not_int + "-inf"},
        {"\"integer xresolution\" 2.5", "integer parameter \"xresolution\" " + not_int + "2.5"},
        {"\"float cropwindow\" [0 1 nan 1]", "cropwindow values must be finite numbers, got nan"},
        {"\"float cropwindow\" [0 inf 0 1]", "cropwindow values must be finite numbers, got inf"},
        {"\"integer xresolution\" 2147483647 \"float cropwindow\" [0 0.5 0 1]",
         "xresolution must be between 1 and 65536, got 2147483647"},
    };
    for (const auto& [params, why] : film_cases)
        EXPECT_EQ(error_of("Film \"image\" " + params + "\n" + kCamera + "WorldBegin\nWorldEnd\n"),
                  "t.pbrt:1:14: error: " + why)
            << params;
    EXPECT_EQ(error_of(std::string(kCamera) +
                       "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                       "\"integer indices\" [0 1 1e10]\nWorldEnd\n"),
              "t.pbrt:3:53: error: integer parameter \"indices\" " + not_int + "10000000000");
}

// Sizes are products computed in 64 bits and bounded before anything is allocated: 65536 x
// 65536 samples per pixel once wrapped to 0 in an int, and 2^31 - 1 pixelsamples asked for a
// vector longer than any.
TEST(HostileInput, FilmAndSampleCountsAboveTheLimitsAreLocatedErrors) {
    const std::pair<std::string, std::string> cases[] = {
        {"Sampler \"stratified\" \"integer xsamples\" 65536 \"integer ysamples\" 65536",
         "t.pbrt:1:22: error: xsamples x ysamples = 65536x65536 = 4294967296 samples per pixel "
         "is above cmam's limit of 1048576"},
        {"Sampler \"halton\" \"integer pixelsamples\" 2147483647",
         "t.pbrt:1:18: error: pixelsamples 2147483647 is above cmam's limit of 1048576 samples "
         "per pixel"},
        {"Film \"image\" \"integer xresolution\" 30000 \"integer yresolution\" 30000",
         "t.pbrt:1:14: error: a film of 30000x30000 = 900000000 pixels is above cmam's limit of "
         "268435456"},
        {"Film \"image\" \"integer yresolution\" 65537",
         "t.pbrt:1:14: error: yresolution must be between 1 and 65536, got 65537"},
        {"Sampler \"stratified\" \"integer xsamples\" 1024 \"integer ysamples\" 1024",
         "t.pbrt:1:1: error: 1048576 samples per pixel along 1280 pixels (the film's larger side) "
         "= 1342177280 samples, above cmam's limit of 67108864"},
        {"Film \"image\" \"integer xresolution\" 16384 \"integer yresolution\" 16384\n"
         "Sampler \"stratified\" \"integer xsamples\" 64 \"integer ysamples\" 64",
         "no error"},
    };
    for (const auto& [options, expected] : cases)
        EXPECT_EQ(error_of(options + "\n" + kCamera + "WorldBegin\nWorldEnd\n"), expected)
            << options;
    render::BuildOptions spp;
    spp.spp_override = 1 << 21;
    try {
        render::build_scene(pbrt::parse_string(std::string(kCamera) + "WorldBegin\nWorldEnd\n"),
                            spp, {});
        ADD_FAILURE() << "no error";
    } catch (const pbrt::SceneError& e) {
        EXPECT_STREQ(e.what(), "error: --spp 2097152 is above cmam's limit of 1048576");
    }
}

namespace {
// A directory of this process's own, removed with everything in it at the end of the test.
struct TempDir {
    fs::path path = fs::temp_directory_path() / ("cmam_hostile_" + std::to_string(::getpid()));
    TempDir() { fs::create_directories(path); }
    ~TempDir() { fs::remove_all(path); }
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(path / name, std::ios::binary) << text;
        return (path / name).string();
    }
};

std::string file_error_of(const std::string& path) {
    try {
        render::build_scene(pbrt::parse_file(path), {}, {});
    } catch (const pbrt::SceneError& e) {
        return e.what();
    }
    return "no error";
}
}  // namespace

// A directory once read as an empty scene, and Include "/dev/zero" grew without end: scene files
// and PLY files are read only when they are regular files, and scene files within 1 GiB.
TEST(HostileInput, OnlyRegularFilesWithinTheSizeLimitAreRead) {
    TempDir dir;
    const std::string d = dir.path.string();
    EXPECT_EQ(file_error_of(d), d + ": error: cannot read scene file: it is a directory");
    EXPECT_EQ(file_error_of("/dev/zero"),
              "/dev/zero: error: cannot read scene file: it is not a regular file");
    EXPECT_EQ(file_error_of(d + "/none.pbrt"),
              d + "/none.pbrt: error: cannot open scene file: No such file or directory");
    // Larger than the limit: sparse, so nothing is written to the disk.
    const std::string big = dir.write("big.pbrt", "");
    fs::resize_file(big, pbrt::kMaxSceneFileBytes + 1);
    const std::pair<std::string, std::string> includes[] = {
        {d, "cannot read scene file \"" + d + "\": it is a directory"},
        {"/dev/zero", "cannot read scene file \"/dev/zero\": it is not a regular file"},
        {big, "scene file \"" + big + "\" is 1073741825 bytes, above cmam's limit of 1073741824"},
    };
    for (const auto& [name, why] : includes) {
        const std::string scene =
            dir.write("inc.pbrt", std::string(kCamera) + "Include \"" + name + "\"\n");
        EXPECT_EQ(file_error_of(scene), scene + ":2:1: error: " + why) << name;
    }
    for (const std::string& ply : {d, std::string("/dev/zero")}) {
        const std::string scene =
            dir.write("ply.pbrt", std::string(kCamera) +
                                      "WorldBegin\nShape \"plymesh\" \"string filename\" \"" + ply +
                                      "\"\nWorldEnd\n");
        EXPECT_EQ(file_error_of(scene),
                  scene + ":3:17: error: " + ply + ": cannot read PLY file: " +
                      (ply == d ? "it is a directory" : "it is not a regular file"));
    }
}

// ObjectEnd closes the ObjectBegin it belongs to, whatever the lines: it was matched by line
// number, so on the ObjectBegin's line it closed an AttributeBegin opened inside the object.
TEST(HostileInput, ObjectEndMatchesItsObjectBeginNotALine) {
    const std::pair<std::string, std::string> cases[] = {
        {"ObjectBegin \"a\" AttributeBegin ObjectEnd AttributeEnd",
         "t.pbrt:3:32: error: ObjectEnd does not match AttributeBegin at t.pbrt:3:17 inside "
         "object \"a\""},
        {"ObjectBegin \"a\"\nTransformBegin\nObjectEnd\nTransformEnd",
         "t.pbrt:5:1: error: ObjectEnd does not match TransformBegin at t.pbrt:4:1 inside object "
         "\"a\""},
        {"ObjectBegin \"a\" AttributeEnd ObjectEnd",
         "t.pbrt:3:17: error: AttributeEnd does not match ObjectBegin at t.pbrt:3:1"},
        {"ObjectBegin \"a\" Shape \"sphere\"",
         "t.pbrt:3:1: error: ObjectBegin is not closed before WorldEnd"},
        {"ObjectBegin \"a\" AttributeBegin Shape \"sphere\" AttributeEnd ObjectEnd "
         "ObjectInstance \"a\"",
         "no error"},
    };
    for (const auto& [world, expected] : cases)
        EXPECT_EQ(error_of(std::string(kCamera) + "WorldBegin\n" + world + "\nWorldEnd\n"),
                  expected)
            << world;
}

// Rays that are not finite, or start beyond Embree's range, once reached Embree and aborted in
// its assertions: the camera (its transform, frame and screen window) is checked where the scene
// is built, and so is a constant glass index.
TEST(HostileInput, CameraAndGlassParametersThatGiveNonFiniteRaysAreLocatedErrors) {
    const std::string world = "WorldBegin\nLightSource \"point\"\nShape \"sphere\"\nWorldEnd\n";
    const std::string corner_hint = " at raster position (0, 0), ";
    const std::pair<std::string, std::string> cameras[] = {
        {"Translate 1e30 0 0\nCamera \"perspective\"",
         "t.pbrt:2:1: error: camera rays start at (-1e+30, 0, 0)" + corner_hint +
             "beyond cmam's limit of 1e+18 on coordinates (check the camera transform and "
             "screenwindow)"},
        {"Translate nan 0 0\nCamera \"perspective\"",
         "t.pbrt:2:1: error: camera rays start at (nan, nan, nan)" + corner_hint +
             "beyond cmam's limit of 1e+18 on coordinates (check the camera transform and "
             "screenwindow)"},
        {"Scale 1e30 1e30 1e30\nCamera \"perspective\"",
         "t.pbrt:2:1: error: camera rays have direction (-inf, inf, inf)" + corner_hint +
             "not a finite unit vector (check the camera transform, screenwindow and "
             "frameaspectratio)"},
        {"Camera \"orthographic\" \"float screenwindow\" [-1e30 1e30 -1 1]",
         "t.pbrt:1:1: error: camera rays start at (-1e+30, 1, 0)" + corner_hint +
             "beyond cmam's limit of 1e+18 on coordinates (check the camera transform and "
             "screenwindow)"},
        {"Camera \"perspective\" \"float frameaspectratio\" 0",
         "t.pbrt:1:22: error: frameaspectratio must be a positive finite number, got 0"},
        {"Camera \"perspective\" \"float frameaspectratio\" nan",
         "t.pbrt:1:22: error: frameaspectratio must be a positive finite number, got nan"},
        {"Camera \"perspective\" \"float screenwindow\" [-1 1 nan 1]",
         "t.pbrt:1:22: error: screenwindow values must be finite numbers, got nan"},
        {"Camera \"perspective\" \"float screenwindow\" [-1 1e300 -1 1]",
         "t.pbrt:1:22: error: screenwindow values must be finite numbers, got 1e+300"},
        {"Translate 0 0 1e17\nCamera \"perspective\"", "no error"},
    };
    for (const auto& [camera, expected] : cameras)
        EXPECT_EQ(error_of(camera + "\n" + world), expected) << camera;
    const std::pair<std::string, std::string> glasses[] = {
        {"\"float index\" nan",
         "t.pbrt:3:18: error: index must be a positive finite number, got nan"},
        {"\"float eta\" inf", "t.pbrt:3:18: error: eta must be a positive finite number, got inf"},
        {"\"float index\" 0", "t.pbrt:3:18: error: index must be a positive finite number, got 0"},
        {"\"float index\" 1.33", "no error"},
    };
    for (const auto& [eta, expected] : glasses)
        EXPECT_EQ(error_of(std::string(kCamera) + "WorldBegin\nMaterial \"glass\" " + eta +
                           "\nShape \"sphere\"\nWorldEnd\n"),
                  expected)
            << eta;
}

// NaN and infinite light, material, texture and shape parameters, and transforms that are not
// finite, would render black without a word: each is a located error naming the value.
TEST(HostileInput, NumbersTheRendererUsesMustBeFinite) {
    const std::string tri = "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]";
    const std::pair<std::string, std::string> cases[] = {
        {"LightSource \"point\" \"rgb I\" [nan 1 1]",
         "t.pbrt:3:21: error: I values must be finite numbers, got nan"},
        {"LightSource \"spot\" \"rgb I\" [1 inf 1]",
         "t.pbrt:3:20: error: I values must be finite numbers, got inf"},
        {"LightSource \"distant\" \"rgb L\" [1 1 nan]",
         "t.pbrt:3:23: error: L values must be finite numbers, got nan"},
        {"LightSource \"infinite\" \"rgb scale\" [-inf 1 1]",
         "t.pbrt:3:24: error: scale values must be finite numbers, got -inf"},
        {"LightSource \"point\" \"point3 from\" [0 nan 0]",
         "t.pbrt:3:21: error: from values must be finite numbers, got nan"},
        {"LightSource \"spot\" \"float coneangle\" nan",
         "t.pbrt:3:20: error: coneangle must be a finite number, got nan"},
        {"Translate nan 0 0 LightSource \"point\"",
         "t.pbrt:3:19: error: the light's transform must be finite, got an entry of nan"},
        {"Material \"matte\" \"float sigma\" nan",
         "t.pbrt:3:18: error: sigma must be a finite number, got nan"},
        {"Material \"plastic\" \"float roughness\" nan",
         "t.pbrt:3:20: error: roughness must be a finite number, got nan"},
        {"Material \"mirror\" \"rgb Kr\" [inf inf inf]",
         "t.pbrt:3:19: error: Kr values must be finite numbers, got inf"},
        {"Material \"matte\" \"spectrum Kd\" [400 1e300 700 1e300]",
         "t.pbrt:3:18: error: Kd values must be finite numbers, got inf"},
        {"Texture \"c\" \"float\" \"constant\" \"float value\" nan",
         "t.pbrt:3:32: error: value must be a finite number, got nan"},
        {"Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"x.png\" \"float scale\" "
         "nan",
         "t.pbrt:3:61: error: scale must be a finite number, got nan"},
        {"Scale inf 1 1 Shape \"sphere\"",
         "t.pbrt:3:15: error: the shape's transform must be finite, got an entry of inf"},
        {"Translate nan 0 0 " + tri,
         "t.pbrt:3:19: error: the shape's transform must be finite, got an entry of nan"},
        {"Shape \"sphere\" \"float radius\" inf",
         "t.pbrt:3:16: error: radius must be a positive finite number, got inf"},
        {"Shape \"sphere\" \"float radius\" -1",
         "t.pbrt:3:16: error: radius must be a positive finite number, got -1"},
        {"Shape \"sphere\" \"float zmax\" nan",
         "t.pbrt:3:16: error: zmax must be a finite number, got nan"},
        {"Shape \"disk\" \"float innerradius\" nan",
         "t.pbrt:3:14: error: innerradius must be a finite number, got nan"},
        {"Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 nan 0 0 1 0]",
         "t.pbrt:3:22: error: P values must be finite numbers, got nan"},
        {"Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 1e39]",
         "t.pbrt:3:22: error: P values must be finite numbers, got 1e+39"},
        {tri + " \"normal N\" [0 0 1 0 0 inf 0 0 1]",
         "t.pbrt:3:53: error: N values must be finite numbers, got inf"},
        {tri + " \"point2 uv\" [0 0 1 0 nan 1]",
         "t.pbrt:3:53: error: uv values must be finite numbers, got nan"},
        {"LightSource \"spot\" \"float conedelta\" 2\nMaterial \"plastic\" \"float roughness\" "
         "0.2\nScale 2 2 2\n" +
             tri + " \"point2 uv\" [0 0 1 0 0 1]",
         "no error"},
    };
    for (const auto& [world, expected] : cases)
        EXPECT_EQ(error_of(std::string(kCamera) + "WorldBegin\n" + world + "\nWorldEnd\n"),
                  expected)
            << world;
}

// Values a texture computes at render time cannot be checked when the scene is read: a glass
// index of infinity or NaN (a scale texture of huge constants) bent rays into directions that
// were not finite, and Embree aborted on them; a negative one gave radiance of 1e24. Such a ray now
// gives its sample a radiance that is not a number, which the film counts and takes as black; no
// ray that is not finite reaches Embree.
TEST(HostileInput, NonFiniteValuesFromTexturesGiveCountedBlackSamples) {
    for (const char* index : {"\"inf\"", "\"nan\"", "\"negative\""}) {
        SCOPED_TRACE(index);
        const std::string text =
            "Camera \"perspective\"\nFilm \"image\" \"integer xresolution\" 8 "
            "\"integer yresolution\" 8\nWorldBegin\nLightSource \"distant\"\n"
            "Texture \"inf\" \"float\" \"scale\" \"float tex1\" 1e30 \"float tex2\" 1e30\n"
            "Texture \"nan\" \"float\" \"scale\" \"texture tex1\" \"inf\" \"float tex2\" 0\n"
            "Texture \"negative\" \"float\" \"constant\" \"float value\" -1.5\n"
            "Material \"glass\" \"texture index\" " +
            std::string(index) + "\nTranslate 0 0 3\nShape \"sphere\"\nWorldEnd\n";
        auto scene = render::build_scene(pbrt::parse_string(text, "t.pbrt"), {}, {});
        render::RenderStats stats;
        const render::Framebuffer fb = render::render(*scene, {}, &stats);
        EXPECT_GT(stats.non_finite_samples, 0u);
        // The sphere's samples, not the background's.
        EXPECT_LT(stats.non_finite_samples, 64u * scene->sampler.spp() / 2);
        for (float v : fb.rgb) EXPECT_TRUE(std::isfinite(v));
    }
    // The scene's own intersection refuses such rays.
    auto scene = render::build_scene(
        pbrt::parse_string(std::string(kCamera) + "WorldBegin\nShape \"sphere\"\nWorldEnd\n",
                           "t.pbrt"),
        {}, {});
    const float nan = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FALSE(scene->intersect({0, 0, -5}, {0, nan, 1}, 0, 1e30f));
    EXPECT_TRUE(scene->occluded({0, 0, -5}, {0, 0, 1}, 0, nan));
    EXPECT_TRUE(scene->intersect({0, 0, -5}, {0, 0, 1}, 0, 1e30f).has_value());
}

// Texture evaluation recurses on a render thread's stack: a chain of 6000 scale textures crashed
// a render thread. A texture nesting more than kMaxTextureDepth is a located error; a chain at
// the limit builds. A chain of mix materials resolves however long it is (17 rendered black).
TEST(HostileInput, TextureNestingIsBoundedAndMixChainsResolve) {
    auto chain = [](int n) {
        std::string s = std::string(kCamera) +
                        "WorldBegin\nTexture \"t0\" \"float\" \"constant\" \"float value\" 0.5\n";
        for (int i = 1; i < n; ++i)
            s += "Texture \"t" + std::to_string(i) + "\" \"float\" \"scale\" \"texture tex1\" \"t" +
                 std::to_string(i - 1) + "\"\n";
        return s + "Material \"matte\" \"texture sigma\" \"t" + std::to_string(n - 1) +
               "\"\nShape \"sphere\"\nWorldEnd\n";
    };
    EXPECT_EQ(error_of(chain(render::kMaxTextureDepth)), "no error");
    EXPECT_EQ(error_of(chain(render::kMaxTextureDepth + 1)),
              "t.pbrt:259:1: error: texture \"t256\" nests 257 textures deep, beyond cmam's "
              "limit of 256");
    std::string mix =
        "Camera \"perspective\" \"float fov\" 10\nFilm \"image\" \"integer xresolution\" 4 "
        "\"integer yresolution\" 4\nWorldBegin\nLightSource \"infinite\"\n"
        "MakeNamedMaterial \"m0\" \"string type\" \"matte\"\n";
    for (int i = 1; i <= 40; ++i)
        mix += "MakeNamedMaterial \"m" + std::to_string(i) +
               "\" \"string type\" \"mix\" \"string namedmaterial1\" \"m" + std::to_string(i - 1) +
               "\" \"string namedmaterial2\" \"m" + std::to_string(i - 1) + "\"\n";
    mix += "NamedMaterial \"m40\"\nTranslate 0 0 3\nShape \"sphere\"\nWorldEnd\n";
    auto scene = render::build_scene(pbrt::parse_string(mix, "t.pbrt"), {}, {});
    const render::Framebuffer fb = render::render(*scene, {}, nullptr);
    for (float v : fb.rgb) EXPECT_GT(v, 0.1f);  // the matte under the environment, not black
}

// A float image may hold NaN or infinite texels: lookups that read them give the same, which
// shading clamps to black. pbrt-v3 reads them silently; cmam warns where the texture is declared.
TEST(HostileInput, NonFiniteTexelsGiveALocatedWarning) {
    const fs::path dir = fs::temp_directory_path() / ("cmam_nan_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    render::write_image((dir / "nan.pfm").string(), 2, 2, {1, 1, 1, nan, 1, 1, 1, 1, 1, 1, 1, 1});
    const std::string text = std::string(kCamera) +
                             "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string "
                             "filename\" \"nan.pfm\"\nMaterial \"matte\" \"texture Kd\" \"t\"\n"
                             "Shape \"sphere\"\nWorldEnd\n";
    std::vector<std::string> warnings;
    auto sink = [&](const std::string& w) { warnings.push_back(w); };
    render::build_scene(pbrt::parse_string(text, (dir / "t.pbrt").string()), {}, sink);
    fs::remove_all(dir);
    std::erase_if(warnings, [](const std::string& w) { return w.find("nan.pfm") == w.npos; });
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], (dir / "t.pbrt").string() +
                               ":3:35: warning: \"nan.pfm\" has 1 texel value that is not a "
                               "finite number (NaN or infinite); the samples whose lookups read "
                               "it are taken as black");
}

// pbrt-v3's "discarddegenerateUVs" (pbrt-v3-scenes' head uses it): with normals, a mesh with a
// triangle two of whose vertices share a (u,v) loses all its (u,v), with a located warning;
// without the flag, or without normals, they are kept.
TEST(HostileInput, DiscardDegenerateUvsDropsTheMeshsUv) {
    auto mesh = [](const std::string& extra) {
        return std::string(kCamera) +
               "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"normal N\" "
               "[0 0 1 0 0 1 0 0 1] \"point2 uv\" [0 0 0 0 1 1]" +
               extra + "\nWorldEnd\n";
    };
    for (const auto& [extra, kept] :
         {std::pair<std::string, bool>{" \"bool discarddegenerateUVs\" true", false},
          {" \"bool discarddegenerateUVs\" false", true},
          {"", true}}) {
        std::vector<std::string> warnings;
        auto sink = [&](const std::string& w) { warnings.push_back(w); };
        auto scene = render::build_scene(pbrt::parse_string(mesh(extra), "t.pbrt"), {}, sink);
        ASSERT_EQ(scene->primitives.size(), 1u) << extra;
        EXPECT_EQ(scene->primitives[0]->uvs.empty(), !kept) << extra;
        std::erase_if(warnings, [](const std::string& w) { return w.find("(u,v)") == w.npos; });
        EXPECT_EQ(warnings.size(), kept ? 0u : 1u) << extra;
        if (!kept) {
            EXPECT_EQ(warnings[0],
                      "t.pbrt:3:110: warning: a triangle has two vertices at the same (u,v): all "
                      "of the mesh's (u,v) are discarded, as pbrt-v3's discarddegenerateUVs does");
        }
    }
}
