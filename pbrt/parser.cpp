#include "pbrt/parser.h"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pbrt/input_file.h"
#include "pbrt/parser_impl.h"

namespace cmam::pbrt {

std::string resolve_path(const std::string& base_dir, const FileLoc& loc, const std::string& name) {
    const std::filesystem::path p(name);
    if (p.is_absolute()) return name;
    // pbrt-v3 resolves every relative path against the main scene file's folder, in Included
    // files too; a path that exists only beside the file naming it (the convention of scenes
    // written for renderers that resolve that way) is found there.
    const std::filesystem::path main = base_dir.empty() ? p : std::filesystem::path(base_dir) / p;
    if (!loc.file) return main.string();
    const std::filesystem::path dir = std::filesystem::path(*loc.file).parent_path();
    const std::filesystem::path beside = dir.empty() ? p : dir / p;
    std::error_code ec;
    if (beside != main && !std::filesystem::exists(main, ec) && std::filesystem::exists(beside, ec))
        return beside.string();
    return main.string();
}

namespace detail {

SceneDesc Parser::run(Tokenizer root) {
    m_desc.base_dir = std::filesystem::path(root.filename()).parent_path().string();
    push_file(std::move(root));
    // After an error the parser skips to the next directive and goes on, so that one run
    // reports every error it can find (up to kMaxReportedErrors), in file order.
    std::vector<SceneError> errors;
    bool readable = true;  // false once the tokenizer itself failed: nothing more is read
    while (readable && errors.size() < kMaxReportedErrors) {
        std::optional<Token> tok;
        try {
            tok = next();
        } catch (const SceneError& e) {
            errors.push_back(e);
            break;
        }
        if (!tok) break;
        try {
            directive(*tok);
        } catch (const SceneError& e) {
            errors.push_back(e);
            // A block that does not match leaves the nesting unknown: what follows would
            // report that error again in other words.
            const bool nesting =
                !tok->quoted && (tok->text.ends_with("Begin") || tok->text.ends_with("End"));
            readable = !nesting && skip_to_directive(errors);
        }
    }
    if (!errors.empty()) throw SceneError(errors);
    if (!m_stack.empty()) {
        const StackEntry& e = m_stack.back();
        throw SceneError(e.loc, std::string(e.begin()) + " is never closed");
    }
    if (m_in_object) throw SceneError(m_object_loc, "ObjectBegin is never closed");
    if (!m_world_begun && m_last_loc.file)
        throw SceneError(m_last_loc, "premature end of file: WorldBegin never given");
    return std::move(m_desc);
}

// Skips the rest of a directive that failed: up to the next directive word.
// False if the tokenizer failed on the way (its error is added).
bool Parser::skip_to_directive(std::vector<SceneError>& errors) {
    try {
        while (const Token* t = peek()) {
            if (is_directive_word(*t)) return true;
            next();
        }
        return true;
    } catch (const SceneError& e) {
        errors.push_back(e);
        return false;
    }
}

void Parser::directive(const Token& dir) {
    if (dir.quoted || dir.text == "[" || dir.text == "]")
        throw SceneError(
            dir.loc, "expected a directive, got " + (dir.quoted ? in_quotes(dir.text) : dir.text));
    for (const Directive& d : directives()) {
        if (d.name != dir.text) continue;
        check_block(dir, d.block);
        (this->*d.handle)(dir);
        return;
    }
    throw SceneError(dir.loc,
                     "unknown directive " + dir.text + " (supported: " + supported_list() + ")");
}

void Parser::check_block(const Token& dir, Block block) const {
    if (block == Block::Anywhere) return;
    if (m_world_ended) throw SceneError(dir.loc, dir.text + " after WorldEnd");
    if (block == Block::World && !m_world_begun)
        throw SceneError(dir.loc,
                         dir.text + " is only allowed inside the world block (after WorldBegin)");
    if (block == Block::Options && m_world_begun)
        throw SceneError(
            dir.loc, dir.text + " is not allowed inside the world block (before WorldBegin only)");
}

// The fully supported directives' names, as the unknown-directive error lists them.
const std::string& Parser::supported_list() {
    static const std::string list = [] {
        std::string s;
        for (const Directive& d : directives())
            if (d.support == Support::Full) s += (s.empty() ? "" : ", ") + std::string(d.name);
        return s;
    }();
    return list;
}

void Parser::warn(const FileLoc& loc, const std::string& msg) {
    if (m_warn) m_warn(format_warning(loc, msg));
}

void Parser::push_file(Tokenizer t) {
    std::error_code ec;
    auto canon = std::filesystem::weakly_canonical(t.filename(), ec).string();
    m_desc.sources.push_back(t.filename());
    m_reading.insert(canon);
    m_files.push_back(std::make_unique<Source>(Source{std::move(t), canon}));
}

void Parser::include(const Token& dir) {
    std::string name = expect_string(dir, "a quoted file name");
    std::string path = resolve_path(m_desc.base_dir, dir.loc, name);
    std::error_code ec;
    std::string canon = std::filesystem::weakly_canonical(path, ec).string();
    if (m_reading.count(canon))  // a set: a chain of 10^5 Includes stays linear
        throw SceneError(dir.loc, "Include cycle: " + in_quotes(name) + " is already being read");
    if (m_peeked) throw SceneError(dir.loc, "internal: lookahead across Include");
    push_file(Tokenizer::from_file(path, dir.loc));
}

std::optional<Token> Parser::next() {
    if (m_peeked) {
        auto t = std::move(m_peeked);
        m_peeked.reset();
        return t;
    }
    while (!m_files.empty()) {
        if (auto t = m_files.back()->tokens.next()) {
            m_last_loc = t->loc;
            return t;
        }
        m_reading.erase(m_files.back()->canonical);
        m_files.pop_back();
    }
    return std::nullopt;
}

const Token* Parser::peek() {
    if (!m_peeked) m_peeked = next();
    return m_peeked ? &*m_peeked : nullptr;
}

Token Parser::expect_any(const Token& after, const char* what) {
    auto t = next();
    if (!t) throw SceneError(after.loc, "premature end of file: " + after.text + " needs " + what);
    return std::move(*t);
}

std::string Parser::expect_string(const Token& dir, const char* what) {
    Token t = expect_any(dir, what);
    if (!t.quoted) throw SceneError(t.loc, dir.text + " expects " + what + ", got " + t.text);
    return t.text;
}

double Parser::expect_number(const Token& dir) {
    // A directive where a number should be is left for the next directive (it is reported
    // here, and the parser goes on from it).
    if (const Token* p = peek(); p && is_directive_word(*p))
        throw SceneError(p->loc, dir.text + " expects a number, got " + p->text);
    Token t = expect_any(dir, "a number");
    return to_number(t, dir.text);
}

bool Parser::number_of(const Token& t, double& v) {
    if (t.quoted) return false;
    const char* b = t.text.data();
    const char* e = b + t.text.size();
    if (!t.text.empty() && *b == '+') ++b;
    auto r = std::from_chars(b, e, v);
    return r.ec == std::errc() && r.ptr == e && b != e;
}

double Parser::to_number(const Token& t, const std::string& context) {
    double v = 0;
    if (number_of(t, v)) return v;
    throw SceneError(t.loc,
                     context + " expects a number, got " + (t.quoted ? in_quotes(t.text) : t.text));
}

std::vector<double> Parser::numbers(const Token& dir, int n, bool allow_brackets) {
    bool bracket = false;
    if (allow_brackets && peek() && peek()->is("[")) {
        next();
        bracket = true;
    }
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(expect_number(dir));
    if (bracket) {
        Token t = expect_any(dir, "']'");
        if (!t.is("]"))
            throw SceneError(t.loc,
                             dir.text + " expects " + std::to_string(n) + " numbers, then ']'");
    }
    return v;
}

ParamSet Parser::param_list() {
    ParamSet ps;
    while (const Token* t = peek()) {
        if (!t->quoted) break;
        Token decl = *next();
        Param p = param_declaration(decl);
        Token v = expect_any(decl, "a value");
        if (v.is("[")) {
            for (;;) {
                Token e = expect_any(decl, "']'");
                if (e.is("]")) break;
                add_value(p, e);
            }
        } else {
            add_value(p, v);
        }
        if (p.type == ParamType::Spectrum && !p.strings.empty() && !p.numbers.empty())
            throw SceneError(p.loc, "spectrum " + in_quotes(p.name) + " mixes numbers and strings");
        if (p.type == ParamType::Spectrum && !p.strings.empty()) read_spd(p);
        const FileLoc loc = p.loc;
        const std::string name = p.name;
        if (const auto first = ps.add(std::move(p)))
            warn(loc, "parameter " + in_quotes(name) +
                          " given twice; the later value is used (the first is at " +
                          first->to_string() + ")");
    }
    return ps;
}

// A parameter's "type name", as a Param without values.
Param Parser::param_declaration(const Token& decl) {
    const std::string& s = decl.text;
    const std::size_t a = s.find_first_not_of(" \t");
    const std::size_t b = s.find_first_of(" \t", a);
    const std::size_t c = s.find_first_not_of(" \t", b);
    const std::size_t d = c == std::string::npos ? c : s.find_first_of(" \t", c);
    if (a == std::string::npos || b == std::string::npos || c == std::string::npos ||
        (d != std::string::npos && s.find_first_not_of(" \t", d) != std::string::npos))
        throw SceneError(decl.loc, "expected a parameter declaration \"type name\", got " +
                                       in_quotes(decl.text));
    const std::string type_name = s.substr(a, b - a);
    auto type = parse_param_type(type_name);
    if (!type)
        throw SceneError(decl.loc, "unknown parameter type " + in_quotes(type_name) +
                                       " (expected " + param_type_names() + ")");
    Param p;
    p.type = *type;
    p.type_name = type_name;
    p.name = s.substr(c, d == std::string::npos ? std::string::npos : d - c);
    p.loc = decl.loc;
    return p;
}

void Parser::add_value(Param& p, const Token& v) {
    const bool want_string = p.type == ParamType::String || p.type == ParamType::Texture;
    if (p.type == ParamType::Bool) {
        if (v.text == "true")
            p.bools.push_back(true);
        else if (v.text == "false")
            p.bools.push_back(false);
        else
            throw SceneError(v.loc, "bool parameter " + in_quotes(p.name) +
                                        " expects \"true\" or \"false\", got " + v.text);
    } else if (want_string || (p.type == ParamType::Spectrum && v.quoted)) {
        if (!v.quoted)
            throw SceneError(v.loc, std::string(to_string(p.type)) + " parameter " +
                                        in_quotes(p.name) + " expects a quoted string, got " +
                                        v.text);
        p.strings.push_back(v.text);
    } else {
        // The context of the error is written only for one (a mesh has millions of numbers).
        double x = 0;
        if (!number_of(v, x))
            x = to_number(v, std::string(to_string(p.type)) + " parameter " + in_quotes(p.name));
        p.numbers.push_back(x);
    }
}

// A spectrum given as a file name: pbrt-v3's .spd text, (wavelength value) pairs with '#'
// comments, resolved as every path is; its samples replace the name.
void Parser::read_spd(Param& p) {
    if (p.strings.size() != 1)
        throw SceneError(p.loc, "spectrum " + in_quotes(p.name) + " names " +
                                    std::to_string(p.strings.size()) +
                                    " files; give one .spd file");
    const std::string path = resolve_path(m_desc.base_dir, p.loc, p.strings[0]);
    if (std::string why = not_a_regular_file(path); !why.empty())
        throw SceneError(p.loc, "cannot read spectrum file " + in_quotes(path) + ": " + why);
    if (std::error_code ec; !std::filesystem::exists(path, ec))
        throw SceneError(p.loc, "cannot read spectrum file " + in_quotes(path) +
                                    ": file not found (named by spectrum " + in_quotes(p.name) +
                                    ")");
    std::ifstream in(path);
    if (!in)
        throw SceneError(p.loc, "cannot read spectrum file " + in_quotes(path) +
                                    " (named by spectrum " + in_quotes(p.name) +
                                    "; pbrt-v3 reads .spd files of wavelength, value pairs)");
    std::vector<double> values;
    std::string line;
    while (std::getline(in, line) && values.size() < 100000) {
        line = line.substr(0, line.find('#'));
        std::istringstream words(line);
        std::string w;
        while (words >> w) {
            char* end = nullptr;
            const double v = std::strtod(w.c_str(), &end);
            if (end != w.c_str() + w.size())
                throw SceneError(p.loc, "spectrum file " + in_quotes(path) + ": " + in_quotes(w) +
                                            " is not a number");
            values.push_back(v);
        }
    }
    if (values.empty() || values.size() % 2 != 0)
        throw SceneError(p.loc, "spectrum file " + in_quotes(path) +
                                    " must hold (wavelength, value) pairs, got " +
                                    std::to_string(values.size()) + " numbers");
    p.strings.clear();
    p.numbers = std::move(values);
    m_desc.sources.push_back(path);
}

Entity Parser::entity(const Token& dir) {
    Entity e;
    e.loc = dir.loc;
    e.type = expect_string(dir, "a quoted type name");
    e.params = param_list();
    e.given = true;
    return e;
}

}  // namespace detail

SceneDesc parse_file(const std::string& path, const WarningSink& warn) {
    return detail::Parser(warn).run(Tokenizer::from_file(path, FileLoc{}));
}

SceneDesc parse_string(const std::string& text, const std::string& filename,
                       const WarningSink& warn) {
    return detail::Parser(warn).run(Tokenizer(filename, text));
}

}  // namespace cmam::pbrt
