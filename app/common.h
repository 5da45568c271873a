// cmam — what the commands share: messages, the usage error, lists on the command line, JSON
// values, the progress bar.
// Warnings and errors have one form: "FILE:LINE:COL: warning: ..." when they point into a scene
// file, "cmam: warning: ..." (or "cmam: error: ...") otherwise.
#pragma once

#include <chrono>
#include <cstdio>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace cmam::app {

/// The app's one exception type for a bad command-line value (an option, a path, an image given
/// to compare); printed as "cmam: error: MESSAGE", the message naming the option or the file.
class UsageError : public std::invalid_argument {
  public:
    using std::invalid_argument::invalid_argument;
};

/// Prints a warning, located ("file:line:col: warning: ...") or not ("warning: ...", printed
/// with the "cmam: " prefix).
void print_warning(const std::string& w);
/// Prints "cmam: warning: MESSAGE".
void warn(const std::string& message);
/// --spp N renders a square grid of k x k strata: says so when k * k != N.
void note_spp_rounding(int spp, const char* flag = "--spp");

/// Comma-separated numbers; throws UsageError naming `flag` on anything else.
std::vector<double> parse_numbers(const std::string& text, const char* flag);
/// Comma-separated items, empty ones dropped.
std::vector<std::string> split_list(const std::string& s);
std::string join(const std::vector<std::string>& v, const char* sep = ", ");

std::string format_duration(double seconds);

/// `s` as the inside of a JSON string: quotes and backslashes escaped, control characters as
/// \u00XX.
std::string json_escape(const std::string& s);
/// A number as JSON has it: JSON has no NaN or infinity, so those are null (a NaN --uv given to
/// see the fallback, an infinite PSNR of identical images).
std::string json_number(double x);

class ProgressBar {
  public:
    explicit ProgressBar(bool enabled)
        : m_enabled(enabled), m_start(std::chrono::steady_clock::now()) {}
    void update(int done, int total) {
        if (!m_enabled) return;
        std::lock_guard<std::mutex> lock(m_mutex);
        double frac = double(done) / total;
        int pct = int(frac * 100);
        if (pct == m_last && done != total) return;
        m_last = pct;
        double el =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
        double eta = frac > 0 ? el / frac - el : 0;
        constexpr int kWidth = 40;
        int fill = int(frac * kWidth);
        std::string bar(fill, '=');
        bar.resize(kWidth, ' ');
        std::fprintf(stderr, "\r[%s] %3d%%  elapsed %s  ETA %s   ", bar.c_str(), pct,
                     format_duration(el).c_str(), format_duration(eta).c_str());
        if (done == total) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

  private:
    bool m_enabled;
    std::chrono::steady_clock::time_point m_start;
    std::mutex m_mutex;
    int m_last = -1;
};

}  // namespace cmam::app
