#include "eval/evaluation.h"

#include <cmam/texture/filter.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "eval/metrics.h"
#include "eval/report.h"
#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/footprint/method.h"
#include "render/image_io.h"
#include "render/integrator.h"

namespace cmam::eval {

namespace fs = std::filesystem;

const char* renderer_version() {
    return "cmam-0.1.0/eval-1";
}

namespace {

// The footprint sources of method names, "SOURCE+FILTER": a footprint method's name
// (render::kFootprintMethodNames) and a variant of its settings, "cmam-literal" say.
struct Source {
    render::FootprintMethod lod;
    const char* variant;
    void (*adjust)(render::BuildOptions&);  // may be null

    std::string name() const {
        return std::string(render::kFootprintMethodNames.name(lod)) + variant;
    }
};
const Source kSources[] = {
    {render::FootprintMethod::Differentials, "", nullptr},
    {render::FootprintMethod::Cones, "", nullptr},
    {render::FootprintMethod::ConesAniso, "", nullptr},
    // Paper mode: scanline tags, average on a miss, conjugate ellipse.
    {render::FootprintMethod::Cmam, "", nullptr},
    {render::FootprintMethod::Cmam, "-literal",
     [](render::BuildOptions& b) { b.cmam.adjacent_only = false; }},
    {render::FootprintMethod::Cmam, "-point",
     [](render::BuildOptions& b) { b.cmam.miss = texture::CmamMiss::Point; }},
    {render::FootprintMethod::Cmam, "-pixel-hull",
     [](render::BuildOptions& b) {
         b.tags = render::TagPolicy::Pixel;
         b.cmam.hull = true;
     }},
    {render::FootprintMethod::Cmam, "2d", [](render::BuildOptions& b) { b.cmam.two_d = true; }},
};

// The filters a method may end with: every filter but nearest (no footprint to filter).
std::optional<texture::FilterKind> parse_method_filter(std::string_view name) {
    auto f = texture::kFilterNames.parse(name);
    if (f == texture::FilterKind::Nearest) return std::nullopt;
    return f;
}

}  // namespace

std::vector<std::string> method_sources() {
    std::vector<std::string> out;
    for (const Source& s : kSources) out.push_back(s.name());
    return out;
}

std::vector<std::string> method_filters() {
    std::vector<std::string> out;
    for (const std::string& name : texture::kFilterNames.names())
        if (parse_method_filter(name)) out.push_back(name);
    return out;
}

std::optional<Method> parse_method(const std::string& name) {
    Method m;
    m.name = name;
    if (render::kFootprintMethodNames.parse(name) == render::FootprintMethod::None) {
        m.build.lod = render::FootprintMethod::None;
        return m;
    }
    auto plus = name.find('+');
    if (plus == std::string::npos) return std::nullopt;
    const std::string source = name.substr(0, plus);
    m.build.filter = parse_method_filter(std::string_view(name).substr(plus + 1));
    if (!m.build.filter) return std::nullopt;
    for (const Source& s : kSources)
        if (source == s.name()) {
            m.build.lod = s.lod;
            if (s.adjust) s.adjust(m.build);
            return m;
        }
    return std::nullopt;
}

std::vector<std::string> default_methods() {
    return {"none",
            "differentials+trilinear",
            "differentials+ewa",
            "differentials+area",
            "cones+trilinear",
            "cones-aniso+ewa",
            "cones-aniso+area",
            "cmam+trilinear",
            "cmam+sat",
            "cmam+ewa",
            "cmam-literal+trilinear",
            "cmam-point+trilinear",
            "cmam-pixel-hull+trilinear",
            "cmam2d+trilinear",
            "cmam2d+sat",
            "cmam2d+ewa",
            "cmam2d+area"};
}

namespace {

uint64_t fnv1a(uint64_t h, const std::string& bytes) {
    for (unsigned char c : bytes) {
        h ^= c;
        h *= 0x100000001b3ull;
    }
    return h;
}

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct Rendered {
    render::Framebuffer image;
    double seconds = 0;
    uint64_t rays = 0;
    bool path_traced = false;  // the scene's integrator
};

Rendered render_with(const pbrt::SceneDesc& desc, render::BuildOptions bo, int spp,
                     render::AovKind aov, const pbrt::WarningSink& warn) {
    bo.spp_override = spp;
    auto scene = render::build_scene(desc, bo, warn);
    render::RenderOptions ro;
    ro.aov = aov;
    ro.count_lookups = false;  // the timings measure the filters without the bookkeeping
    ro.pixel_filter = false;   // box-filtered pixels, the ground truth's (algorithms.md §9)
    render::RenderStats stats;
    auto t0 = std::chrono::steady_clock::now();
    Rendered r;
    r.image = render::render(*scene, ro, &stats);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.rays = stats.total_rays();
    r.path_traced = scene->path_tracing;
    return r;
}

std::vector<float> read_rgb(const std::string& path) {
    render::RawImage raw = render::read_image(path);
    std::vector<float> v(static_cast<std::size_t>(raw.width) * raw.height * 3);
    for (std::size_t p = 0; p < v.size() / 3; ++p)
        for (int c = 0; c < 3; ++c)
            v[3 * p + c] = raw.pixels[p * raw.channels + std::min(c, raw.channels - 1)];
    return v;
}

std::string safe_name(std::string s) {
    for (char& c : s)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.')
            c = '_';
    return s;
}

}  // namespace

std::string reference_key(const std::string& scene_path, int reference_spp) {
    return reference_key(pbrt::parse_file(scene_path), reference_spp);
}

std::string reference_key(const pbrt::SceneDesc& desc, int reference_spp) {
    uint64_t h = 0xcbf29ce484222325ull;
    h = fnv1a(h, renderer_version());
    h = fnv1a(h, std::to_string(reference_spp));
    // The film as rendered: a resolution or crop window given on the command line is not in the
    // files.
    std::string film =
        std::to_string(desc.film.params.get_int("xresolution", render::kDefaultFilmWidth)) + "x" +
        std::to_string(desc.film.params.get_int("yresolution", render::kDefaultFilmHeight));
    for (double c : desc.film.params.get_floats("cropwindow").value_or(std::vector<double>{})) {
        char buf[32];
        std::snprintf(buf, sizeof buf, ",%.17g", c);
        film += buf;
    }
    h = fnv1a(h, film);
    for (const std::string& src : desc.sources) h = fnv1a(h, read_file(src));
    // Every file a texture or a shape names (images, PLY meshes).
    auto add_files = [&](const pbrt::Entity& e) {
        if (const pbrt::Param* p = e.params.find("filename"))
            if (!p->strings.empty())
                h = fnv1a(h, read_file(pbrt::resolve_path(desc.base_dir, p->loc, p->strings[0])));
    };
    for (const auto& t : desc.textures) add_files(t.entity);
    for (const auto& s : desc.shapes) add_files(s.entity);
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

int rendered_spp(int spp) {
    const int k = std::max(1, static_cast<int>(std::lround(std::sqrt(double(spp)))));
    return k * k;
}

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n == 0 ? 0 : n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// Evaluates one scene: ground truth (cached), then every method at every sample count. Appends
// its rows and the files it wrote (relative to out_dir) to `result`; throws on failure.
class SceneEvaluation {
  public:
    SceneEvaluation(const EvalOptions& o, std::function<void(const std::string&)> step)
        : o(o), step(std::move(step)) {}

    SceneReport run(const std::string& scene_path) {
        SceneReport sr;
        sr.path = scene_path;
        sr.name = safe_name(fs::path(scene_path).stem().string());
        const pbrt::WarningSink warn = [&](const std::string& w) {
            if (std::find(sr.warnings.begin(), sr.warnings.end(), w) != sr.warnings.end()) return;
            sr.warnings.push_back(w);
            if (o.warn) o.warn(w);
        };
        pbrt::SceneDesc desc = pbrt::parse_file(scene_path, warn);
        if (o.adjust_scene) o.adjust_scene(desc, warn);
        fs::path dir = fs::path(o.out_dir) / sr.name;
        fs::create_directories(dir);
        const GroundTruth gt = ground_truth(sr, desc, warn);
        for (int spp : o.spp) {
            const OffEdges off = off_edges(sr, desc, gt, spp, warn);
            for (const Method& m : o.methods) evaluate(sr, desc, gt, off, m, spp, warn);
        }
        return sr;
    }

    std::vector<ResultRow> rows;     // of this scene
    std::vector<std::string> files;  // written for this scene

  private:
    // The ground truth's images (linear RGB) and the heat maps' scales.
    struct GroundTruth {
        render::BuildOptions options;
        std::vector<float> beauty, texture, untextured;
        double heat_scale = 0, texture_heat_scale = 0;
    };

    // The ground truth's files in the cache.
    struct CacheFiles {
        fs::path beauty, texture, untextured;
    };

    // The pixels off edges at one sample count, and their fraction of the image.
    struct OffEdges {
        std::vector<bool> mask;
        double fraction = 0;
    };

    // Ground truth: point-sampled textures (bilinear at level 0), jittered strata; cached.
    GroundTruth ground_truth(SceneReport& sr, const pbrt::SceneDesc& desc,
                             const pbrt::WarningSink& warn) {
        const std::string key = reference_key(desc, o.reference_spp);
        const fs::path cache = fs::path(o.out_dir) / "cache";
        const CacheFiles cached{cache / (sr.name + "-" + key + "-beauty.exr"),
                                cache / (sr.name + "-" + key + "-texture.exr"),
                                cache / (sr.name + "-" + key + "-untextured.exr")};
        GroundTruth gt;
        gt.options.lod = render::FootprintMethod::None;
        gt.options.filter = texture::FilterKind::Bilinear;
        sr.reference_spp = rendered_spp(o.reference_spp);
        sr.reference_cached = fs::exists(cached.beauty) && fs::exists(cached.texture) &&
                              fs::exists(cached.untextured);
        bool path_traced;
        if (!sr.reference_cached) {
            path_traced = warn_of_cost(sr, desc, gt.options, warn);
            render_ground_truth(sr.name, desc, gt.options, cached, warn);
        } else {
            // The warnings of building, which a cached ground truth did not show.
            path_traced = render::build_scene(desc, gt.options, warn)->path_tracing;
            for (int k = 0; k < 3; ++k) step(sr.name + ": ground truth (cached)");
        }
        // A path tracer's noise at the methods' sample counts is far above what the filters
        // change in the image; the unlit texture AOV is what compares them there.
        if (path_traced)
            warn("warning: " + sr.path +
                 ": the scene is path traced, so its images carry the path tracer's noise at "
                 "every sample count, and so does the off-edge mask; the texture RMSE (the unlit "
                 "texture, the same for any integrator) compares the filters");
        gt.beauty = read_rgb(cached.beauty.string());
        gt.texture = read_rgb(cached.texture.string());
        gt.untextured = read_rgb(cached.untextured.string());
        render::RawImage dims = render::read_image(cached.beauty.string());
        sr.width = dims.width;
        sr.height = dims.height;
        sr.reference_image = sr.name + "/reference.png";
        sr.reference_texture = sr.name + "/reference-texture.png";
        write_png(sr.reference_image, sr.width, sr.height, to_srgb8(gt.beauty));
        write_png(sr.reference_texture, sr.width, sr.height, to_srgb8(gt.texture));
        gt.heat_scale = std::max(1e-3, compare(gt.beauty, gt.beauty).reference_mean);
        gt.texture_heat_scale = std::max(1e-3, compare(gt.texture, gt.texture).reference_mean);
        return gt;
    }

    // A ground truth that will take long (a large film, many light samples) is announced before
    // it starts, with what shortens it: its three renders take about three times the image's,
    // which is its render at one sample per pixel times the samples (measured here, at a
    // thousandth of the cost).
    // Returns whether the scene is path traced.
    bool warn_of_cost(const SceneReport& sr, const pbrt::SceneDesc& desc,
                      const render::BuildOptions& gt_opts, const pbrt::WarningSink& warn) const {
        const Rendered one = render_with(desc, gt_opts, 1, render::AovKind::None, warn);
        const double estimate = 3 * one.seconds * sr.reference_spp;
        if (estimate < o.long_ground_truth) return one.path_traced;
        char span[32], text[400];
        if (estimate >= 7200)
            std::snprintf(span, sizeof span, "%.1f h", estimate / 3600);
        else
            std::snprintf(span, sizeof span, "%.0f min", std::max(1.0, estimate / 60));
        std::snprintf(text, sizeof text,
                      "warning: %s: its ground truth at %d samples per pixel will take about %s "
                      "(%.2f s at 1 spp); --reference-spp, --resolution or --crop make it shorter",
                      sr.path.c_str(), sr.reference_spp, span, one.seconds);
        warn(text);
        return one.path_traced;
    }

    // Renders the ground truth's image, texture AOV and untextured image into the cache.
    void render_ground_truth(const std::string& name, const pbrt::SceneDesc& desc,
                             const render::BuildOptions& gt_opts, const CacheFiles& cached,
                             const pbrt::WarningSink& warn) {
        Rendered b = render_with(desc, gt_opts, o.reference_spp, render::AovKind::None, warn);
        render::write_image(cached.beauty.string(), b.image.width, b.image.height, b.image.rgb);
        step(name + ": ground truth");
        Rendered t = render_with(desc, gt_opts, o.reference_spp, render::AovKind::Texture, warn);
        render::write_image(cached.texture.string(), t.image.width, t.image.height, t.image.rgb);
        step(name + ": ground truth texture");
        render::BuildOptions un = gt_opts;
        un.untextured = true;
        Rendered u = render_with(desc, un, o.reference_spp, render::AovKind::None, warn);
        render::write_image(cached.untextured.string(), u.image.width, u.image.height, u.image.rgb);
        step(name + ": untextured ground truth");
    }

    // The pixels where an untextured render at `spp` agrees with the untextured ground truth.
    OffEdges off_edges(SceneReport& sr, const pbrt::SceneDesc& desc, const GroundTruth& gt, int spp,
                       const pbrt::WarningSink& warn) {
        render::BuildOptions un = gt.options;
        un.untextured = true;
        Rendered u = render_with(desc, un, spp, render::AovKind::None, warn);
        step(sr.name + ": untextured at " + std::to_string(spp) + " spp");
        OffEdges off;
        off.mask = edge_mask(gt.untextured, u.image.rgb);
        double kept = 0;
        for (bool b : off.mask) kept += b;
        off.fraction = kept / off.mask.size();
        sr.off_edge_fraction.emplace_back(spp, off.fraction);
        return off;
    }

    // One method at one sample count: its timed renders, texture AOV, metrics and images.
    void evaluate(const SceneReport& sr, const pbrt::SceneDesc& desc, const GroundTruth& gt,
                  const OffEdges& off, const Method& m, int spp, const pbrt::WarningSink& warn) {
        Rendered b;
        std::vector<double> seconds;
        for (int run = 0; run < std::max(1, o.timing_runs); ++run) {
            b = render_with(desc, m.build, spp, render::AovKind::None, warn);
            seconds.push_back(b.seconds);
            step(sr.name + ": " + m.name + " at " + std::to_string(spp) + " spp");
        }
        Rendered t = render_with(desc, m.build, spp, render::AovKind::Texture, warn);
        step(sr.name + ": " + m.name + " texture at " + std::to_string(spp) + " spp");
        ResultRow row = measure(sr, gt, off, b.image.rgb, t.image.rgb);
        row.method = m.name;
        row.spp = spp;
        row.seconds = median(seconds);
        row.seconds_min = *std::min_element(seconds.begin(), seconds.end());
        row.seconds_max = *std::max_element(seconds.begin(), seconds.end());
        row.timing_runs = static_cast<int>(seconds.size());
        row.rays_per_second = row.seconds > 0 ? b.rays / row.seconds : 0;
        std::string base = safe_name(m.name) + "-spp" + std::to_string(spp);
        row.image = sr.name + "/" + base + ".png";
        row.heatmap = sr.name + "/" + base + "-error.png";
        row.texture_heatmap = sr.name + "/" + base + "-texture-error.png";
        write_png(row.image, sr.width, sr.height, to_srgb8(b.image.rgb));
        write_png(row.heatmap, sr.width, sr.height,
                  error_heatmap(gt.beauty, b.image.rgb, gt.heat_scale));
        write_png(row.texture_heatmap, sr.width, sr.height,
                  error_heatmap(gt.texture, t.image.rgb, gt.texture_heat_scale));
        rows.push_back(row);
    }

    // The error metrics of an image and its texture AOV against the ground truth.
    static ResultRow measure(const SceneReport& sr, const GroundTruth& gt, const OffEdges& off,
                             const std::vector<float>& image, const std::vector<float>& texture) {
        ResultRow row;
        row.scene = sr.name;
        ErrorStats full = compare(gt.beauty, image), masked = compare(gt.beauty, image, &off.mask);
        row.rmse = full.rmse;
        row.psnr = full.psnr;
        row.ssim = ssim(gt.beauty, image, sr.width, sr.height);
        row.rmse_masked = masked.rmse;
        row.psnr_masked = masked.psnr;
        row.ssim_masked = ssim(gt.beauty, image, sr.width, sr.height, &off.mask);
        row.masked_fraction = off.fraction;
        ErrorStats tex = compare(gt.texture, texture);
        row.texture_rmse = tex.rmse;
        row.texture_psnr = tex.psnr;
        return row;
    }

    void write_png(const std::string& rel, int w, int h, const std::vector<unsigned char>& rgb) {
        render::write_png8((fs::path(o.out_dir) / rel).string(), w, h, rgb);
        files.push_back(rel);
    }

    const EvalOptions& o;
    std::function<void(const std::string&)> step;
};

}  // namespace

EvalResult run_eval(const EvalOptions& o) {
    EvalResult result;
    fs::create_directories(fs::path(o.out_dir) / "cache");
    const int per_scene =
        3 + static_cast<int>(o.spp.size()) *
                (1 + (std::max(1, o.timing_runs) + 1) * static_cast<int>(o.methods.size()));
    const int total = per_scene * static_cast<int>(o.scenes.size());
    int done = 0;
    for (const std::string& scene_path : o.scenes) {
        const int done_before = done;
        SceneEvaluation ev(o, [&](const std::string& what) {
            ++done;
            if (o.progress) o.progress(done, total, what);
        });
        try {
            SceneReport sr = ev.run(scene_path);
            result.rows.insert(result.rows.end(), ev.rows.begin(), ev.rows.end());
            result.files.insert(result.files.end(), ev.files.begin(), ev.files.end());
            result.scenes.push_back(sr);
        } catch (const std::exception& e) {
            // Skipped: its images go, the other scenes go on.
            std::error_code ec;
            for (const std::string& f : ev.files) fs::remove(fs::path(o.out_dir) / f, ec);
            const fs::path scene_dir =
                fs::path(o.out_dir) / safe_name(fs::path(scene_path).stem().string());
            if (fs::is_empty(scene_dir, ec)) fs::remove(scene_dir, ec);
            result.failed.push_back({scene_path, e.what()});
            if (o.scene_failed) o.scene_failed(scene_path, e.what());
            done = done_before + per_scene;
            if (o.progress) o.progress(done, total, scene_path + ": failed");
        }
    }
    write_reports(o, result);
    return result;
}

}  // namespace cmam::eval
