#include "pbrt/error.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace cmam::pbrt {

std::string FileLoc::to_string() const {
    if (!file) return {};
    if (line == 0) return *file;  // the file as a whole
    return *file + ":" + std::to_string(line) + ":" + std::to_string(col);
}

namespace {
std::string located(const FileLoc& loc, const char* kind, const std::string& message) {
    std::string where = loc.to_string();
    return where.empty() ? std::string(kind) + ": " + message
                         : where + ": " + kind + ": " + message;
}
}  // namespace

SceneError::SceneError(const FileLoc& loc, const std::string& message)
    : std::runtime_error(located(loc, "error", message)), m_loc(loc), m_message(message) {}

SceneError::SceneError(const std::string& message)
    : std::runtime_error("error: " + message), m_message(message) {}

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
