// The evaluation: metrics against hand-computed values, the edge mask, the ground-truth cache,
// and the ground truth itself against an exact integral (algorithms.md §9, T-GT-1).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "eval/evaluation.h"
#include "eval/metrics.h"
#include "expect_throw.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/image_io.h"
#include "render/integrator.h"
#include "temp_dir.h"

using namespace cmam;
namespace fs = std::filesystem;

TEST(Metrics, RmsePsnrByHand) {
    std::vector<float> ref = {0, 0, 0, 1, 1, 1}, img = {0.1f, 0.1f, 0.1f, 0.9f, 0.9f, 0.9f};
    eval::ErrorStats s = eval::compare(ref, img);
    EXPECT_NEAR(s.rmse, 0.1, 1e-7);
    EXPECT_NEAR(s.psnr, 20.0, 1e-5);
    EXPECT_NEAR(s.relative_rmse, 0.2, 1e-6);
    std::vector<bool> mask = {false, true};
    EXPECT_NEAR(eval::compare(ref, img, &mask).rmse, 0.1, 1e-7);
    EXPECT_TRUE(std::isinf(eval::compare(ref, ref).psnr));
    EXPECT_THROW_CONTAINS(eval::compare(ref, {0, 0, 0}), eval::EvalError,
                          "images differ in size (2 vs 1 pixels)");
    std::vector<bool> short_mask = {true};
    EXPECT_THROW_CONTAINS(eval::compare(ref, img, &short_mask), eval::EvalError,
                          "mask size does not match the image");
    EXPECT_THROW_CONTAINS(eval::ssim(ref, img, 2, 2), eval::EvalError, "images are not 2x2");
    EXPECT_THROW_CONTAINS(eval::edge_mask(ref, {0, 0, 0}), eval::EvalError,
                          "images differ in size (2 vs 1 pixels)");
    EXPECT_THROW_CONTAINS(eval::error_heatmap(ref, {0, 0, 0}, 1), eval::EvalError,
                          "images differ in size (2 vs 1 pixels)");
}

TEST(Metrics, SsimByHand) {
    // Identical images: 1. Constant images a and b: (2ab + C1) / (a^2 + b^2 + C1), variances 0.
    std::vector<float> a(4 * 3 * 3, 0.2f), b(4 * 3 * 3, 0.4f);
    EXPECT_NEAR(eval::ssim(a, a, 4, 3), 1.0, 1e-12);
    EXPECT_NEAR(eval::ssim(a, b, 4, 3), (2 * 0.2 * 0.4 + 1e-4) / (0.04 + 0.16 + 1e-4), 1e-6);
    // A checkerboard against its mean: the structure term vanishes, SSIM ~ C2 / (var + C2).
    std::vector<float> chk(8 * 8 * 3), mean(8 * 8 * 3, 0.5f);
    for (int p = 0; p < 64; ++p)
        for (int c = 0; c < 3; ++c) chk[3 * p + c] = ((p % 8 + p / 8) % 2) ? 1.0f : 0.0f;
    EXPECT_LT(eval::ssim(chk, mean, 8, 8), 0.01);
}

TEST(Metrics, EdgeMaskMarksDisagreeingPixels) {
    std::vector<float> ref = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0, 0, 0};
    std::vector<float> img = {0.505f, 0.5f, 0.5f, 0.9f, 0.5f, 0.5f, 0.0005f, 0, 0};
    std::vector<bool> m = eval::edge_mask(ref, img);
    EXPECT_EQ(m, (std::vector<bool>{true, false, true}));  // 1% off: kept; 80% off: an edge
}

