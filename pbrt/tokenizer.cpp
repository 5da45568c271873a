#include "pbrt/tokenizer.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "pbrt/input_file.h"

namespace cmam::pbrt {

Tokenizer::Tokenizer(std::string filename, std::string contents)
    : m_file(std::make_shared<const std::string>(std::move(filename))),
      m_text(std::move(contents)) {}

Tokenizer Tokenizer::from_file(const std::string& path, const FileLoc& included_from) {
    // An Include's problems are located at the Include, the main file's at its name.
    const bool included = included_from.file != nullptr;
    const FileLoc where =
        included ? included_from : FileLoc{std::make_shared<const std::string>(path)};
    const std::string what = included ? "scene file \"" + path + "\"" : "scene file";
    if (std::string why = not_a_regular_file(path); !why.empty())
        throw SceneError(where, "cannot read " + what + ": " + why);
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        std::string why = std::strerror(errno);
        throw SceneError(where, "cannot open " + what + ": " + why);
    }
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxSceneFileBytes)
        throw SceneError(where, what + " is " + std::to_string(size) +
                                    " bytes, above cmam's limit of " +
                                    std::to_string(kMaxSceneFileBytes));
    // At most the size seen above, should the file grow while it is read.
    std::string text(ec ? 0 : size, '\0');
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    text.resize(static_cast<std::size_t>(in.gcount()));
    return Tokenizer(path, std::move(text));
}

namespace {
// std::isspace in the "C" locale (the one cmam runs in), without a call a byte.
bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}
}  // namespace

char Tokenizer::advance() {
    char c = m_text[m_pos++];
    if (c == '\n') {
        ++m_line;
        m_col = 1;
    } else {
        ++m_col;
    }
    return c;
}

std::optional<Token> Tokenizer::next() {
    while (m_pos < m_text.size()) {
        char c = m_text[m_pos];
        if (is_space(c)) {
            advance();
            continue;
        }
        if (c == '#') {
            while (m_pos < m_text.size() && m_text[m_pos] != '\n') advance();
            continue;
        }
        Token tok;
        tok.loc = here();
        if (c == '[' || c == ']') {
            tok.text = std::string(1, advance());
            return tok;
        }
        if (c == '"') {
            advance();
            tok.quoted = true;
            for (;;) {
                if (m_pos >= m_text.size() || m_text[m_pos] == '\n')
                    throw SceneError(tok.loc, "unterminated string");
                char d = advance();
                if (d == '"') break;
                if (d == '\\') {
                    if (m_pos >= m_text.size()) throw SceneError(tok.loc, "unterminated string");
                    char e = advance();
                    switch (e) {
                        case 'n':
                            tok.text += '\n';
                            break;
                        case 't':
                            tok.text += '\t';
                            break;
                        case 'b':
                            tok.text += '\b';
                            break;
                        case 'f':
                            tok.text += '\f';
                            break;
                        case 'r':
                            tok.text += '\r';
                            break;
                        case '\\':
                            tok.text += '\\';
                            break;
                        case '\'':
                            tok.text += '\'';
                            break;
                        case '"':
                            tok.text += '"';
                            break;
                        default:
                            throw SceneError(tok.loc,
                                             std::string("unknown escape \\") + e + " in string");
                    }
                    continue;
                }
                tok.text += d;
            }
            return tok;
        }
        // A bare word (a number, a directive) holds no newline: taken whole, one column a byte.
        std::size_t end = m_pos;
        while (end < m_text.size()) {
            const char d = m_text[end];
            if (is_space(d) || d == '"' || d == '[' || d == ']' || d == '#') break;
            ++end;
        }
        tok.text.assign(m_text, m_pos, end - m_pos);
        m_col += static_cast<int>(end - m_pos);
        m_pos = end;
        return tok;
    }
    return std::nullopt;
}

}  // namespace cmam::pbrt
