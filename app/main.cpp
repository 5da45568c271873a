// cmam — command-line front end: `cmam render`, `cmam check`, `cmam lookup`, `cmam compare`,
// `cmam eval`.
// Libraries throw; this file is the only place that prints errors.
#include <cmam/texture/cmam.h>
#include <cmam/texture/ewa.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <sstream>

#include "eval/evaluation.h"
#include "eval/metrics.h"
#include "pbrt/parser.h"
#include "render/image_io.h"
#include "render/integrator.h"
#include "render/scene.h"

namespace {

using namespace cmam;

std::vector<double> parse_numbers(const std::string& text, const char* flag) {
    std::vector<double> out;
    std::size_t pos = 0;
    while (pos <= text.size()) {
        std::size_t comma = text.find(',', pos);
        std::string item =
            text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
        char* end = nullptr;
        double v = std::strtod(item.c_str(), &end);
        if (item.empty() || end != item.c_str() + item.size())
            throw std::invalid_argument(std::string(flag) + ": \"" + item + "\" is not a number");
        out.push_back(v);
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    return out;
}

struct RenderArgs {
    std::string scene;
    std::string output;
    int spp = 0;
    int threads = 0;
    bool quiet = false;
    bool stats = false;
    std::string lod, filter, cmam_miss = "average", cmam_tags = "scanline",
                             cmam_ellipse = "conjugate", cmam_sat_miss = "average",
                             cmam_adjacency = "on";
    bool cmam_hull = false, cmam_2d = false;
    std::string aov;
    std::string resolution, crop;
};

// Warnings and errors have one form: "FILE:LINE:COL: warning: ..." when they point into a scene
// file, "cmam: warning: ..." otherwise.
void print_warning(const std::string& w) {
    std::cerr << (w.rfind("warning: ", 0) == 0 ? "cmam: " : "") << w << "\n";
}

void warn(const std::string& message) {
    print_warning("warning: " + message);
}

// --spp N renders a square grid of k x k strata: says so when k * k != N.
void note_spp_rounding(int spp, const char* flag = "--spp") {
    if (spp <= 0) return;
    const int n = eval::rendered_spp(spp), k = static_cast<int>(std::lround(std::sqrt(n)));
    if (n != spp)
        warn(std::string(flag) + " " + std::to_string(spp) + " renders " + std::to_string(k) + "x" +
             std::to_string(k) + " = " + std::to_string(n) +
             " samples per pixel (stratified samples form a square grid)");
}

pbrt::Param film_param(const char* type, const char* name, std::vector<double> values) {
    pbrt::Param p;
    p.type = std::string(type) == "integer" ? pbrt::ParamType::Integer : pbrt::ParamType::Float;
    p.type_name = type;
    p.name = name;
    p.numbers = std::move(values);
    return p;
}

// --resolution W or WxH: the film's resolution, as if the Film said so. W alone keeps the
// scene's aspect ratio (and so the camera's framing); another aspect frames more or less of the
// scene, as in pbrt-v3, with a warning.
void override_resolution(pbrt::SceneDesc& desc, const std::string& text) {
    const int xres = desc.film.params.get_int("xresolution", 640),
              yres = desc.film.params.get_int("yresolution", 480);
    int w = 0, h = 0;
    char x = 0, extra = 0;
    const int n = std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra);
    if (n == 1 && w > 0)
        h = std::max(1, static_cast<int>(std::lround(double(w) * yres / xres)));
    else if (!(n == 3 && (x == 'x' || x == 'X') && w > 0 && h > 0))
        throw std::invalid_argument("--resolution: expected WIDTHxHEIGHT or WIDTH, got \"" + text +
                                    "\"");
    if (std::abs(double(w) / h - double(xres) / yres) > 1.0 / std::min(w, h))
        warn("--resolution " + std::to_string(w) + "x" + std::to_string(h) +
             " has another aspect ratio than the scene's " + std::to_string(xres) + "x" +
             std::to_string(yres) + " film: the camera frames " +
             (double(w) / h > double(xres) / yres ? "more" : "less") +
             " of the scene horizontally (give the width alone to keep the aspect)");
    desc.film.params.add(film_param("integer", "xresolution", {double(w)}));
    desc.film.params.add(film_param("integer", "yresolution", {double(h)}));
}

// --crop x0,x1,y0,y1: the Film's cropwindow (fractions of the image, y down, as pbrt-v3); it
// replaces the scene's.
void override_crop(pbrt::SceneDesc& desc, const std::vector<double>& c) {
    if (c.size() != 4) throw std::invalid_argument("--crop needs four numbers: X0,X1,Y0,Y1");
    for (double v : c)
        if (!(v >= 0 && v <= 1))
            throw std::invalid_argument("--crop: values are fractions of the image, in [0, 1]");
    if (!(c[0] < c[1] && c[2] < c[3]))
        throw std::invalid_argument("--crop: needs X0 < X1 and Y0 < Y1");
    desc.film.params.add(film_param("float", "cropwindow", c));
}

bool is_float_format(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".exr" || ext == ".pfm";
}

// The footprint AOV reports the footprint of image textures in texels: refuse where there is
// none to report rather than write zeros.
void check_footprint_aov(const render::Scene& scene, const std::string& out) {
    if (!is_float_format(out))
        throw std::invalid_argument(
            "--aov footprint writes lengths in texels and MIP levels, "
            "which need a float image: use .exr or .pfm, not \"" +
            out + "\"");
    bool image = false, footprint = false;
    for (const render::TextureNode& n : scene.textures) {
        if (n.kind != render::TextureNode::Kind::Image) continue;
        image = true;
        footprint = footprint || n.lod != render::Lod::None;
    }
    if (!image)
        throw std::invalid_argument(
            "--aov footprint measures image textures, and this scene has none (procedural "
            "textures such as checkerboard have no texel size)");
    if (!footprint)
        throw std::invalid_argument(
            "--aov footprint: --lod none point-samples, there is no footprint");
}

std::string format_duration(double s) {
    char buf[64];
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%.1fs", s);
    else
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    return buf;
}

class ProgressBar {
  public:
    explicit ProgressBar(bool enabled)
        : m_enabled(enabled), m_start(std::chrono::steady_clock::now()) {}
    void update(int done, int total) {
        if (!m_enabled) return;
        std::lock_guard<std::mutex> lock(m_mutex);
        double frac = double(done) / total;
        int pct = int(frac * 100);
        if (pct == m_last && done != total) return;
        m_last = pct;
        double el =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
        double eta = frac > 0 ? el / frac - el : 0;
        constexpr int kWidth = 40;
        int fill = int(frac * kWidth);
        std::string bar(fill, '=');
        bar.resize(kWidth, ' ');
        std::fprintf(stderr, "\r[%s] %3d%%  elapsed %s  ETA %s   ", bar.c_str(), pct,
                     format_duration(el).c_str(), format_duration(eta).c_str());
        if (done == total) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

  private:
    bool m_enabled;
    std::chrono::steady_clock::time_point m_start;
    std::mutex m_mutex;
    int m_last = -1;
};

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
        throw std::invalid_argument("cannot write \"" + out + "\": the folder \"" + dir.string() +
                                    "\" does not exist");
    if (!fs::is_directory(dir, ec))
        throw std::invalid_argument("cannot write \"" + out + "\": \"" + dir.string() +
                                    "\" is not a folder");
    if (::access(dir.c_str(), W_OK) != 0)
        throw std::invalid_argument("cannot write \"" + out + "\": the folder \"" + dir.string() +
                                    "\" is not writable");
}

int run_render(const RenderArgs& a) {
    auto t0 = std::chrono::steady_clock::now();
    pbrt::SceneDesc desc = pbrt::parse_file(a.scene, print_warning);
    if (!a.resolution.empty()) override_resolution(desc, a.resolution);
    if (!a.crop.empty()) override_crop(desc, parse_numbers(a.crop, "--crop"));
    render::BuildOptions bo;
    bo.spp_override = a.spp;
    note_spp_rounding(a.spp);
    if (!a.lod.empty()) {
        bo.lod = render::parse_lod(a.lod);
        if (!bo.lod)
            throw std::invalid_argument(
                "--lod: unknown \"" + a.lod +
                "\" (expected none, differentials, cones, cones-aniso or cmam)");
    }
    if (!a.filter.empty()) {
        bo.filter = texture::parse_filter(a.filter);
        if (!bo.filter)
            throw std::invalid_argument("--filter: unknown \"" + a.filter + "\" (expected " +
                                        texture::filter_names() + ")");
    }
    auto miss = texture::parse_cmam_miss(a.cmam_miss);
    auto tags = render::parse_tag_policy(a.cmam_tags);
    auto ell = texture::parse_cmam_ellipse(a.cmam_ellipse);
    auto sat_miss = texture::parse_cmam_sat_miss(a.cmam_sat_miss);
    if (!miss) throw std::invalid_argument("--cmam-miss: expected average or point");
    if (!tags) throw std::invalid_argument("--cmam-tags: expected scanline or pixel");
    if (!ell)
        throw std::invalid_argument(
            "--cmam-ellipse: expected conjugate, orthogonal or orthogonalised");
    if (!sat_miss)
        throw std::invalid_argument("--cmam-sat-miss: expected average or paper-literal");
    if (a.cmam_adjacency != "on" && a.cmam_adjacency != "off")
        throw std::invalid_argument("--cmam-adjacency: expected on or off");
    if (a.cmam_hull && *tags != render::TagPolicy::Pixel)
        throw std::invalid_argument("--cmam-hull works per pixel: it needs --cmam-tags pixel");
    bo.tags = *tags;
    bo.cmam.miss = *miss;
    bo.cmam.ellipse = *ell;
    bo.cmam.sat_miss = *sat_miss;
    bo.cmam.adjacent_only = a.cmam_adjacency == "on";
    bo.cmam.hull = a.cmam_hull;
    if (a.cmam_2d && *tags != render::TagPolicy::Scanline)
        throw std::invalid_argument(
            "--cmam-2d finds the pixel above through scanline tags: use --cmam-tags scanline");
    bo.cmam.two_d = a.cmam_2d;
    auto scene = render::build_scene(desc, bo, print_warning);
    std::string out = a.output.empty() ? scene->film.filename : a.output;
    check_output_folder(out);  // before rendering: a long render is not lost to a typo

    ProgressBar bar(!a.quiet && ::isatty(STDERR_FILENO));
    render::RenderOptions ro;
    ro.threads = a.threads;
    if (a.aov == "footprint") {
        ro.aov = render::AovKind::Footprint;
        check_footprint_aov(*scene, out);
    } else if (a.aov == "texture")
        ro.aov = render::AovKind::Texture;
    else if (!a.aov.empty())
        throw std::invalid_argument("--aov: unknown \"" + a.aov +
                                    "\" (expected footprint or texture)");
    ro.progress = [&](int done, int total) { bar.update(done, total); };
    render::RenderStats stats;
    auto t1 = std::chrono::steady_clock::now();
    render::Framebuffer fb = render::render(*scene, ro, &stats);
    auto t2 = std::chrono::steady_clock::now();
    render::write_image(out, fb.width, fb.height, fb.rgb, fb.channel_names);
    double render_s = std::chrono::duration<double>(t2 - t1).count();
    double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!a.quiet) {
        uint64_t rays = stats.total_rays();
        std::fprintf(stderr,
                     "%s: %dx%d, %d spp, wall %.3fs (render %.3fs), %llu rays, %.2f Mrays/s\n",
                     out.c_str(), fb.width, fb.height, scene->sampler.spp(), wall_s, render_s,
                     (unsigned long long)rays, render_s > 0 ? rays / render_s / 1e6 : 0.0);
    }
    if (a.stats) print_stats(*scene, stats);
    return 0;
}