TEST(Eval, GroundTruthIsCachedAndInvalidatedWhenTheSceneChanges) {
    const test::TempDir tmp("cmam_eval_cache");
    const fs::path& dir = tmp.path;
    fs::path scene = dir / "tiny.pbrt";
    std::string tex = std::string(CMAM_SCENES_DIR) + "/textures/gravel.png";
    auto write_scene = [&](const std::string& extra) {
        std::ofstream(scene)
            << "LookAt 0 1 -3  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 50\n"
            << "Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
            << "Integrator \"whitted\"\nWorldBegin\nLightSource \"distant\" \"point from\" [0 1 "
               "-1]\n"
            << "Texture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"" << tex << "\"\n"
            << "Material \"matte\" \"texture Kd\" \"g\"\n"
            << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
            << "\"point3 P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5] \"point2 uv\" [0 0 8 0 8 8 0 8]\n"
            << extra << "WorldEnd\n";
    };
    write_scene("");
    eval::EvalOptions o;
    o.scenes = {scene.string()};
    o.methods = {*eval::parse_method("none"), *eval::parse_method("differentials+ewa")};
    o.spp = {1};
    o.reference_spp = 4;
    o.out_dir = (dir / "out").string();
    int renders = 0;
    o.progress = [&](int, int, const std::string&) { ++renders; };
    eval::EvalResult first = eval::run_eval(o);
    ASSERT_EQ(first.scenes.size(), 1u);
    EXPECT_FALSE(first.scenes[0].reference_cached);
    EXPECT_EQ(first.rows.size(), 2u);
    EXPECT_LT(first.rows[1].rmse, first.rows[0].rmse);  // filtering beats point sampling here
    for (const char* f : {"results.csv", "results.md", "index.html"})
        EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / f));
    const std::string key = eval::reference_key(scene.string(), 4);
    EXPECT_EQ(eval::run_eval(o).scenes[0].reference_cached, true);
    EXPECT_EQ(eval::reference_key(scene.string(), 4), key);
    EXPECT_NE(eval::reference_key(scene.string(), 8), key);
    write_scene("# a changed scene\n");
    EXPECT_NE(eval::reference_key(scene.string(), 4), key);
    EXPECT_FALSE(eval::run_eval(o).scenes[0].reference_cached);
}

namespace {

// dir/plane.pbrt, a plane under a distant light with `integrator` (a directive, or nothing)
// before WorldBegin, and the options that evaluate it with "none" at 1 spp into dir/out against
// a ground truth of `reference_spp`, its warnings kept in `warnings`.
eval::EvalOptions plane_eval(const fs::path& dir, const std::string& integrator, int reference_spp,
                             std::vector<std::string>& warnings) {
    std::ofstream(dir / "plane.pbrt")
        << "LookAt 0 1 -3  0 0 0  0 1 0 Camera \"perspective\"\n"
        << "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 8\n"
        << integrator << "WorldBegin LightSource \"distant\" \"point from\" [0 1 -1]\n"
        << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
        << "\"point3 P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5]\nWorldEnd\n";
    eval::EvalOptions o;
    o.scenes = {(dir / "plane.pbrt").string()};
    o.methods = {*eval::parse_method("none")};
    o.spp = {1};
    o.reference_spp = reference_spp;
    o.out_dir = (dir / "out").string();
    o.warn = [&warnings](const std::string& w) { warnings.push_back(w); };
    return o;
}

}  // namespace

// A ground truth expected to take longer than EvalOptions::long_ground_truth is announced with a
// warning before it is rendered, naming the scene and its samples; a cached one is not.
TEST(Eval, LongGroundTruthIsAnnouncedBeforeItIsRendered) {
    const test::TempDir tmp("cmam_eval_long");
    std::vector<std::string> warnings;
    eval::EvalOptions o = plane_eval(tmp.path, "", 9, warnings);
    const std::string scene = o.scenes[0];
    auto announced = [&] {
        return std::count_if(warnings.begin(), warnings.end(), [&](const std::string& w) {
            return w.rfind("warning: " + scene +
                               ": its ground truth at 9 samples per pixel will take about ",
                           0) == 0 &&
                   w.find("--reference-spp, --resolution or --crop make it shorter") !=
                       std::string::npos;
        });
    };
    o.long_ground_truth = 1e9;  // (a tiny scene: seconds would never be reached)
    eval::run_eval(o);
    EXPECT_EQ(announced(), 0);
    std::filesystem::remove_all(o.out_dir);
    o.long_ground_truth = 0;
    const eval::EvalResult r = eval::run_eval(o);
    EXPECT_EQ(announced(), 1);
    EXPECT_EQ(std::count_if(r.scenes[0].warnings.begin(), r.scenes[0].warnings.end(),
                            [](const std::string& w) {
                                return w.find("its ground truth") != std::string::npos;
                            }),
              1);       // in the report too
    eval::run_eval(o);  // cached: nothing to announce
    EXPECT_EQ(announced(), 1);
}

