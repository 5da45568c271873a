// cmam — a subcommand: its options, registered on the app, and what runs once they are parsed.
// Each add_*_command adds one subcommand with its own options to `app`; main parses the command
// line and runs the one given. A command throws on errors (UsageError for a bad value); main
// prints them.
#pragma once

#include <cmam/texture/names.h>

#include <CLI/CLI.hpp>
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>

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

/// Accepts the names of `table`; refuses any other value with "unknown "VALUE" (expected a, b
/// or c)", which CLI11 prints after the option's name.
template <class E, std::size_t N>
CLI::Validator choice_validator(const texture::NameTable<E, N>& table) {
    return CLI::Validator(
        [&table](std::string& value) {
            if (table.parse(value)) return std::string();
            return "unknown \"" + value + "\" (expected " + table.list() + ")";
        },
        "");
}

/// Adds option `flag`, whose value is one of `table`'s names, to `cmd`. `value` is an E, whose
/// default --help shows, or an optional<E>, left empty when the option is not given. The
/// description should list the names (table.list()).
template <class T, class E, std::size_t N>
CLI::Option* add_choice(CLI::App& cmd, const std::string& flag, T& value,
                        const texture::NameTable<E, N>& table, const std::string& description) {
    static_assert(std::is_same_v<T, E> || std::is_same_v<T, std::optional<E>>);
    CLI::Option* opt = cmd.add_option_function<std::string>(
        flag, [&value, &table](const std::string& name) { value = *table.parse(name); },
        description);
    opt->check(choice_validator(table));
    if constexpr (std::is_same_v<T, E>) opt->default_str(std::string(table.name(value)));
    return opt;
}

Command add_render_command(CLI::App& app);
Command add_check_command(CLI::App& app);
Command add_lookup_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_eval_command(CLI::App& app);

}  // namespace cmam::app
