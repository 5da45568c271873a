#include "eval/evaluation.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "eval/metrics.h"
#include "eval/report.h"
#include "pbrt/parser.h"
#include "render/image_io.h"
#include "render/integrator.h"

namespace cmam::eval {

namespace fs = std::filesystem;

const char* renderer_version() {
    return "cmam-0.1.0/eval-1";
}

std::optional<Method> parse_method(const std::string& name) {
    Method m;
    m.name = name;
    if (name == "none") {
        m.build.lod = render::Lod::None;
        return m;
    }
    auto plus = name.find('+');
    if (plus == std::string::npos) return std::nullopt;
    std::string source = name.substr(0, plus), filter = name.substr(plus + 1);
    auto f = texture::parse_filter(filter);
    if (!f || *f == texture::FilterKind::Nearest) return std::nullopt;
    m.build.filter = *f;
    if (source == "differentials")
        m.build.lod = render::Lod::Differentials;
    else if (source == "cones")
        m.build.lod = render::Lod::Cones;
    else if (source == "cones-aniso")
        m.build.lod = render::Lod::ConesAniso;
    else if (source.rfind("cmam", 0) == 0) {
        m.build.lod = render::Lod::Cmam;
        if (source == "cmam-literal")
            m.build.cmam.adjacent_only = false;
        else if (source == "cmam-point")
            m.build.cmam.miss = texture::CmamMiss::Point;
        else if (source == "cmam2d")
            m.build.cmam.two_d = true;
        else if (source == "cmam-pixel-hull") {
            m.build.tags = render::TagPolicy::Pixel;
            m.build.cmam.hull = true;
        } else if (source != "cmam")
            return std::nullopt;
    } else {
        return std::nullopt;
    }
    return m;
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
};

Rendered render_with(const pbrt::SceneDesc& desc, render::BuildOptions bo, int spp,
                     render::AovKind aov) {
    bo.spp_override = spp;
    auto scene = render::build_scene(desc, bo, {});
    render::RenderOptions ro;
    ro.aov = aov;
    render::RenderStats stats;
    auto t0 = std::chrono::steady_clock::now();
    Rendered r;
    r.image = render::render(*scene, ro, &stats);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.rays = stats.total_rays();
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
    pbrt::SceneDesc desc = pbrt::parse_file(scene_path);
    uint64_t h = 0xcbf29ce484222325ull;
    h = fnv1a(h, renderer_version());
    h = fnv1a(h, std::to_string(reference_spp));
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

EvalResult run_eval(const EvalOptions& o) {
    EvalResult result;
    fs::create_directories(fs::path(o.out_dir) / "cache");
    const int per_scene =
        3 + static_cast<int>(o.spp.size()) * (1 + 2 * static_cast<int>(o.methods.size()));
    const int total = per_scene * static_cast<int>(o.scenes.size());
    int done = 0;
    auto step = [&](const std::string& what) {
        ++done;
        if (o.progress) o.progress(done, total, what);
    };
    for (const std::string& scene_path : o.scenes) {
        pbrt::SceneDesc desc = pbrt::parse_file(scene_path);
        SceneReport sr;
        sr.name = safe_name(fs::path(scene_path).stem().string());
        fs::path dir = fs::path(o.out_dir) / sr.name;
        fs::create_directories(dir);
        // Ground truth: point-sampled textures (bilinear at level 0), jittered strata; cached.
        const std::string key = reference_key(scene_path, o.reference_spp);
        fs::path cache = fs::path(o.out_dir) / "cache";
        fs::path gt_beauty = cache / (sr.name + "-" + key + "-beauty.exr");
        fs::path gt_texture = cache / (sr.name + "-" + key + "-texture.exr");
        fs::path gt_untextured = cache / (sr.name + "-" + key + "-untextured.exr");
        render::BuildOptions gt_opts;
        gt_opts.lod = render::Lod::None;
        gt_opts.filter = texture::FilterKind::Bilinear;
        sr.reference_cached =
            fs::exists(gt_beauty) && fs::exists(gt_texture) && fs::exists(gt_untextured);
        if (!sr.reference_cached) {
            Rendered b = render_with(desc, gt_opts, o.reference_spp, render::AovKind::None);
            render::write_image(gt_beauty.string(), b.image.width, b.image.height, b.image.rgb);
            step(sr.name + ": ground truth");
            Rendered t = render_with(desc, gt_opts, o.reference_spp, render::AovKind::Texture);
            render::write_image(gt_texture.string(), t.image.width, t.image.height, t.image.rgb);
            step(sr.name + ": ground truth texture");
            render::BuildOptions un = gt_opts;
            un.untextured = true;
            Rendered u = render_with(desc, un, o.reference_spp, render::AovKind::None);
            render::write_image(gt_untextured.string(), u.image.width, u.image.height, u.image.rgb);
            step(sr.name + ": untextured ground truth");
        } else {
            done += 3;
            if (o.progress) o.progress(done, total, sr.name + ": ground truth (cached)");
        }
        const std::vector<float> ref = read_rgb(gt_beauty.string()),
                                 ref_tex = read_rgb(gt_texture.string()),
                                 ref_un = read_rgb(gt_untextured.string());
        render::RawImage dims = render::read_image(gt_beauty.string());
        sr.width = dims.width;
        sr.height = dims.height;
        sr.reference_image = sr.name + "/reference.png";
        render::write_png8((fs::path(o.out_dir) / sr.reference_image).string(), sr.width, sr.height,
                           to_srgb8(ref));
        double ref_mean = compare(ref, ref).reference_mean;
        const double heat_scale = std::max(1e-3, ref_mean);
        for (int spp : o.spp) {
            render::BuildOptions un = gt_opts;
            un.untextured = true;
            Rendered u = render_with(desc, un, spp, render::AovKind::None);
            step(sr.name + ": untextured at " + std::to_string(spp) + " spp");
            std::vector<bool> mask = edge_mask(ref_un, u.image.rgb);
            double kept = 0;
            for (bool b : mask) kept += b;
            for (const Method& m : o.methods) {
                Rendered b = render_with(desc, m.build, spp, render::AovKind::None);
                step(sr.name + ": " + m.name + " at " + std::to_string(spp) + " spp");
                Rendered t = render_with(desc, m.build, spp, render::AovKind::Texture);
                step(sr.name + ": " + m.name + " texture at " + std::to_string(spp) + " spp");
                ResultRow row;
                row.scene = sr.name;
                row.method = m.name;
                row.spp = spp;
                ErrorStats full = compare(ref, b.image.rgb),
                           masked = compare(ref, b.image.rgb, &mask);
                row.rmse = full.rmse;
                row.psnr = full.psnr;
                row.ssim = ssim(ref, b.image.rgb, sr.width, sr.height);
                row.rmse_masked = masked.rmse;
                row.psnr_masked = masked.psnr;
                row.ssim_masked = ssim(ref, b.image.rgb, sr.width, sr.height, &mask);
                row.masked_fraction = kept / mask.size();
                ErrorStats tex = compare(ref_tex, t.image.rgb);
                row.texture_rmse = tex.rmse;
                row.texture_psnr = tex.psnr;
                row.seconds = b.seconds;
                row.rays_per_second = b.seconds > 0 ? b.rays / b.seconds : 0;
                std::string base = safe_name(m.name) + "-spp" + std::to_string(spp);
                row.image = sr.name + "/" + base + ".png";
                row.heatmap = sr.name + "/" + base + "-error.png";
                render::write_png8((fs::path(o.out_dir) / row.image).string(), sr.width, sr.height,
                                   to_srgb8(b.image.rgb));
                render::write_png8((fs::path(o.out_dir) / row.heatmap).string(), sr.width,
                                   sr.height, error_heatmap(ref, b.image.rgb, heat_scale));
                result.rows.push_back(row);
            }
        }
        result.scenes.push_back(sr);
    }
    write_reports(o, result);
    return result;
}

}  // namespace cmam::eval
