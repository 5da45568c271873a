// eval — `cmam eval`: ground truth, every footprint method at several sample counts, error
// metrics, and the results table and HTML report (algorithms.md §9).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

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
/// F in bilinear, trilinear, sat, ewa, area.
std::optional<Method> parse_method(const std::string& name);
/// The default list of the evaluation.
std::vector<std::string> default_methods();

struct EvalOptions {
    std::vector<std::string> scenes;
    std::vector<Method> methods;
    std::vector<int> spp = {1, 4, 16};
    int reference_spp = 1024;
    std::string out_dir = "eval-out";
    /// Called after each render with (renders done, renders total, what was rendered).
    std::function<void(int, int, const std::string&)> progress;
};

struct ResultRow {
    std::string scene, method;
    int spp = 0;
    double rmse = 0, psnr = 0, ssim = 0;  // full image
    double rmse_masked = 0, psnr_masked = 0, ssim_masked = 0, masked_fraction = 0;
    double texture_rmse = 0, texture_psnr = 0;  // texture AOV
    double seconds = 0, rays_per_second = 0;
    std::string image, heatmap;  // relative to out_dir
};

struct SceneReport {
    std::string name, reference_image;
    bool reference_cached = false;
    int width = 0, height = 0;
};

struct EvalResult {
    std::vector<ResultRow> rows;
    std::vector<SceneReport> scenes;
};

/// Runs the evaluation and writes results.csv, results.md and index.html into out_dir.
EvalResult run_eval(const EvalOptions& options);

/// Key of a scene's ground truth: a hash of every file it reads (scene files, textures, PLY),
/// the renderer's version and the reference sample count, as 16 hex digits.
std::string reference_key(const std::string& scene_path, int reference_spp);

/// The renderer's version string (part of every cache key).
const char* renderer_version();

}  // namespace cmam::eval
