// cmam — a subcommand: its options, registered on the app, and what runs once they are parsed.
// Each add_*_command adds one subcommand with its own options to `app`; main parses the command
// line and runs the one given. A command throws on errors (UsageError for a bad value); main
// prints them.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>

namespace cmam::app {

struct Command {
    CLI::App* subcommand;      // set when the command line names it
    std::function<int()> run;  // the exit code
};

/// Adds subcommand `name` whose options, registered by `add_options`, fill an `Args` that `run`
/// runs with.
template <class Args>
Command make_command(CLI::App& app, const char* name, const char* description,
                     void (*add_options)(CLI::App&, Args&), int (*run)(const Args&)) {
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(name, description);
    add_options(*cmd, *args);
    return {cmd, [args, run] { return run(*args); }};
}

Command add_render_command(CLI::App& app);
Command add_check_command(CLI::App& app);
Command add_lookup_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_eval_command(CLI::App& app);

}  // namespace cmam::app
