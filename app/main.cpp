// cmam — command-line front end: `cmam render`, `cmam check`, `cmam lookup`, `cmam compare`,
// `cmam eval`.
// Libraries throw; the app/ files are the only place that prints errors.
#include <cmam/texture/cmam.h>
#include <cmam/texture/ewa.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "app/common.h"
#include "app/eval_command.h"
#include "app/render_command.h"
#include "eval/evaluation.h"
#include "eval/metrics.h"
#include "pbrt/parser.h"
#include "render/image_io.h"
#include "render/scene.h"

namespace {

using namespace cmam;
using namespace cmam::app;

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
    const auto [v, info] = tex.lookup_with_info(uv[0], uv[1], fp, {*kind, a.max_aniso});
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
            out += ", \"rectangle_texels\": [" + num(info.rect.lo.u) + ", " + num(info.rect.lo.v) +
                   ", " + num(info.rect.hi.u) + ", " + num(info.rect.hi.v) + "]";
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
        std::printf("footprint: rectangle [%.4f, %.4f] x [%.4f, %.4f] texels\n", info.rect.lo.u,
                    info.rect.hi.u, info.rect.lo.v, info.rect.hi.v);
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

int run_check(const std::string& path) {
    pbrt::SceneDesc desc = pbrt::parse_file(path, print_warning);
    auto scene = render::build_scene(desc, {}, print_warning);
    // Triangles and quadrics as rendered: an object's count once per instance.
    auto count = [](const std::vector<std::unique_ptr<render::Primitive>>& prims, std::size_t times,
                    std::size_t* tris, std::size_t* quadrics) {
        for (const auto& p : prims) {
            if (p->kind == render::Primitive::Kind::Triangles)
                *tris += times * (p->indices.size() / 3);
            else
                *quadrics += times;
        }
    };
    std::size_t tris = 0, quadrics = 0;
    count(scene->primitives, 1, &tris, &quadrics);
    for (const auto& in : scene->instances)
        count(scene->objects[in.object].primitives, 1, &tris, &quadrics);
    std::string instances;
    if (!scene->instances.empty())
        instances = " (" + std::to_string(scene->instances.size()) + " instances of " +
                    std::to_string(scene->objects.size()) +
                    (scene->objects.size() == 1 ? " object)" : " objects)");
    std::printf(
        "%s: ok: %dx%d film, %d spp, %zu triangles, %zu quadrics%s, %zu lights, %zu materials, "
        "%zu textures\n",
        path.c_str(), scene->film.width(), scene->film.height(), scene->sampler.spp(), tris,
        quadrics, instances.c_str(), scene->lights.size(), scene->materials.size(),
        scene->textures.size());
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
    render_cmd->add_option("--max-memory", ra.max_memory,
                           "Refuse, before rendering, a render that would take the process over "
                           "this size (8G, 512M; default: the machine's memory)");
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
    } catch (const std::bad_alloc&) {
        std::cerr << "cmam: error: out of memory (the scene, its textures or the film need more "
                     "than this machine or process may use)\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "cmam: error: " << pbrt::printable(e.what()) << "\n";
        return 1;
    }
    return 0;
}
