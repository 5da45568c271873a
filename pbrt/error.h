// pbrt — locations and errors of scene input.
// Every problem found in a scene file carries FILE:LINE:COL; the library throws, main prints.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace cmam::pbrt {

/// A position in a scene file: 1-based line and column.
struct FileLoc {
    std::shared_ptr<const std::string> file;  // shared by every token of one file
    int line = 0;
    int col = 0;

    std::string to_string() const;  // "file:line:col", "file" when line is 0, "" when unknown
};

/// The one exception type of the pbrt library (tokenizer, parser, PLY reader, transforms) and of
/// the scene builder. `what()` is the complete, printable message: "file:line:col: error:
/// message"; `message()` is the message alone.
class SceneError : public std::runtime_error {
  public:
    SceneError(const FileLoc& loc, const std::string& message);
    explicit SceneError(const std::string& message);  // not tied to a location
    /// Several errors as one, in the given order: the first's location and message, and every
    /// one's located text, a line each (one error gives that error's own text).
    explicit SceneError(const std::vector<SceneError>& errors);
    const std::string& message() const { return m_message; }
    const FileLoc& loc() const { return m_loc; }

  private:
    FileLoc m_loc;
    std::string m_message;
};

/// How many errors the parser and the scene builder collect before they stop.
inline constexpr std::size_t kMaxReportedErrors = 20;

/// Receives located warnings ("file:line:col: warning: message").
using WarningSink = std::function<void(const std::string&)>;

/// `s` with the bytes a terminal would act on (control characters, bytes that are not UTF-8) as
/// \xNN: a binary file given as a scene must not echo raw bytes into the terminal. Errors and
/// warnings are formatted through it.
std::string printable(const std::string& s);

/// `s` in double quotes, as messages show names and values: in_quotes("imagemap") is "imagemap"
/// with its quotes.
inline std::string in_quotes(const std::string& s) {
    return "\"" + s + "\"";
}

/// Formats a warning the same way errors are formatted.
std::string format_warning(const FileLoc& loc, const std::string& message);

/// A number as messages show it: up to `digits` significant digits (7 suit a float), "nan",
/// "inf" ("1e+10", "0.5").
std::string number_text(double v, int digits = 15);

}  // namespace cmam::pbrt
