// cmam eval: every footprint method against a ground truth, and the report.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "app/command.h"
#include "app/common.h"
#include "app/film_overrides.h"
#include "eval/evaluation.h"
#include "pbrt/error.h"
#include "render/scene.h"

namespace cmam::app {

namespace {

struct EvalArgs {
    std::vector<std::string> scenes;
    std::optional<std::string> methods;  // given, even empty: the list; not given: the defaults
    std::string spp = "1,4,16", out = "eval-out";
    int reference_spp = 1024, timing_runs = 1;
    bool quiet = false;
    std::string resolution, crop;  // empty: each scene's film
};

// What a method name is, from the evaluation's own tables (for --help and errors).
std::string method_syntax() {
    return "none, or SOURCE+FILTER with SOURCE one of " + join(eval::method_sources()) +
           " and FILTER one of " + join(eval::method_filters());
}

// The evaluation's options from the command line's: methods and sample counts checked.
eval::EvalOptions eval_options(const EvalArgs& a) {
    eval::EvalOptions o;
    o.scenes = a.scenes;
    o.reference_spp = a.reference_spp;
    o.out_dir = a.out;
    for (const std::string& name : a.methods ? split_list(*a.methods) : eval::default_methods()) {
        auto m = eval::parse_method(name);
        if (!m)
            throw UsageError("--methods: unknown method \"" + name + "\" (" + method_syntax() +
                             ")");
        o.methods.push_back(*m);
    }
    if (o.methods.empty()) throw UsageError("--methods: give at least one method");
    o.spp.clear();
    for (const std::string& v : split_list(a.spp)) {
        char* end = nullptr;
        errno = 0;
        long n = std::strtol(v.c_str(), &end, 10);
        if (*end || n < 1 || errno == ERANGE)
            throw UsageError("--spp: \"" + v + "\" is not a positive integer");
        if (n > render::kMaxSamplesPerPixel)  // an int would wrap 4294967297 to 1
            throw UsageError("--spp " + v + " is above cmam's limit of " +
                             std::to_string(render::kMaxSamplesPerPixel) + " samples per pixel");
        o.spp.push_back(static_cast<int>(n));
        note_spp_rounding(o.spp.back());
    }
    if (o.spp.empty()) throw UsageError("--spp: give at least one sample count");
    note_spp_rounding(a.reference_spp, "--reference-spp");
    o.timing_runs = a.timing_runs;
    // Checked here, before any scene is read; applied to each scene as it is.
    const FilmOverrides film(a.resolution, a.crop);
    if (!film.empty())
        o.adjust_scene = [film](pbrt::SceneDesc& desc, const pbrt::WarningSink& warn) {
            film.apply(desc, warn);
        };
    return o;
}

int run_eval(const EvalArgs& a) {
    eval::EvalOptions o = eval_options(a);
    {
        std::error_code ec;
        if (std::filesystem::exists(a.out, ec) && !std::filesystem::is_directory(a.out, ec))
            throw UsageError("-o " + a.out + ": it is a file, not a folder for the report");
    }
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

void add_eval_options(CLI::App& cmd, EvalArgs& a) {
    cmd.add_option("scenes", a.scenes, "Scene files (.pbrt)")->required();
    cmd.add_option("--methods", a.methods,
                   "Comma-separated methods: " + method_syntax() +
                       ". Default: " + join(eval::default_methods(), ","));
    cmd.add_option("--spp", a.spp, "Comma-separated samples per pixel")->capture_default_str();
    cmd.add_option("--reference-spp", a.reference_spp, "Ground-truth samples per pixel")
        ->capture_default_str()
        ->check(CLI::Range(1, 1 << 20));
    cmd.add_option("--timing-runs", a.timing_runs,
                   "Renders timed per method and sample count; the report gives their median "
                   "and range (1: single runs, marked as such)")
        ->capture_default_str()
        ->check(CLI::Range(1, 100));
    cmd.add_option("--resolution", a.resolution,
                   "Film resolution WxH, or W alone to keep each scene's aspect ratio, for the "
                   "ground truth and every method (a quicker evaluation of a big scene)");
    cmd.add_option("--crop", a.crop,
                   "Evaluate only X0,X1,Y0,Y1 of each image: the Film's cropwindow, fractions of "
                   "the width and height from the top left (replaces the scene's)");
    cmd.add_option("-o,--output", a.out,
                   "Output directory; a report already there is replaced (its own files only)")
        ->capture_default_str();
    cmd.add_flag("--quiet", a.quiet, "No progress bar and no summary line");
}

}  // namespace

Command add_eval_command(CLI::App& app) {
    return make_command(app, "eval",
                        "Compare footprint methods against a ground truth; write a report",
                        add_eval_options, run_eval);
}

}  // namespace cmam::app
