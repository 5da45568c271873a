#include "pbrt/error.h"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

namespace cmam::pbrt {

std::string FileLoc::to_string() const {
    if (!file) return {};
    if (line == 0) return *file;  // the file as a whole
    return *file + ":" + std::to_string(line) + ":" + std::to_string(col);
}

std::string printable(const std::string& s) {
    std::string out;
    out.reserve(s.size());
    for (std::size_t i = 0; i < s.size();) {
        const auto c = static_cast<unsigned char>(s[i]);
        std::size_t n = c < 0x80         ? 1
                        : (c >> 5) == 6  ? 2
                        : (c >> 4) == 14 ? 3
                        : (c >> 3) == 30 ? 4
                                         : 0;
        bool ok = n > 0 && i + n <= s.size() && (n > 1 || (c >= 0x20 && c != 0x7f) || c == '\n');
        for (std::size_t k = 1; ok && k < n; ++k)
            ok = (static_cast<unsigned char>(s[i + k]) & 0xc0) == 0x80;
        if (ok) {
            out.append(s, i, n);
            i += n;
            continue;
        }
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\x%02x", c);
        out += buf;
        ++i;
    }
    return out;
}

namespace {
std::string located(const FileLoc& loc, const char* kind, const std::string& raw) {
    const std::string message = printable(raw);
    std::string where = printable(loc.to_string());
    return where.empty() ? std::string(kind) + ": " + message
                         : where + ": " + kind + ": " + message;
}
}  // namespace

SceneError::SceneError(const FileLoc& loc, const std::string& message)
    : std::runtime_error(located(loc, "error", message)), m_loc(loc), m_message(message) {}

SceneError::SceneError(const std::string& message)
    : std::runtime_error(located({}, "error", message)), m_message(message) {}

namespace {
std::string joined(const std::vector<SceneError>& errors) {
    std::string s;
    for (const SceneError& e : errors) s += (s.empty() ? "" : "\n") + std::string(e.what());
    return s;
}
}  // namespace

SceneError::SceneError(const std::vector<SceneError>& errors)
    : std::runtime_error(joined(errors)),
      m_loc(errors.empty() ? FileLoc{} : errors.front().loc()),
      m_message(errors.empty() ? std::string() : errors.front().message()) {}

std::string format_warning(const FileLoc& loc, const std::string& message) {
    return located(loc, "warning", message);
}

std::string number_text(double v, int digits) {
    if (std::isnan(v)) return "nan";  // whatever its sign bit ("-nan" from 0 * -inf)
    std::ostringstream os;
    os << std::setprecision(digits) << v;
    return os.str();
}

}  // namespace cmam::pbrt
