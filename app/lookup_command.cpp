// cmam lookup: one filtered texture lookup, and what the filter did (levels, texels read, the
// footprint's region in texels), as text or as one JSON object.
#include <cmam/texture/cmam.h>
#include <cmam/texture/ewa.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "app/command.h"
#include "app/common.h"
#include "render/image_io.h"

namespace cmam::app {

namespace {

struct LookupArgs {
    std::string image, uv, axes, points;
    texture::FilterKind filter = texture::FilterKind::Ewa;
    texture::WrapMode wrap = texture::WrapMode::Repeat;
    double max_aniso = 8;
    bool json = false;
};

// Where the lookup is, and its footprint.
struct LookupAt {
    double u = 0, v = 0;
    texture::Footprint footprint;
};

// --uv, and --axes or --points (whose first pair is the lookup point).
LookupAt lookup_point(const LookupArgs& a) {
    LookupAt at;
    std::vector<double> uv;
    if (!a.uv.empty() || a.points.empty()) uv = parse_numbers(a.uv, "--uv");
    if (a.points.empty() && uv.size() != 2) throw UsageError("--uv needs two numbers: U,V");
    if (!a.axes.empty()) {
        auto ax = parse_numbers(a.axes, "--axes");
        if (ax.size() != 4) throw UsageError("--axes needs four numbers: AU,AV,BU,BV");
        at.footprint = texture::Footprint::axes({ax[0], ax[1]}, {ax[2], ax[3]});
    } else if (!a.points.empty()) {
        auto pt = parse_numbers(a.points, "--points");
        if (pt.size() % 2 != 0 || pt.size() < 2 || pt.size() > 6)
            throw UsageError("--points needs one to three U,V pairs (the current sample first)");
        texture::Footprint& fp = at.footprint;
        fp.kind = texture::Footprint::Kind::Points;
        fp.point_count = static_cast<int>(pt.size() / 2);
        for (int i = 0; i < fp.point_count; ++i) fp.points[i] = {pt[2 * i], pt[2 * i + 1]};
        uv = {pt[0], pt[1]};
    }
    at.u = uv[0];
    at.v = uv[1];
    return at;
}

// What one lookup returned and read.
struct LookupReport {
    texture::FilterKind kind;
    LookupAt at;
    texture::Texel value;
    texture::LookupInfo info;
    bool region;  // the filter read a footprint's region (not a point, not the fallback)
};

void print_json(const std::string& image_path, const texture::Image& img, const LookupReport& r) {
    const auto num = json_number;
    const texture::LookupInfo& info = r.info;
    const texture::Texel& v = r.value;
    std::string out = "{\"image\": \"" + json_escape(image_path) +
                      "\", \"width\": " + std::to_string(img.width()) +
                      ", \"height\": " + std::to_string(img.height()) + ", \"filter\": \"" +
                      std::string(texture::to_string(r.kind)) + "\", \"uv\": [" + num(r.at.u) +
                      ", " + num(r.at.v) + "], \"value\": [" + num(v[0]) + ", " + num(v[1]) + ", " +
                      num(v[2]) + "], \"levels\": [" + std::to_string(info.level_lo) + ", " +
                      std::to_string(info.level_hi) + "], \"lambda\": " + num(info.lambda) +
                      ", \"texels_read\": " + std::to_string(info.texels_read) +
                      ", \"fallback\": " + (info.fallback ? "true" : "false");
    if (r.region && r.kind == texture::FilterKind::Sat)
        out += ", \"rectangle_texels\": [" + num(info.rect.lo.u) + ", " + num(info.rect.lo.v) +
               ", " + num(info.rect.hi.u) + ", " + num(info.rect.hi.v) + "]";
    if (r.region && r.kind == texture::FilterKind::Ewa)
        out += ", \"ellipse_texels\": {\"major\": " + num(info.major) +
               ", \"minor\": " + num(info.minor) + "}";
    if (r.region && r.kind == texture::FilterKind::Trilinear)
        out += ", \"width_texels\": " + num(info.width);
    if (r.region && r.kind == texture::FilterKind::Area)
        out += ", \"region_texels\": {\"shape\": \"" +
               std::string(info.major > 0 ? "parallelogram" : "triangle") +
               "\", \"major\": " + num(info.major) + ", \"minor\": " + num(info.minor) +
               ", \"area\": " + num(info.area) + "}";
    std::printf("%s}\n", out.c_str());
}

void print_text(const LookupReport& r) {
    const texture::LookupInfo& info = r.info;
    std::printf("value (linear RGB): %.6f %.6f %.6f\n", r.value[0], r.value[1], r.value[2]);
    std::printf("filter: %s, MIP levels %d..%d (lambda %.4f), texels read: %d%s\n",
                std::string(texture::to_string(r.kind)).c_str(), info.level_lo, info.level_hi,
                info.lambda, info.texels_read,
                info.fallback ? " (non-finite input: texture mean)" : "");
    if (!r.region)
        std::printf("footprint: none (bilinear at level 0)\n");
    else if (r.kind == texture::FilterKind::Sat)
        std::printf("footprint: rectangle [%.4f, %.4f] x [%.4f, %.4f] texels\n", info.rect.lo.u,
                    info.rect.hi.u, info.rect.lo.v, info.rect.hi.v);
    else if (r.kind == texture::FilterKind::Ewa)
        std::printf("footprint: ellipse, axes %.4f and %.4f texels (after the anisotropy clamp)\n",
                    info.major, info.minor);
    else if (r.kind == texture::FilterKind::Area && info.major > 0)
        std::printf(
            "footprint: parallelogram, sides %.4f and %.4f texels (with the reconstruction "
            "term), area %.4f texels^2, integrated on level %d\n",
            info.major, info.minor, info.area, info.level_lo);
    else if (r.kind == texture::FilterKind::Area)
        std::printf(
            "footprint: the samples' triangle, area %.4f texels^2, integrated on level %d\n",
            info.area, info.level_lo);
    else
        std::printf("footprint: width %.4f texels\n", info.width);
}

int run_lookup(const LookupArgs& a) {
    LookupReport r{a.filter, lookup_point(a), {}, {}, false};
    if (r.kind == texture::FilterKind::Ewa && a.max_aniso > texture::kEwaMaxAnisotropy)
        std::cerr << "cmam: warning: --maxaniso " << a.max_aniso << " is above cmam's limit of "
                  << texture::kEwaMaxAnisotropy << ", which is used instead\n";
    texture::FilteredTexture tex(render::load_texture(a.image, false, std::nullopt, 1.0f, a.wrap));
    const texture::LookupResult looked =
        tex.lookup_with_info(r.at.u, r.at.v, r.at.footprint, {r.kind, a.max_aniso});
    r.value = looked.value;
    r.info = looked.info;
    r.region = r.at.footprint.kind != texture::Footprint::Kind::None &&
               r.kind != texture::FilterKind::Nearest && r.kind != texture::FilterKind::Bilinear &&
               !r.info.fallback;
    if (a.json)
        print_json(a.image, tex.image(), r);
    else
        print_text(r);
    return 0;
}

void add_lookup_options(CLI::App& cmd, LookupArgs& a) {
    cmd.add_option("image", a.image, "Texture image")->required();
    cmd.add_option("--uv", a.uv, "Lookup point U,V (v = 0 is the bottom row, as in pbrt-v3)");
    auto* axes = cmd.add_option("--axes", a.axes, "Footprint axes AU,AV,BU,BV in (u,v) units");
    cmd.add_option("--points", a.points,
                   "Footprint sample points U1,V1[,U2,V2[,U3,V3]], current first")
        ->excludes(axes);
    add_choice(cmd, "--filter", a.filter, texture::kFilterNames,
               "Filter: " + texture::kFilterNames.list());
    add_choice(cmd, "--wrap", a.wrap, texture::kWrapModeNames,
               "Wrap mode: " + texture::kWrapModeNames.list());
    cmd.add_option("--maxaniso", a.max_aniso, "EWA maximum anisotropy")
        ->capture_default_str()
        ->check(CLI::Range(1.0, 1e6));
    cmd.add_flag("--json", a.json, "One JSON object on stdout");
    // Without a point there is nothing to look up: a usage error, exit code 2.
    cmd.callback([&a] {
        if (a.uv.empty() && a.points.empty())
            throw CLI::ValidationError("give --uv U,V (or --points)", 2);
    });
}

}  // namespace

Command add_lookup_command(CLI::App& app) {
    return make_command(app, "lookup", "Filter one texture lookup and show what the filter did",
                        add_lookup_options, run_lookup);
}

}  // namespace cmam::app
