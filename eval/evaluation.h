// eval — `cmam eval`: ground truth, every footprint method at several sample counts, error
// metrics, and the results table and HTML report (algorithms.md §9).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "eval/error.h"
#include "pbrt/error.h"
#include "pbrt/scene_desc.h"
#include "render/build_scene.h"
#include "render/scene.h"

namespace cmam::eval {

/// A footprint method as the evaluation names it, e.g. "differentials+ewa", "cmam+sat",
/// "cmam-pixel-hull+trilinear".
struct Method {
    std::string name;
    render::BuildOptions build;  // lod, filter and CMAM settings (spp set per run)
};

/// Parses a method name; nullopt for an unknown one. Known forms: none; differentials+F;
/// cones+F; cones-aniso+F; cmam+F (paper mode: scanline tags, average miss, conjugate
/// ellipse); cmam-literal+F (no adjacency check); cmam-point+F (point sample on a miss);
/// cmam-pixel-hull+F (pixel tags with convex hull weighting); cmam2d+F (the 2-D CMAM);
/// F a filter of texture::kFilterNames other than nearest. The footprint method and the
/// filter are read with their name tables.
std::optional<Method> parse_method(const std::string& name);
/// The default list of the evaluation.
std::vector<std::string> default_methods();
/// The footprint sources a method name may start with (before "+FILTER"), in the order of
/// parse_method's table, and the filters it may end with.
std::vector<std::string> method_sources();
std::vector<std::string> method_filters();

struct EvalOptions {
    std::vector<std::string> scenes;
    std::vector<Method> methods;
    std::vector<int> spp = {1, 4, 16};
    int reference_spp = 1024;
    std::string out_dir = "eval-out";
    /// Renders timed per method and sample count: the report gives their median and range
    /// (1: a single run, marked as such).
    int timing_runs = 1;
    /// A ground truth to be rendered that is expected to take longer than this (seconds, from
    /// the scene's render at 1 spp) is announced first with a warning (through `warn`).
    double long_ground_truth = 120;
    /// Called after each render with (renders done, renders total, what was rendered).
    std::function<void(int, int, const std::string&)> progress;
    /// Receives each distinct warning of a scene (parsing and building), once.
    std::function<void(const std::string&)> warn;
    /// Receives the message of a scene that failed; the evaluation goes on with the others.
    std::function<void(const std::string& scene, const std::string& message)> scene_failed;
    /// Applied to each scene's description once it is parsed, before anything is rendered (the
    /// command line's --resolution and --crop), with the scene's warning sink; an exception
    /// fails that scene. The film it makes is part of the ground truth's key.
    std::function<void(pbrt::SceneDesc&, const pbrt::WarningSink&)> adjust_scene;
};

struct ResultRow {
    std::string scene, method;
    int spp = 0;
    double rmse = 0, psnr = 0, ssim = 0;  // full image
    double rmse_masked = 0, psnr_masked = 0, ssim_masked = 0, masked_fraction = 0;
    double texture_rmse = 0, texture_psnr = 0;  // texture AOV
    double seconds = 0, rays_per_second = 0;    // seconds: median of the timed runs
    std::string image, heatmap;                 // relative to out_dir
    double seconds_min = 0, seconds_max = 0;    // range of the timed runs
    int timing_runs = 1;
    std::string texture_heatmap;  // error of the texture AOV, relative to out_dir
};

struct SceneReport {
    std::string name, reference_image;
    bool reference_cached = false;
    int width = 0, height = 0;
    std::string path;                   // the scene file as given
    int reference_spp = 0;              // samples per pixel of the ground truth, as rendered
    std::string reference_texture;      // the ground truth's texture AOV (relative to out_dir)
    std::vector<std::string> warnings;  // distinct warnings of parsing and building
    /// Per sample count: the fraction of pixels kept as off edges (what the "off edges"
    /// metrics average over).
    std::vector<std::pair<int, double>> off_edge_fraction;
};

struct FailedScene {
    std::string path, message;
};

struct EvalResult {
    std::vector<ResultRow> rows;
    std::vector<SceneReport> scenes;
    std::vector<FailedScene> failed;  // scenes that could not be evaluated (skipped)
    std::vector<std::string> files;   // every file the report wrote, relative to out_dir
};

/// The samples per pixel a request of `spp` renders: a square grid of round(sqrt(spp))^2.
int rendered_spp(int spp);

/// Runs the evaluation and writes results.csv, results.md and index.html into out_dir. A scene
/// that fails is reported through scene_failed, listed in EvalResult::failed and skipped. Files
/// of an earlier report in out_dir that this one does not write again are removed (the report
/// lists what it wrote in out_dir/report-files.txt; the ground-truth cache is kept).
EvalResult run_eval(const EvalOptions& options);

/// Key of a scene's ground truth: a hash of every file it reads (scene files, textures, PLY),
/// its film's resolution and crop window, the renderer's version and the reference sample count,
/// as 16 hex digits.
std::string reference_key(const std::string& scene_path, int reference_spp);
/// The same for a scene already parsed (and perhaps adjusted: EvalOptions::adjust_scene).
std::string reference_key(const pbrt::SceneDesc& desc, int reference_spp);

/// The renderer's version string (part of every cache key).
const char* renderer_version();

}  // namespace cmam::eval