// A path-traced scene (pbrt-v3's default integrator) is flagged: its image errors are mostly the
// path tracer's noise, and the texture RMSE compares the filters. A whitted one is not.
TEST(Eval, PathTracedSceneIsFlagged) {
    const test::TempDir tmp("cmam_eval_path");
    for (const std::string integrator : {"", "Integrator \"whitted\"\n"}) {
        SCOPED_TRACE(integrator);
        std::vector<std::string> warnings;
        const eval::EvalOptions o = plane_eval(tmp.path, integrator, 4, warnings);
        const eval::EvalResult r = eval::run_eval(o);
        ASSERT_EQ(r.scenes.size(), 1u);
        const auto flagged =
            std::count_if(warnings.begin(), warnings.end(), [&](const std::string& w) {
                return w == "warning: " + o.scenes[0] +
                                ": the scene is path traced, so its images carry the path "
                                "tracer's noise at every sample count, and so does the off-edge "
                                "mask; the texture RMSE (the unlit texture, the same for any "
                                "integrator) compares the filters";
            });
        EXPECT_EQ(flagged, integrator.empty() ? 1 : 0);
        fs::remove_all(o.out_dir);
    }
}

// EvalOptions::adjust_scene changes each scene's film before anything is rendered (the command
// line's --resolution and --crop): the ground truth and the methods have its size, its warnings
// reach the scene's, and the film it makes is part of the ground truth's key, so a cached ground
// truth of another film is not taken for it.
TEST(Eval, AdjustedFilmIsRenderedAndKeyed) {
    const test::TempDir tmp("cmam_eval_adjust");
    const fs::path& dir = tmp.path;
    const fs::path scene = dir / "tiny.pbrt";
    std::ofstream(scene) << "LookAt 0 1 -3  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 50\n"
                         << "Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 16\n"
                         << "Integrator \"whitted\"\nWorldBegin\n"
                         << "LightSource \"distant\" \"point from\" [0 1 -1]\n"
                         << "Shape \"sphere\"\nWorldEnd\n";
    auto film = [](int w, int h) {
        return [w, h](pbrt::SceneDesc& desc, const pbrt::WarningSink& warn) {
            for (const auto& [name, value] : {std::pair{"xresolution", w}, {"yresolution", h}}) {
                pbrt::Param p;
                p.type = pbrt::ParamType::Integer;
                p.type_name = "integer";
                p.name = name;
                p.numbers = {double(value)};
                desc.film.params.add(p);
            }
            warn("warning: film changed");
        };
    };
    eval::EvalOptions o;
    o.scenes = {scene.string()};
    o.methods = {*eval::parse_method("none")};
    o.spp = {1};
    o.reference_spp = 1;
    o.out_dir = (dir / "out").string();
    o.adjust_scene = film(12, 8);
    eval::EvalResult r = eval::run_eval(o);
    ASSERT_EQ(r.scenes.size(), 1u);
    EXPECT_EQ(r.scenes[0].width, 12);
    EXPECT_EQ(r.scenes[0].height, 8);
    EXPECT_FALSE(r.scenes[0].reference_cached);
    EXPECT_EQ(r.scenes[0].warnings, std::vector<std::string>{"warning: film changed"});
    const render::RawImage img = render::read_image(o.out_dir + "/" + r.rows.at(0).image);
    EXPECT_EQ(img.width, 12);
    EXPECT_EQ(img.height, 8);
    // The same film again: from the cache; another film, or none: not.
    r = eval::run_eval(o);
    ASSERT_EQ(r.scenes.size(), 1u);
    EXPECT_TRUE(r.scenes[0].reference_cached);
    o.adjust_scene = film(6, 4);
    r = eval::run_eval(o);
    ASSERT_EQ(r.scenes.size(), 1u) << "a ground truth of another film was taken from the cache";
    EXPECT_FALSE(r.scenes[0].reference_cached);
    EXPECT_EQ(r.scenes[0].width, 6);
    o.adjust_scene = nullptr;
    r = eval::run_eval(o);
    ASSERT_EQ(r.scenes.size(), 1u);
    EXPECT_FALSE(r.scenes[0].reference_cached);
    EXPECT_EQ(r.scenes[0].width, 24);
    // The key of the file as written is the key of its parsed scene.
    EXPECT_EQ(eval::reference_key(scene.string(), 1),
              eval::reference_key(pbrt::parse_file(scene.string()), 1));
}

