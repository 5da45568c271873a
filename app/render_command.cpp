// cmam render: a scene to an image, with the command line's overrides of the scene.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "app/command.h"
#include "app/common.h"
#include "app/film_overrides.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/image_io.h"
#include "render/integrator.h"
#include "render/memory.h"
#include "render/scene.h"

namespace cmam::app {

namespace {

// The AOVs --aov names; radiance (render::AovKind::None) is the option left out.
using AovName = texture::Named<render::AovKind>;
constexpr texture::NameTable kAovNames{AovName{render::AovKind::Footprint, "footprint"},
                                       AovName{render::AovKind::Texture, "texture"}};
// --cmam-adjacency: whether the CMAM accepts only adjacent samples.
constexpr texture::NameTable kAdjacencyNames{texture::Named<bool>{true, "on"},
                                             texture::Named<bool>{false, "off"}};

struct RenderArgs {
    std::string scene;
    std::string output;
    int spp = 0;
    int threads = 0;
    bool quiet = false;
    bool stats = false;
    std::optional<render::FootprintMethod> lod;  // empty: the scene's
    std::optional<texture::FilterKind> filter;   // empty: the scene's
    std::optional<render::AovKind> aov;          // empty: radiance
    texture::CmamMiss cmam_miss = texture::CmamMiss::Average;
    render::TagPolicy cmam_tags = render::TagPolicy::Scanline;
    texture::CmamEllipse cmam_ellipse = texture::CmamEllipse::Conjugate;
    texture::CmamSatMiss cmam_sat_miss = texture::CmamSatMiss::Average;
    bool cmam_adjacency = true;
    bool cmam_hull = false, cmam_2d = false;
    std::string resolution, crop;
    std::string max_memory;  // empty: the machine's memory (render::memory_limit())
};

bool is_float_format(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".exr" || ext == ".pfm";
}

// The footprint AOV reports the footprint of image textures in texels: refuse where there is
// none to report rather than write zeros.
void check_footprint_aov(const render::Scene& scene, const std::string& out) {
    if (!is_float_format(out))
        throw UsageError(
            "--aov footprint writes lengths in texels and MIP levels, "
            "which need a float image: use .exr or .pfm, not \"" +
            out + "\"");
    bool image = false, footprint = false;
    for (const render::TextureNode& n : scene.textures) {
        if (n.kind != render::TextureNode::Kind::Image) continue;
        image = true;
        footprint = footprint || n.lod != render::FootprintMethod::None;
    }
    if (!image)
        throw UsageError(
            "--aov footprint measures image textures, and this scene has none (procedural "
            "textures such as checkerboard have no texel size)");
    if (!footprint)
        throw UsageError("--aov footprint: --lod none point-samples, there is no footprint");
}

void print_stats(const render::Scene& scene, const render::RenderStats& stats) {
    std::size_t level0 = 0, pyramids = 0, tables = 0, prefixes = 0;
    for (const auto& [key, tex] : scene.images) {
        level0 += tex->image().memory_bytes();
        std::size_t all = tex->memory_bytes();
        std::size_t sat = tex->sat_built() ? tex->sat().memory_bytes() : 0;
        std::size_t rows = tex->row_prefix_bytes();
        tables += sat;
        prefixes += rows;
        pyramids += all - sat - rows - tex->image().memory_bytes();
    }
    auto mb = [](std::size_t b) { return double(b) / (1 << 20); };
    std::fprintf(
        stderr,
        "textures: %zu images, level 0 %.2f MB, MIP pyramids %.2f MB, summed-area tables %.2f MB, "
        "row prefix tables (area) %.2f MB\n",
        scene.images.size(), mb(level0), mb(pyramids), mb(tables), mb(prefixes));
    std::fprintf(stderr, "lookups: point-sampled (no footprint) %llu",
                 (unsigned long long)stats.lookups_point_sampled);
    for (int k = 0; k < texture::kFilterKinds; ++k)
        std::fprintf(stderr, ", %s %llu",
                     std::string(texture::to_string(texture::FilterKind(k))).c_str(),
                     (unsigned long long)stats.lookups_by_filter[k]);
    std::fprintf(stderr, "\n");
    if (stats.lookups_non_finite)
        std::fprintf(stderr, "lookups with a non-finite uv or footprint (texture mean): %llu\n",
                     (unsigned long long)stats.lookups_non_finite);
    if (stats.cmam_2d_without_above)
        std::fprintf(stderr, "2-D CMAM lookups without a sample above: %llu\n",
                     (unsigned long long)stats.cmam_2d_without_above);
    if (stats.dropped_differentials)
        std::fprintf(stderr, "ray differentials dropped (grazing or non-finite): %llu\n",
                     (unsigned long long)stats.dropped_differentials);
}

// The image is written to a temporary beside `out` and renamed: its folder must exist and be
// writable.
void check_output_folder(const std::string& out) {
    namespace fs = std::filesystem;
    fs::path dir = fs::path(out).parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    if (!fs::exists(dir, ec))
        throw UsageError("cannot write \"" + out + "\": the folder \"" + dir.string() +
                         "\" does not exist");
    if (!fs::is_directory(dir, ec))
        throw UsageError("cannot write \"" + out + "\": \"" + dir.string() + "\" is not a folder");
    if (::access(dir.c_str(), W_OK) != 0)
        throw UsageError("cannot write \"" + out + "\": the folder \"" + dir.string() +
                         "\" is not writable");
}

// The scene's build options as the command line overrides them.
render::BuildOptions build_options(const RenderArgs& a) {
    render::BuildOptions bo;
    bo.spp_override = a.spp;
    bo.lod = a.lod;
    bo.filter = a.filter;
    if (a.cmam_hull && a.cmam_tags != render::TagPolicy::Pixel)
        throw UsageError("--cmam-hull works per pixel: it needs --cmam-tags pixel");
    bo.tags = a.cmam_tags;
    bo.cmam.miss = a.cmam_miss;
    bo.cmam.ellipse = a.cmam_ellipse;
    bo.cmam.sat_miss = a.cmam_sat_miss;
    bo.cmam.adjacent_only = a.cmam_adjacency;
    bo.cmam.hull = a.cmam_hull;
    if (a.cmam_2d && a.cmam_tags != render::TagPolicy::Scanline)
        throw UsageError(
            "--cmam-2d finds the pixel above through scanline tags: use --cmam-tags scanline");
    bo.cmam.two_d = a.cmam_2d;
    return bo;
}

// The summary line: wall time, split into loading (parsing, images and acceleration structures;
// pyramids and tables are built on first use, inside the render) and rendering, and the rays.
void print_summary(const std::string& out, const render::Framebuffer& fb, int spp,
                   const render::RenderStats& stats, double wall_s, double load_s,
                   double render_s) {
    uint64_t rays = stats.total_rays();
    std::fprintf(stderr,
                 "%s: %dx%d, %d spp, wall %.3fs (load %.3fs, render %.3fs), %llu rays, "
                 "%.2f Mrays/s\n",
                 out.c_str(), fb.width, fb.height, spp, wall_s, load_s, render_s,
                 (unsigned long long)rays, render_s > 0 ? rays / render_s / 1e6 : 0.0);
}

int run_render(const RenderArgs& a) {
    auto t0 = std::chrono::steady_clock::now();
    const FilmOverrides film(a.resolution, a.crop);
    pbrt::SceneDesc desc = pbrt::parse_file(a.scene, print_warning);
    film.apply(desc, print_warning);
    note_spp_rounding(a.spp);
    std::optional<std::size_t> max_memory;
    if (!a.max_memory.empty() && !(max_memory = render::parse_bytes(a.max_memory)))
        throw UsageError("--max-memory: expected a size such as 8G or 512M, not \"" + a.max_memory +
                         "\"");
    render::BuildOptions bo = build_options(a);
    bo.max_memory = max_memory;  // mesh files too big are refused before they are read
    bo.threads = a.threads;
    auto scene = render::build_scene(desc, bo, print_warning);
    std::string out = a.output.empty() ? scene->film.filename : a.output;
    check_output_folder(out);  // before rendering: a long render is not lost to a typo
    render::check_render_memory(*scene, max_memory);  // before rendering, with the sizes

    ProgressBar bar(!a.quiet && ::isatty(STDERR_FILENO));
    render::RenderOptions ro;
    ro.threads = a.threads;
    ro.aov = a.aov.value_or(render::AovKind::None);
    ro.count_lookups = a.stats;  // printed with --stats only
    if (ro.aov == render::AovKind::Footprint) check_footprint_aov(*scene, out);
    ro.progress = [&](int done, int total) { bar.update(done, total); };
    render::RenderStats stats;
    auto t1 = std::chrono::steady_clock::now();
    render::Framebuffer fb = render::render(*scene, ro, &stats);
    auto t2 = std::chrono::steady_clock::now();
    render::write_image(out, fb.width, fb.height, fb.rgb, fb.channel_names);
    if (!a.quiet) {
        const auto seconds = [](auto from, auto to) {
            return std::chrono::duration<double>(to - from).count();
        };
        // (An sppm scene's AOVs are traced by the path tracer, at the sampler's count.)
        const bool sppm = scene->sppm.on && ro.aov == render::AovKind::None;
        print_summary(out, fb, sppm ? scene->sppm.iterations : scene->sampler.spp(), stats,
                      seconds(t0, std::chrono::steady_clock::now()), seconds(t0, t1),
                      seconds(t1, t2));
    }
    if (a.stats) print_stats(*scene, stats);
    if (stats.non_finite_samples)
        warn(std::to_string(stats.non_finite_samples) +
             " samples had a radiance that is not a finite number (from NaN or infinite "
             "texels or parameters, or an index of refraction a texture gives that is not "
             "positive) and were taken as black");
    return 0;
}

// Scene, output and sampling.
void add_output_options(CLI::App& cmd, RenderArgs& a) {
    cmd.add_option("scene", a.scene, "Scene file (.pbrt)")->required();
    cmd.add_option("-o,--output", a.output,
                   "Output image: .exr or .pfm (float, linear), .png, .jpg or .tga (8-bit "
                   "sRGB); default: the Film's filename");
    cmd.add_option("--spp", a.spp,
                   "Samples per pixel, rounded to a square grid (5 renders 2x2 = 4, with a "
                   "warning); 1 = the pixel centre")
        ->check(CLI::Range(1, 1 << 20));
    cmd.add_option("--threads", a.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 4096));
    cmd.add_flag("--quiet", a.quiet, "No progress bar and no summary line");
    cmd.add_option("--max-memory", a.max_memory,
                   "Refuse, before rendering, a render that would take the process over "
                   "this size (8G, 512M; default: the machine's memory)");
    cmd.add_option("--resolution", a.resolution,
                   "Film resolution WxH, or W alone to keep the scene's aspect ratio (a "
                   "quick preview of a big scene)");
    cmd.add_option("--crop", a.crop,
                   "Render only X0,X1,Y0,Y1 of the image: the Film's cropwindow, fractions "
                   "of the width and height from the top left (replaces the scene's)");
    cmd.add_flag("--stats", a.stats, "Print texture memory and lookup counts per filter");
}

// Footprints, filters and AOVs of image textures.
void add_texture_options(CLI::App& cmd, RenderArgs& a) {
    add_choice(cmd, "--lod", a.lod, render::kFootprintMethodNames,
               "Footprint source for image textures: " + render::kFootprintMethodNames.list() +
                   " (default: differentials, as pbrt-v3; none point-samples)");
    add_choice(cmd, "--aov", a.aov, kAovNames,
               "Write an AOV instead of radiance, " + kAovNames.list() +
                   ": footprint gives the major and minor axis in texels and the MIP level (.exr "
                   "or .pfm; with --lod cmam the region the CMAM built), texture the unlit "
                   "filtered texture of the first non-specular hit");
    add_choice(cmd, "--filter", a.filter, texture::kFilterNames,
               "Filter for image textures: " + texture::kFilterNames.list() +
                   " (default: the scene's; area is the exact mean over each sample's "
                   "footprint)");
}

void add_cmam_options(CLI::App& cmd, RenderArgs& a) {
    add_choice(cmd, "--cmam-miss", a.cmam_miss, texture::kCmamMissNames,
               "CMAM, no matching sample: " + texture::kCmamMissNames.list());
    add_choice(cmd, "--cmam-tags", a.cmam_tags, render::kTagPolicyNames,
               "CMAM ray IDs: " + render::kTagPolicyNames.list());
    add_choice(cmd, "--cmam-ellipse", a.cmam_ellipse, texture::kCmamEllipseNames,
               "CMAM EWA reading of two vectors: " + texture::kCmamEllipseNames.list());
    add_choice(cmd, "--cmam-sat-miss", a.cmam_sat_miss, texture::kCmamSatMissNames,
               "CMAM SAT on a miss: " + texture::kCmamSatMissNames.list());
    add_choice(cmd, "--cmam-adjacency", a.cmam_adjacency, kAdjacencyNames,
               "CMAM accepts only adjacent samples: " + kAdjacencyNames.list() +
                   " (off: the paper's literal matching)");
    cmd.add_flag("--cmam-2d", a.cmam_2d,
                 "2-D CMAM: also use the sample of the pixel above (scanline tags), an "
                 "improvement beyond the paper");
    cmd.add_flag("--cmam-hull", a.cmam_hull,
                 "CMAM convex hull weighting (paper section 4; pixel tags)");
}

void add_render_options(CLI::App& cmd, RenderArgs& a) {
    add_output_options(cmd, a);
    add_texture_options(cmd, a);
    add_cmam_options(cmd, a);
}

}  // namespace

Command add_render_command(CLI::App& app) {
    return make_command(app, "render", "Render a pbrt-v3 scene", add_render_options, run_render);
}

}  // namespace cmam::app