struct LookupArgs {
    std::string image, uv, axes, points, filter = "ewa", wrap = "repeat";
    double max_aniso = 8;
    bool json = false;
};

std::string json_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (static_cast<unsigned char>(c) < 0x20) {  // control characters as \u00XX
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
            out += buf;
            continue;
        }
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out;
}

// A number as JSON has it: JSON has no NaN or infinity, so those are null (a NaN --uv given to
// see the fallback, an infinite PSNR of identical images).
std::string json_number(double x) {
    if (!std::isfinite(x)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", x);
    return buf;
}

int run_lookup(const LookupArgs& a) {
    auto kind = texture::parse_filter(a.filter);
    if (!kind)
        throw std::invalid_argument("--filter: unknown filter \"" + a.filter + "\" (expected " +
                                    texture::filter_names() + ")");
    auto wrap = texture::parse_wrap_mode(a.wrap);
    if (!wrap)
        throw std::invalid_argument("--wrap: unknown wrap mode \"" + a.wrap +
                                    "\" (expected repeat, clamp, black or mirror)");
    std::vector<double> uv;  // --points gives the lookup point as its first pair
    if (!a.uv.empty() || a.points.empty()) uv = parse_numbers(a.uv, "--uv");
    if (a.points.empty() && uv.size() != 2)
        throw std::invalid_argument("--uv needs two numbers: U,V");
    texture::Footprint fp;
    if (!a.axes.empty()) {
        auto ax = parse_numbers(a.axes, "--axes");
        if (ax.size() != 4) throw std::invalid_argument("--axes needs four numbers: AU,AV,BU,BV");
        fp = texture::Footprint::axes({ax[0], ax[1]}, {ax[2], ax[3]});
    } else if (!a.points.empty()) {
        auto pt = parse_numbers(a.points, "--points");
        if (pt.size() % 2 != 0 || pt.size() < 2 || pt.size() > 6)
            throw std::invalid_argument(
                "--points needs one to three U,V pairs (the current sample first)");
        fp.kind = texture::Footprint::Kind::Points;
        fp.point_count = static_cast<int>(pt.size() / 2);
        for (int i = 0; i < fp.point_count; ++i) fp.points[i] = {pt[2 * i], pt[2 * i + 1]};
        uv = {pt[0], pt[1]};
    }
    if (*kind == texture::FilterKind::Ewa && a.max_aniso > texture::kEwaMaxAnisotropy)
        std::cerr << "cmam: warning: --maxaniso " << a.max_aniso << " is above cmam's limit of "
                  << texture::kEwaMaxAnisotropy << ", which is used instead\n";
    texture::FilteredTexture tex(render::load_texture(a.image, false, std::nullopt, 1.0f, *wrap));
    texture::LookupInfo info;
    texture::Texel v = tex.lookup(uv[0], uv[1], fp, {*kind, a.max_aniso}, &info);
    const texture::Image& img = tex.image();
    bool region = fp.kind != texture::Footprint::Kind::None &&
                  *kind != texture::FilterKind::Nearest && *kind != texture::FilterKind::Bilinear &&
                  !info.fallback;
    if (a.json) {
        const auto num = json_number;
        std::string out = "{\"image\": \"" + json_escape(a.image) +
                          "\", \"width\": " + std::to_string(img.width()) +
                          ", \"height\": " + std::to_string(img.height()) + ", \"filter\": \"" +
                          std::string(texture::to_string(*kind)) + "\", \"uv\": [" + num(uv[0]) +
                          ", " + num(uv[1]) + "], \"value\": [" + num(v[0]) + ", " + num(v[1]) +
                          ", " + num(v[2]) + "], \"levels\": [" + std::to_string(info.level_lo) +
                          ", " + std::to_string(info.level_hi) +
                          "], \"lambda\": " + num(info.lambda) +
                          ", \"texels_read\": " + std::to_string(info.texels_read) +
                          ", \"fallback\": " + (info.fallback ? "true" : "false");
        if (region && *kind == texture::FilterKind::Sat)
            out += ", \"rectangle_texels\": [" + num(info.rect[0]) + ", " + num(info.rect[1]) +
                   ", " + num(info.rect[2]) + ", " + num(info.rect[3]) + "]";
        if (region && *kind == texture::FilterKind::Ewa)
            out += ", \"ellipse_texels\": {\"major\": " + num(info.major) +
                   ", \"minor\": " + num(info.minor) + "}";
        if (region && *kind == texture::FilterKind::Trilinear)
            out += ", \"width_texels\": " + num(info.width);
        if (region && *kind == texture::FilterKind::Area)
            out += ", \"region_texels\": {\"shape\": \"" +
                   std::string(info.major > 0 ? "parallelogram" : "triangle") +
                   "\", \"major\": " + num(info.major) + ", \"minor\": " + num(info.minor) +
                   ", \"area\": " + num(info.area) + "}";
        std::printf("%s}\n", out.c_str());
        return 0;
    }
    std::printf("value (linear RGB): %.6f %.6f %.6f\n", v[0], v[1], v[2]);
    std::printf("filter: %s, MIP levels %d..%d (lambda %.4f), texels read: %d%s\n",
                std::string(texture::to_string(*kind)).c_str(), info.level_lo, info.level_hi,
                info.lambda, info.texels_read,
                info.fallback ? " (non-finite input: texture mean)" : "");
    if (!region)
        std::printf("footprint: none (bilinear at level 0)\n");
    else if (*kind == texture::FilterKind::Sat)
        std::printf("footprint: rectangle [%.4f, %.4f] x [%.4f, %.4f] texels\n", info.rect[0],
                    info.rect[2], info.rect[1], info.rect[3]);
    else if (*kind == texture::FilterKind::Ewa)
        std::printf("footprint: ellipse, axes %.4f and %.4f texels (after the anisotropy clamp)\n",
                    info.major, info.minor);
    else if (*kind == texture::FilterKind::Area && info.major > 0)
        std::printf(
            "footprint: parallelogram, sides %.4f and %.4f texels (with the reconstruction "
            "term), area %.4f texels^2, integrated on level %d\n",
            info.major, info.minor, info.area, info.level_lo);
    else if (*kind == texture::FilterKind::Area)
        std::printf(
            "footprint: the samples' triangle, area %.4f texels^2, integrated on level %d\n",
            info.area, info.level_lo);
    else
        std::printf("footprint: width %.4f texels\n", info.width);
    return 0;
}

int run_compare(const std::string& ref_path, const std::string& img_path, bool json) {
    render::RawImage ref = render::read_image(ref_path), img = render::read_image(img_path);
    if (ref.width != img.width || ref.height != img.height)
        throw std::invalid_argument("\"" + img_path + "\" is " + std::to_string(img.width) + "x" +
                                    std::to_string(img.height) + ", the reference is " +
                                    std::to_string(ref.width) + "x" + std::to_string(ref.height));
    auto rgb = [](const render::RawImage& r) {
        std::vector<float> v(static_cast<std::size_t>(r.width) * r.height * 3);
        for (std::size_t p = 0; p < v.size() / 3; ++p)
            for (int c = 0; c < 3; ++c) {
                float x = r.pixels[p * r.channels + std::min(c, r.channels - 1)];
                v[3 * p + c] = r.is_8bit ? texture::srgb_to_linear(x) : x;  // compare linear values
            }
        return v;
    };
    eval::ErrorStats s = eval::compare(rgb(ref), rgb(img));
    if (json)
        std::printf(
            "{\"reference\": \"%s\", \"image\": \"%s\", \"rmse\": %s, \"relative_rmse\": %s, "
            "\"psnr\": %s, \"pixels\": %zu}\n",
            json_escape(ref_path).c_str(), json_escape(img_path).c_str(),
            json_number(s.rmse).c_str(), json_number(s.relative_rmse).c_str(),
            json_number(s.psnr).c_str(), s.pixels);
    else
        std::printf("%s vs %s: RMSE %.6f (%.2f%% of the reference mean %.6f), PSNR %.2f dB\n",
                    img_path.c_str(), ref_path.c_str(), s.rmse, 100 * s.relative_rmse,
                    s.reference_mean, s.psnr);
    return 0;
}

struct EvalArgs {
    std::vector<std::string> scenes;
    std::string methods, spp = "1,4,16", out = "eval-out";
    int reference_spp = 1024, timing_runs = 1;
    bool quiet = false;
};

std::vector<std::string> split_list(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ','))
        if (!item.empty()) out.push_back(item);
    return out;
}

