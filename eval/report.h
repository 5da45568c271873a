// eval — the evaluation's outputs: results.csv, results.md (a table to paste) and index.html (a
// self-contained report: images side by side with synchronized zoom, error heat maps, an
// error-versus-time plot per scene). Each file is written to a temporary and renamed.
#pragma once

#include "eval/evaluation.h"

namespace cmam::eval {

void write_reports(const EvalOptions& options, const EvalResult& result);

/// The markdown table alone (what docs/results.md embeds).
std::string results_markdown(const EvalResult& result);

}  // namespace cmam::eval
