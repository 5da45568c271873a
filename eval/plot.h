// eval — the report's plots (log-log error against render time, one line per method across
// sample counts) as inline SVG, and the text helpers the report and the plots share.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "eval/evaluation.h"

namespace cmam::eval {

/// `v` formatted by the printf format `f` (one double).
inline std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

/// `s` with <, >, & and " as HTML entities.
inline std::string html_escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '<')
            o += "&lt;";
        else if (c == '>')
            o += "&gt;";
        else if (c == '&')
            o += "&amp;";
        else if (c == '"')
            o += "&quot;";
        else
            o += c;
    }
    return o;
}

/// One log-log plot: `error` of each row against its render time, one polyline per method (in
/// `methods`' order, each with its own colour, marker and dash) across sample counts, with a
/// legend; `aria` is its accessible name.
std::string svg_plot(const std::vector<const ResultRow*>& rows,
                     const std::vector<std::string>& methods, double ResultRow::*error,
                     const std::string& ylabel, const std::string& xlabel, const std::string& aria);

}  // namespace cmam::eval
