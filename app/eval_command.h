// cmam eval: every footprint method against a ground truth, and the report.
#pragma once

#include <string>
#include <vector>

namespace cmam::app {

struct EvalArgs {
    std::vector<std::string> scenes;
    std::string methods, spp = "1,4,16", out = "eval-out";
    int reference_spp = 1024, timing_runs = 1;
    bool quiet = false;
};

/// What a method name is, from the evaluation's own tables (for --help and errors).
std::string method_syntax();

int run_eval(const EvalArgs& args);

}  // namespace cmam::app
