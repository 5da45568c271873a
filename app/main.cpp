// cmam — command-line front end: `cmam render`, `cmam check`, `cmam lookup`, `cmam compare`,
// `cmam eval`, one file each (app/*_command.cpp).
// Libraries throw; main is the only place that prints their errors, and CLI11 prints the errors
// of the command line itself.
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <new>
#include <string>

#include "app/command.h"
#include "pbrt/error.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

// Runs a command; an error it throws is printed and exits 1.
int run_reporting_errors(const std::function<int()>& run) {
    try {
        return run();
    } catch (const cmam::pbrt::SceneError& e) {
        // Located: "FILE:LINE:COL: error: ..."; otherwise "error: ...", printed as the others.
        std::cerr << (e.loc().file ? "" : "cmam: ") << e.what() << "\n";
    } catch (const std::bad_alloc&) {
        std::cerr << "cmam: error: out of memory (the scene, its textures or the film need more "
                     "than this machine or process may use)\n";
    } catch (const std::exception& e) {
        std::cerr << "cmam: error: " << cmam::pbrt::printable(e.what()) << "\n";
    }
    return 1;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace cmam::app;
    // Past a file size limit (ulimit -f) a write fails with EFBIG, which the writers report and
    // clean up after, instead of the process ending on SIGXFSZ with a temporary left behind.
    std::signal(SIGXFSZ, SIG_IGN);
#if defined(__GLIBC__)
    // glibc's allocator serves blocks up to 32 MB from its heap and keeps up to 64 MB of freed
    // memory for reuse. By default it maps blocks from 128 KB on (raising that only as large
    // blocks are freed) and hands freed memory over 128 KB back to the system, so that memory
    // allocated and freed again and again (zlib's 260 KB of buffers for every block of an EXR,
    // for one) is faulted in anew each time, a page at a time: coffee-splash took 8.7% more
    // CPU time, for 3 MB less at its peak (docs/performance.md).
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
    CLI::App app{"cmam: a texture-filtering Whitted ray tracer for pbrt-v3 scenes"};
    app.set_version_flag("--version", std::string("cmam ") + CMAM_VERSION);
    app.require_subcommand(1);
    const Command commands[] = {add_render_command(app), add_check_command(app),
                                add_lookup_command(app), add_compare_command(app),
                                add_eval_command(app)};
    app.failure_message([](const CLI::App* a, const CLI::Error& e) {
        return "cmam: error: " + std::string(e.what()) + "\nRun with " +
               (a->get_help_ptr() ? a->get_help_ptr()->get_name() : std::string("--help")) +
               " for more information.\n";
    });
    CLI11_PARSE(app, argc, argv);
    for (const Command& c : commands)
        if (*c.subcommand) return run_reporting_errors(c.run);
    return 0;
}
