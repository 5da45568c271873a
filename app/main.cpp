// cmam — command-line front end: `cmam render`, `cmam check`.
// Libraries throw; this file is the only place that prints errors.
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <mutex>

#include "pbrt/parser.h"
#include "render/image_io.h"
#include "render/integrator.h"
#include "render/scene.h"

namespace {

using namespace cmam;

struct RenderArgs {
    std::string scene;
    std::string output;
    int spp = 0;
    int threads = 0;
    bool quiet = false;
};

void print_warning(const std::string& w) { std::cerr << w << "\n"; }

std::string format_duration(double s) {
    char buf[64];
    if (s < 60) std::snprintf(buf, sizeof buf, "%.1fs", s);
    else std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    return buf;
}

class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : m_enabled(enabled), m_start(std::chrono::steady_clock::now()) {}
    void update(int done, int total) {
        if (!m_enabled) return;
        std::lock_guard<std::mutex> lock(m_mutex);
        double frac = double(done) / total;
        int pct = int(frac * 100);
        if (pct == m_last && done != total) return;
        m_last = pct;
        double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
        double eta = frac > 0 ? el / frac - el : 0;
        constexpr int kWidth = 40;
        int fill = int(frac * kWidth);
        std::string bar(fill, '=');
        bar.resize(kWidth, ' ');
        std::fprintf(stderr, "\r[%s] %3d%%  elapsed %s  ETA %s   ", bar.c_str(), pct, format_duration(el).c_str(),
                     format_duration(eta).c_str());
        if (done == total) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

private:
    bool m_enabled;
    std::chrono::steady_clock::time_point m_start;
    std::mutex m_mutex;
    int m_last = -1;
};

int run_render(const RenderArgs& a) {
    auto t0 = std::chrono::steady_clock::now();
    pbrt::SceneDesc desc = pbrt::parse_file(a.scene, print_warning);
    render::BuildOptions bo;
    bo.spp_override = a.spp;
    auto scene = render::build_scene(desc, bo, print_warning);
    std::string out = a.output.empty() ? scene->film.filename : a.output;

    ProgressBar bar(!a.quiet && ::isatty(STDERR_FILENO));
    render::RenderOptions ro;
    ro.threads = a.threads;
    ro.progress = [&](int done, int total) { bar.update(done, total); };
    render::RenderStats stats;
    auto t1 = std::chrono::steady_clock::now();
    render::Framebuffer fb = render::render(*scene, ro, &stats);
    auto t2 = std::chrono::steady_clock::now();
    render::write_image(out, fb.width, fb.height, fb.rgb);
    double render_s = std::chrono::duration<double>(t2 - t1).count();
    double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!a.quiet) {
        uint64_t rays = stats.total_rays();
        std::fprintf(stderr, "%s: %dx%d, %d spp, wall %.3fs (render %.3fs), %llu rays, %.2f Mrays/s\n", out.c_str(),
                     fb.width, fb.height, scene->sampler.spp(), wall_s, render_s, (unsigned long long)rays,
                     render_s > 0 ? rays / render_s / 1e6 : 0.0);
    }
    return 0;
}

int run_check(const std::string& path) {
    pbrt::SceneDesc desc = pbrt::parse_file(path, print_warning);
    auto scene = render::build_scene(desc, {}, print_warning);
    std::size_t tris = 0, quadrics = 0;
    for (const auto& p : scene->primitives) {
        if (p->kind == render::Primitive::Kind::Triangles) tris += p->indices.size() / 3;
        else ++quadrics;
    }
    std::printf("%s: ok: %dx%d film, %d spp, %zu triangles, %zu quadrics, %zu lights, %zu materials, %zu textures\n",
                path.c_str(), scene->film.width(), scene->film.height(), scene->sampler.spp(), tris, quadrics,
                scene->lights.size(), scene->materials.size(), scene->textures.size());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"cmam: a texture-filtering Whitted ray tracer for pbrt-v3 scenes"};
    app.require_subcommand(1);

    RenderArgs ra;
    auto* render_cmd = app.add_subcommand("render", "Render a pbrt-v3 scene");
    render_cmd->add_option("scene", ra.scene, "Scene file (.pbrt)")->required();
    render_cmd->add_option("-o,--output", ra.output, "Output image (.exr, .pfm, .png); default: the Film's filename");
    render_cmd->add_option("--spp", ra.spp, "Samples per pixel (rounded to a square; 1 = pixel centre)")
        ->check(CLI::Range(1, 1 << 20));
    render_cmd->add_option("--threads", ra.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 4096));
    render_cmd->add_flag("--quiet", ra.quiet, "No progress bar and no summary line");

    std::string check_path;
    auto* check_cmd = app.add_subcommand("check", "Parse and build a scene, report problems, render nothing");
    check_cmd->add_option("scene", check_path, "Scene file (.pbrt)")->required();

    CLI11_PARSE(app, argc, argv);
    try {
        if (*render_cmd) return run_render(ra);
        if (*check_cmd) return run_check(check_path);
    } catch (const pbrt::SceneError& e) {
        std::cerr << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "cmam: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