std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
    std::string out;
    for (const std::string& x : v) out += (out.empty() ? "" : sep) + x;
    return out;
}

// What a method name is, from the evaluation's own tables.
std::string method_syntax() {
    return "none, or SOURCE+FILTER with SOURCE one of " + join(eval::method_sources()) +
           " and FILTER one of " + join(eval::method_filters());
}

int run_eval(const EvalArgs& a) {
    eval::EvalOptions o;
    o.scenes = a.scenes;
    o.reference_spp = a.reference_spp;
    o.out_dir = a.out;
    for (const std::string& name :
         a.methods.empty() ? eval::default_methods() : split_list(a.methods)) {
        auto m = eval::parse_method(name);
        if (!m)
            throw std::invalid_argument("--methods: unknown method \"" + name + "\" (" +
                                        method_syntax() + ")");
        o.methods.push_back(*m);
    }
    o.spp.clear();
    for (const std::string& v : split_list(a.spp)) {
        char* end = nullptr;
        long n = std::strtol(v.c_str(), &end, 10);
        if (*end || n < 1)
            throw std::invalid_argument("--spp: \"" + v + "\" is not a positive integer");
        o.spp.push_back(static_cast<int>(n));
        note_spp_rounding(o.spp.back());
    }
    if (o.spp.empty()) throw std::invalid_argument("--spp: give at least one sample count");
    note_spp_rounding(a.reference_spp, "--reference-spp");
    o.timing_runs = a.timing_runs;
    ProgressBar bar(!a.quiet && ::isatty(STDERR_FILENO));
    o.progress = [&](int done, int total, const std::string&) { bar.update(done, total); };
    // Warnings and failures interrupt the progress bar on a line of their own.
    auto line = [&](const std::string& text) {
        if (!a.quiet && ::isatty(STDERR_FILENO)) std::fputs("\r\033[K", stderr);
        std::cerr << text << "\n";
    };
    o.warn = [&](const std::string& w) {
        line((w.rfind("warning: ", 0) == 0 ? "cmam: " : "") + w);
    };
    o.scene_failed = [&](const std::string& scene, const std::string& message) {
        line("cmam: error: " + pbrt::printable(scene + " is skipped: " + message));
    };
    auto t0 = std::chrono::steady_clock::now();
    eval::EvalResult r = eval::run_eval(o);
    if (!a.quiet) {
        int cached = 0;
        for (const auto& s : r.scenes) cached += s.reference_cached;
        std::fprintf(stderr,
                     "%s: %zu scenes (%d ground truths from the cache), %zu results, %.1fs; see "
                     "%s/index.html\n",
                     a.out.c_str(), r.scenes.size(), cached, r.rows.size(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                     a.out.c_str());
    }
    if (!r.failed.empty()) {
        std::fprintf(stderr, "cmam: error: %zu of %zu scenes failed (listed in %s/index.html)\n",
                     r.failed.size(), a.scenes.size(), a.out.c_str());
        return 1;
    }
    return 0;
}

int run_check(const std::string& path) {
    pbrt::SceneDesc desc = pbrt::parse_file(path, print_warning);
    auto scene = render::build_scene(desc, {}, print_warning);
    std::size_t tris = 0, quadrics = 0;
    for (const auto& p : scene->primitives) {
        if (p->kind == render::Primitive::Kind::Triangles)
            tris += p->indices.size() / 3;
        else
            ++quadrics;
    }
    std::printf(
        "%s: ok: %dx%d film, %d spp, %zu triangles, %zu quadrics, %zu lights, %zu materials, %zu "
        "textures\n",
        path.c_str(), scene->film.width(), scene->film.height(), scene->sampler.spp(), tris,
        quadrics, scene->lights.size(), scene->materials.size(), scene->textures.size());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"cmam: a texture-filtering Whitted ray tracer for pbrt-v3 scenes"};
    app.set_version_flag("--version", std::string("cmam ") + CMAM_VERSION);
    app.require_subcommand(1);

    RenderArgs ra;
    auto* render_cmd = app.add_subcommand("render", "Render a pbrt-v3 scene");
    render_cmd->add_option("scene", ra.scene, "Scene file (.pbrt)")->required();
    render_cmd->add_option("-o,--output", ra.output,
                           "Output image: .exr or .pfm (float, linear), .png, .jpg or .tga (8-bit "
                           "sRGB); default: the Film's filename");
    render_cmd
        ->add_option("--spp", ra.spp,
                     "Samples per pixel, rounded to a square grid (5 renders 2x2 = 4, with a "
                     "warning); 1 = the pixel centre")
        ->check(CLI::Range(1, 1 << 20));
    render_cmd->add_option("--threads", ra.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, 4096));
    render_cmd->add_flag("--quiet", ra.quiet, "No progress bar and no summary line");
    render_cmd->add_option("--resolution", ra.resolution,
                           "Film resolution WxH, or W alone to keep the scene's aspect ratio (a "
                           "quick preview of a big scene)");
    render_cmd->add_option("--crop", ra.crop,
                           "Render only X0,X1,Y0,Y1 of the image: the Film's cropwindow, fractions "
                           "of the width and height from the top left (replaces the scene's)");
    render_cmd->add_flag("--stats", ra.stats, "Print texture memory and lookup counts per filter");
    render_cmd->add_option(
        "--lod", ra.lod,
        "Footprint source for image textures: differentials (default, as pbrt-v3), cones, "
        "cones-aniso, cmam, or none (point sampling)");
    render_cmd->add_option(
        "--aov", ra.aov,
        "Write an AOV instead of radiance: footprint (major, minor axis in texels, MIP level; "
        ".exr or .pfm; with --lod cmam the region the CMAM built) or texture "
        "(unlit filtered texture of the first non-specular hit)");
    render_cmd->add_option(
        "--filter", ra.filter,
        "Filter for image textures: " + texture::filter_names() +
            " (default: the scene's; area is the exact mean over each sample's footprint)");
    render_cmd
        ->add_option("--cmam-miss", ra.cmam_miss, "CMAM, no matching sample: average or point")
        ->capture_default_str();
    render_cmd->add_option("--cmam-tags", ra.cmam_tags, "CMAM ray IDs: scanline or pixel")
        ->capture_default_str();
    render_cmd
        ->add_option("--cmam-ellipse", ra.cmam_ellipse,
                     "CMAM EWA reading of two vectors: conjugate, orthogonal or orthogonalised")
        ->capture_default_str();
    render_cmd
        ->add_option("--cmam-sat-miss", ra.cmam_sat_miss,
                     "CMAM SAT on a miss: average or paper-literal")
        ->capture_default_str();
    render_cmd
        ->add_option(
            "--cmam-adjacency", ra.cmam_adjacency,
            "CMAM accepts only adjacent samples: on, or off (the paper's literal matching)")
        ->capture_default_str();
    render_cmd->add_flag(
        "--cmam-2d", ra.cmam_2d,
        "2-D CMAM: also use the sample of the pixel above (scanline tags), an improvement "
        "beyond the paper");
    render_cmd->add_flag("--cmam-hull", ra.cmam_hull,
                         "CMAM convex hull weighting (paper section 4; pixel tags)");

    std::string check_path;
    auto* check_cmd =
        app.add_subcommand("check", "Parse and build a scene, report problems, render nothing");
    check_cmd->add_option("scene", check_path, "Scene file (.pbrt)")->required();

    LookupArgs la;
    auto* lookup_cmd =
        app.add_subcommand("lookup", "Filter one texture lookup and show what the filter did");
    lookup_cmd->add_option("image", la.image, "Texture image")->required();
    lookup_cmd->add_option("--uv", la.uv,
                           "Lookup point U,V (v = 0 is the bottom row, as in pbrt-v3)");
    auto* axes_opt =
        lookup_cmd->add_option("--axes", la.axes, "Footprint axes AU,AV,BU,BV in (u,v) units");
    lookup_cmd
        ->add_option("--points", la.points,
                     "Footprint sample points U1,V1[,U2,V2[,U3,V3]], current first")
        ->excludes(axes_opt);
    lookup_cmd->add_option("--filter", la.filter, texture::filter_names())->capture_default_str();
    lookup_cmd->add_option("--wrap", la.wrap, "repeat, clamp, black or mirror")
        ->capture_default_str();
    lookup_cmd->add_option("--maxaniso", la.max_aniso, "EWA maximum anisotropy")
        ->capture_default_str()
        ->check(CLI::Range(1.0, 1e6));
    lookup_cmd->add_flag("--json", la.json, "One JSON object on stdout");

    std::string cmp_ref, cmp_img;
    bool cmp_json = false;
    auto* compare_cmd =
        app.add_subcommand("compare", "Error of an image against a reference (linear RGB)");
    compare_cmd->add_option("reference", cmp_ref, "Reference image")->required();
    compare_cmd->add_option("image", cmp_img, "Image to measure")->required();
    compare_cmd->add_flag("--json", cmp_json, "One JSON object on stdout");

    EvalArgs ea;
    auto* eval_cmd = app.add_subcommand(
        "eval", "Compare footprint methods against a ground truth; write a report");
    eval_cmd->add_option("scenes", ea.scenes, "Scene files (.pbrt)")->required();
    eval_cmd->add_option("--methods", ea.methods,
                         "Comma-separated methods: " + method_syntax() +
                             ". Default: " + join(eval::default_methods(), ","));
    eval_cmd->add_option("--spp", ea.spp, "Comma-separated samples per pixel")
        ->capture_default_str();
    eval_cmd->add_option("--reference-spp", ea.reference_spp, "Ground-truth samples per pixel")
        ->capture_default_str()
        ->check(CLI::Range(1, 1 << 20));
    eval_cmd
        ->add_option("--timing-runs", ea.timing_runs,
                     "Renders timed per method and sample count; the report gives their median "
                     "and range (1: single runs, marked as such)")
        ->capture_default_str()
        ->check(CLI::Range(1, 100));
    eval_cmd
        ->add_option("-o,--output", ea.out,
                     "Output directory; a report already there is replaced (its own files only)")
        ->capture_default_str();
    eval_cmd->add_flag("--quiet", ea.quiet, "No progress bar and no summary line");

    app.failure_message([](const CLI::App* a, const CLI::Error& e) {
        return "cmam: error: " + std::string(e.what()) + "\nRun with " +
               (a->get_help_ptr() ? a->get_help_ptr()->get_name() : std::string("--help")) +
               " for more information.\n";
    });
    CLI11_PARSE(app, argc, argv);
    if (*lookup_cmd && la.uv.empty() && la.points.empty()) {
        std::cerr << "cmam: error: give --uv U,V (or --points)\n";
        return 2;
    }
    try {
        if (*render_cmd) return run_render(ra);
        if (*check_cmd) return run_check(check_path);
        if (*lookup_cmd) return run_lookup(la);
        if (*compare_cmd) return run_compare(cmp_ref, cmp_img, cmp_json);
        if (*eval_cmd) return run_eval(ea);
    } catch (const pbrt::SceneError& e) {
        // Located: "FILE:LINE:COL: error: ..."; otherwise "error: ...", printed as the others.
        std::cerr << (e.loc().file ? "" : "cmam: ") << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "cmam: error: " << pbrt::printable(e.what()) << "\n";
        return 1;
    }
    return 0;
}