// A scene that fails is reported and skipped; the others give their rows and the report. Each
// warning of a scene arrives once, however many renders build it. A second report into the same
// folder removes the images of methods it no longer has, and nothing else.
TEST(Eval, FailingSceneIsSkippedWarningsOnceAndReportsReplaceCleanly) {
    const test::TempDir tmp("cmam_eval_skip");
    const fs::path& dir = tmp.path;
    std::string tex = std::string(CMAM_SCENES_DIR) + "/textures/gravel.png";
    std::ofstream(dir / "good.pbrt")  // an integrator cmam renders as whitted: one warning
        << "LookAt 0 1 -3  0 0 0  0 1 0 Camera \"perspective\" \"float fov\" 50\n"
        << "Film \"image\" \"integer xresolution\" 12 \"integer yresolution\" 8\n"
        << "Integrator \"photonmap\"\nWorldBegin\n"
        << "LightSource \"distant\" \"point from\" [0 1 -1]\n"
        << "Texture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"" << tex << "\"\n"
        << "Material \"matte\" \"texture Kd\" \"g\"\n"
        << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
        << "\"point3 P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5] \"point2 uv\" [0 0 8 0 8 8 0 8]\nWorldEnd\n";
    std::ofstream(dir / "bad.pbrt")
        << "Camera \"perspective\"\nWorldBegin\nShape \"nope\"\nWorldEnd\n";
    eval::EvalOptions o;
    o.scenes = {(dir / "bad.pbrt").string(), (dir / "good.pbrt").string()};
    o.methods = {*eval::parse_method("none"), *eval::parse_method("differentials+ewa")};
    o.spp = {1, 4};
    o.reference_spp = 4;
    o.timing_runs = 3;
    o.out_dir = (dir / "out").string();
    std::vector<std::string> warnings, failed;
    o.warn = [&](const std::string& w) { warnings.push_back(w); };
    o.scene_failed = [&](const std::string& s, const std::string&) { failed.push_back(s); };
    eval::EvalResult r = eval::run_eval(o);
    ASSERT_EQ(r.failed.size(), 1u);
    EXPECT_EQ(failed, std::vector<std::string>{(dir / "bad.pbrt").string()});
    EXPECT_NE(r.failed[0].message.find("bad.pbrt:3:"), std::string::npos) << r.failed[0].message;
    ASSERT_EQ(r.scenes.size(), 1u);
    EXPECT_EQ(r.rows.size(), 4u);
    EXPECT_EQ(r.scenes[0].reference_spp, 4);
    ASSERT_EQ(r.scenes[0].off_edge_fraction.size(), 2u);
    EXPECT_GT(r.scenes[0].off_edge_fraction[0].second, 0.5);
    for (const eval::ResultRow& row : r.rows) {
        EXPECT_EQ(row.timing_runs, 3);
        EXPECT_LE(row.seconds_min, row.seconds);
        EXPECT_LE(row.seconds, row.seconds_max);
        EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / row.texture_heatmap));
    }
    std::vector<std::string> good;  // the warnings about good.pbrt
    for (const std::string& w : warnings)
        if (w.find("good.pbrt") != std::string::npos) good.push_back(w);
    ASSERT_EQ(good.size(), 1u);
    EXPECT_NE(good[0].find("Integrator"), std::string::npos) << good[0];
    EXPECT_EQ(r.scenes[0].warnings, good);
    std::ifstream html(fs::path(o.out_dir) / "index.html");
    std::string page((std::istreambuf_iterator<char>(html)), {});
    EXPECT_NE(page.find("bad.pbrt"), std::string::npos);  // the failure is in the report
    EXPECT_FALSE(fs::exists(fs::path(o.out_dir) / "bad"));

    const fs::path ewa = fs::path(o.out_dir) / "good" / "differentials_ewa-spp1.png";
    const fs::path own = fs::path(o.out_dir) / "good" / "notes.txt";
    ASSERT_TRUE(fs::exists(ewa));
    std::ofstream(own) << "not the report's";
    o.scenes = {(dir / "good.pbrt").string()};
    o.methods = {*eval::parse_method("none")};
    eval::EvalResult again = eval::run_eval(o);
    EXPECT_TRUE(again.failed.empty());
    EXPECT_FALSE(fs::exists(ewa));
    EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / "good" / "none-spp1.png"));
    EXPECT_TRUE(fs::exists(own));
}

