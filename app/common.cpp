#include "app/common.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "eval/evaluation.h"

namespace cmam::app {

void print_warning(const std::string& w) {
    std::cerr << (w.rfind("warning: ", 0) == 0 ? "cmam: " : "") << w << "\n";
}

void warn(const std::string& message) {
    print_warning("warning: " + message);
}

void note_spp_rounding(int spp, const char* flag) {
    if (spp <= 0) return;
    const int n = eval::rendered_spp(spp), k = static_cast<int>(std::lround(std::sqrt(n)));
    if (n != spp)
        warn(std::string(flag) + " " + std::to_string(spp) + " renders " + std::to_string(k) + "x" +
             std::to_string(k) + " = " + std::to_string(n) +
             " samples per pixel (stratified samples form a square grid)");
}

std::vector<double> parse_numbers(const std::string& text, const char* flag) {
    std::vector<double> out;
    std::size_t pos = 0;
    while (pos <= text.size()) {
        std::size_t comma = text.find(',', pos);
        std::string item =
            text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
        char* end = nullptr;
        double v = std::strtod(item.c_str(), &end);
        if (item.empty() || end != item.c_str() + item.size())
            throw UsageError(std::string(flag) + ": \"" + item + "\" is not a number");
        out.push_back(v);
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    return out;
}

std::vector<std::string> split_list(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ','))
        if (!item.empty()) out.push_back(item);
    return out;
}

std::string join(const std::vector<std::string>& v, const char* sep) {
    std::string out;
    for (const std::string& x : v) out += (out.empty() ? "" : sep) + x;
    return out;
}

std::string format_duration(double s) {
    char buf[64];
    if (s < 60)
        std::snprintf(buf, sizeof buf, "%.1fs", s);
    else
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    return buf;
}

std::string json_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (static_cast<unsigned char>(c) < 0x20) {
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

std::string json_number(double x) {
    if (!std::isfinite(x)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", x);
    return buf;
}

}  // namespace cmam::app
