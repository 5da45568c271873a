// pbrt — tokenizer for the pbrt-v3 scene format.
// Tokens are quoted strings, '[' and ']', and bare words (numbers, directive names, true/false).
// '#' starts a comment to the end of the line. Every token remembers its FileLoc.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "pbrt/error.h"

namespace cmam::pbrt {

struct Token {
    std::string text;  // unquoted, escapes resolved, for strings
    FileLoc loc;
    bool quoted = false;

    bool is(std::string_view s) const { return !quoted && text == s; }
};

class Tokenizer {
  public:
    /// Tokenizes `contents`, reporting locations against `filename`.
    Tokenizer(std::string filename, std::string contents);
    /// Reads a whole file (a regular file of at most kMaxSceneFileBytes); throws SceneError
    /// located at `included_from` when it cannot, or at `path` itself for the main file.
    static Tokenizer from_file(const std::string& path, const FileLoc& included_from);

    /// Next token, or nullopt at the end of the input. Throws SceneError on malformed input.
    std::optional<Token> next();
    const std::string& filename() const { return *m_file; }

  private:
    std::shared_ptr<const std::string> m_file;
    std::string m_text;
    std::size_t m_pos = 0;
    int m_line = 1, m_col = 1;

    char advance();
    FileLoc here() const { return {m_file, m_line, m_col}; }
};

}  // namespace cmam::pbrt