TEST(Eval, MethodNames) {
    for (const std::string& m : eval::default_methods()) EXPECT_TRUE(eval::parse_method(m)) << m;
    EXPECT_FALSE(eval::parse_method("cmam+nearest"));
    EXPECT_FALSE(eval::parse_method("magic+ewa"));
    EXPECT_FALSE(eval::parse_method("none+ewa"));
    EXPECT_FALSE(eval::parse_method("cmam"));
    EXPECT_FALSE(eval::parse_method("cmam+"));
    EXPECT_FALSE(eval::parse_method("+ewa"));
    EXPECT_FALSE(eval::parse_method("Cmam+ewa"));
    EXPECT_EQ(
        eval::method_sources(),
        (std::vector<std::string>{"differentials", "cones", "cones-aniso", "cmam", "cmam-literal",
                                  "cmam-point", "cmam-pixel-hull", "cmam2d"}));
    EXPECT_EQ(eval::method_filters(),
              (std::vector<std::string>{"bilinear", "trilinear", "sat", "ewa", "area"}));
    auto none = eval::parse_method("none");
    ASSERT_TRUE(none);
    EXPECT_EQ(none->build.lod, render::FootprintMethod::None);
    EXPECT_FALSE(none->build.filter);
    auto literal = eval::parse_method("cmam-literal+sat");
    ASSERT_TRUE(literal);
    EXPECT_EQ(literal->build.lod, render::FootprintMethod::Cmam);
    EXPECT_EQ(literal->build.filter, texture::FilterKind::Sat);
    EXPECT_FALSE(literal->build.cmam.adjacent_only);
    auto cones = eval::parse_method("cones-aniso+area");
    ASSERT_TRUE(cones);
    EXPECT_EQ(cones->build.lod, render::FootprintMethod::ConesAniso);
    EXPECT_EQ(cones->build.filter, texture::FilterKind::Area);
    for (const std::string& source : eval::method_sources())
        for (const std::string& filter : eval::method_filters())
            EXPECT_TRUE(eval::parse_method(source + "+" + filter)) << source << "+" << filter;
    auto hull = eval::parse_method("cmam-pixel-hull+trilinear");
    ASSERT_TRUE(hull);
    EXPECT_TRUE(hull->build.cmam.hull);
    EXPECT_EQ(hull->build.tags, render::TagPolicy::Pixel);
}

// T-GT-1: one pixel of an orthographic camera sees the parallelogram (0.5,0.25), (1.75,0.75),
// (1.25,1.75), (0,1.25) of the 2x2 texture [1 2; 3 4] (texel space). The stratified ground
// truth (64 x 64 samples, nearest reconstruction) must match the exact average 2.4.
TEST(GroundTruth, TGt1MatchesTheExactIntegral) {
    const test::TempDir tmp("cmam_eval_gt1");
    const fs::path& dir = tmp.path;
    // File rows go top to bottom; v = 0 (texel row 0: values 1, 2) is the bottom row.
    render::write_image((dir / "t.exr").string(), 2, 2, {3, 3, 3, 4, 4, 4, 1, 1, 1, 2, 2, 2});
    // Raster (x, y) in [0,1]^2 maps to texel A + x (B - A) + (1 - y) (D - A) with A = (0.5, 0.25),
    // B - A = (1.25, 0.5), D - A = (-0.5, 1): a quad whose corners carry those uv (texel / 2).
    // Screen window [-1,1]^2 with the camera looking down +z: world x = screen x, world y = screen
    // y.
    std::ofstream(dir / "gt.pbrt")
        << "Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
        << "Film \"image\" \"integer xresolution\" 1 \"integer yresolution\" 1\n"
        << "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"t.exr\"\n"
        << "Material \"matte\" \"texture Kd\" \"t\"\n"
        << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-1 -1 5  1 -1 5 "
           " 1 1 5  -1 1 5]\n"
        << "  \"point2 uv\" [0.25 0.125  0.875 0.375  0.625 0.875  0 0.625]\nWorldEnd\n";
    pbrt::SceneDesc d = pbrt::parse_file((dir / "gt.pbrt").string());
    render::BuildOptions bo;
    bo.spp_override = 64 * 64;
    bo.lod = render::FootprintMethod::None;
    bo.filter = texture::FilterKind::Nearest;
    auto s = render::build_scene(d, bo, {});
    render::RenderOptions ro;
    ro.aov = render::AovKind::Texture;
    render::Framebuffer fb = render::render(*s, ro, nullptr);
    EXPECT_NEAR(fb.rgb[0], 2.4, 0.006) << fb.rgb[0];  // RMS error about 0.002 at N = 64 (§9)
}
