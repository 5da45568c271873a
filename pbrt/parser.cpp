#include "pbrt/parser.h"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

#include "pbrt/input_file.h"
#include "pbrt/tokenizer.h"

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

namespace {

std::string q(const std::string& s) {
    return "\"" + s + "\"";
}

// The part of pbrt-v3's graphics state copied at each AttributeBegin. Named textures and
// materials, also scoped by AttributeBegin/End, are kept in NamedTables instead.
struct GraphicsState {
    Mat4 ctm = Mat4::identity();
    bool reverse_orientation = false;
    int material = -1;
    int area_light = -1;  // the AreaLightSource in effect (index into SceneDesc::area_lights)
};

// The named textures and materials visible at the current point of the file: one table each,
// changed in place. Each change made inside a block is logged with the value it replaced, so
// AttributeEnd undoes the block's declarations; nothing is copied per block or per directive.
class NamedTables {
  public:
    std::map<std::string, int> float_textures, spectrum_textures, materials;

    // Binds `name` to `index`; true when it was bound already (a redefinition).
    bool bind(std::map<std::string, int>& table, const std::string& name, int index,
              bool in_block) {
        auto [it, added] = table.try_emplace(name, index);
        if (in_block)
            m_undo.push_back({&table, name, added ? std::nullopt : std::optional(it->second)});
        it->second = index;
        return !added;
    }
    std::size_t mark() const { return m_undo.size(); }
    void undo_to(std::size_t mark) {
        for (; m_undo.size() > mark; m_undo.pop_back()) {
            const Change& c = m_undo.back();
            if (c.previous)
                (*c.table)[c.name] = *c.previous;
            else
                c.table->erase(c.name);
        }
    }
    // The textures `params` name, as visible now (what the builder resolves them against).
    TextureScope scope_for(const ParamSet& params) const {
        TextureScope s;
        for (const Param& p : params.params()) {
            if (p.type != ParamType::Texture) continue;
            for (const std::string& name : p.strings) {
                if (auto it = float_textures.find(name); it != float_textures.end())
                    s.float_textures.insert(*it);
                if (auto it = spectrum_textures.find(name); it != spectrum_textures.end())
                    s.spectrum_textures.insert(*it);
            }
        }
        return s;
    }

  private:
    struct Change {
        std::map<std::string, int>* table;
        std::string name;
        std::optional<int> previous;
    };
    std::vector<Change> m_undo;
};

// A block that restores the graphics state: AttributeBegin, TransformBegin, or ObjectBegin
// (which implies AttributeBegin, as in pbrt-v3).
struct StackEntry {
    enum class Kind { Attribute, Transform, Object };
    Kind kind = Kind::Attribute;
    FileLoc loc;
    GraphicsState saved;
    std::size_t names_mark = 0;  // NamedTables::mark() when the block was opened

    const char* begin() const {
        return kind == Kind::Attribute   ? "AttributeBegin"
               : kind == Kind::Transform ? "TransformBegin"
                                         : "ObjectBegin";
    }
};

const char* kSupportedDirectives =
    "LookAt, Translate, Rotate, Scale, Transform, ConcatTransform, Identity, CoordinateSystem, "
    "CoordSysTransform, ReverseOrientation, WorldBegin, WorldEnd, AttributeBegin, AttributeEnd, "
    "TransformBegin, TransformEnd, Include, MakeNamedMaterial, NamedMaterial, Material, Texture, "
    "Shape, LightSource, AreaLightSource, Camera, Film, Sampler, PixelFilter, Integrator, "
    "Accelerator, "
    "ObjectBegin, ObjectEnd, ObjectInstance";

class Parser {
  public:
    explicit Parser(const WarningSink& warn) : m_warn(warn) {}

    SceneDesc run(Tokenizer root) {
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

  private:
    // A bare word starting with a capital letter: what every directive is (parameters are
    // quoted, values quoted or numbers).
    static bool is_directive_word(const Token& t) {
        return !t.quoted && !t.text.empty() && t.text[0] >= 'A' && t.text[0] <= 'Z';
    }

    // Skips the rest of a directive that failed: up to the next directive word.
    // False if the tokenizer failed on the way (its error is added).
    bool skip_to_directive(std::vector<SceneError>& errors) {
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

    struct Source {
        Tokenizer tokens;
        std::string canonical;
    };
    std::vector<std::unique_ptr<Source>> m_files;
    std::optional<Token> m_peeked;
    WarningSink m_warn;
    SceneDesc m_desc;
    GraphicsState m_gs;
    NamedTables m_names;
    std::vector<StackEntry> m_stack;
    std::map<std::string, Mat4> m_coord_systems;
    std::map<std::string, int> m_objects;  // name -> index in m_desc.objects (the latest)
    bool m_world_begun = false, m_world_ended = false;
    bool m_in_object = false;
    std::string m_object_name;
    FileLoc m_object_loc, m_last_loc;

    // A spectrum given as a file name: pbrt-v3's .spd text, (wavelength value) pairs with '#'
    // comments, resolved as every path is; its samples replace the name.
    void read_spd(Param& p) {
        if (p.strings.size() != 1)
            throw SceneError(p.loc, "spectrum " + q(p.name) + " names " +
                                        std::to_string(p.strings.size()) +
                                        " files; give one .spd file");
        const std::string path = resolve_path(m_desc.base_dir, p.loc, p.strings[0]);
        if (std::string why = not_a_regular_file(path); !why.empty())
            throw SceneError(p.loc, "cannot read spectrum file " + q(path) + ": " + why);
        if (std::error_code ec; !std::filesystem::exists(path, ec))
            throw SceneError(p.loc, "cannot read spectrum file " + q(path) +
                                        ": file not found (named by spectrum " + q(p.name) + ")");
        std::ifstream in(path);
        if (!in)
            throw SceneError(p.loc, "cannot read spectrum file " + q(path) +
                                        " (named by spectrum " + q(p.name) +
                                        "; pbrt-v3 reads .spd files of wavelength, value "
                                        "pairs)");
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
                    throw SceneError(p.loc,
                                     "spectrum file " + q(path) + ": " + q(w) + " is not a number");
                values.push_back(v);
            }
        }
        if (values.empty() || values.size() % 2 != 0)
            throw SceneError(p.loc, "spectrum file " + q(path) +
                                        " must hold (wavelength, value) pairs, got " +
                                        std::to_string(values.size()) + " numbers");
        p.strings.clear();
        p.numbers = std::move(values);
        m_desc.sources.push_back(path);
    }

    void warn(const FileLoc& loc, const std::string& msg) {
        if (m_warn) m_warn(format_warning(loc, msg));
    }
    // A "mix" material's two named materials, resolved where it is declared (as pbrt-v3 does).
    void resolve_mix(MaterialDesc& m) {
        if (m.entity.type != "mix") return;
        for (int k = 0; k < 2; ++k) {
            const std::string param = "namedmaterial" + std::to_string(k + 1);
            const Param* p = m.entity.params.find(param);
            if (!p) continue;  // the builder reports it
            const std::string name = m.entity.params.get_string(param, "");
            auto it = m_names.materials.find(name);
            if (it != m_names.materials.end()) m.mix[k] = it->second;
        }
    }
    // AttributeEnd or ObjectEnd: the state and the names as the innermost block found them.
    void restore_attributes() {
        m_gs = m_stack.back().saved;
        m_names.undo_to(m_stack.back().names_mark);
    }

    void push_file(Tokenizer t) {
        std::error_code ec;
        auto canon = std::filesystem::weakly_canonical(t.filename(), ec).string();
        m_desc.sources.push_back(t.filename());
        m_files.push_back(std::make_unique<Source>(Source{std::move(t), canon}));
    }

    std::optional<Token> next() {
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
            m_files.pop_back();
        }
        return std::nullopt;
    }
    const Token* peek() {
        if (!m_peeked) m_peeked = next();
        return m_peeked ? &*m_peeked : nullptr;
    }
    Token expect_any(const Token& after, const char* what) {
        auto t = next();
        if (!t)
            throw SceneError(after.loc, "premature end of file: " + after.text + " needs " + what);
        return *t;
    }
    std::string expect_string(const Token& dir, const char* what) {
        Token t = expect_any(dir, what);
        if (!t.quoted) throw SceneError(t.loc, dir.text + " expects " + what + ", got " + t.text);
        return t.text;
    }
    double expect_number(const Token& dir) {
        // A directive where a number should be is left for the next directive (it is reported
        // here, and the parser goes on from it).
        if (const Token* p = peek(); p && is_directive_word(*p))
            throw SceneError(p->loc, dir.text + " expects a number, got " + p->text);
        Token t = expect_any(dir, "a number");
        return to_number(t, dir.text);
    }
    static double to_number(const Token& t, const std::string& context) {
        double v = 0;
        if (!t.quoted) {
            const char* b = t.text.data();
            const char* e = b + t.text.size();
            if (!t.text.empty() && *b == '+') ++b;
            auto r = std::from_chars(b, e, v);
            if (r.ec == std::errc() && r.ptr == e && b != e) return v;
        }
        throw SceneError(t.loc,
                         context + " expects a number, got " + (t.quoted ? q(t.text) : t.text));
    }
    std::vector<double> numbers(const Token& dir, int n, bool allow_brackets) {
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

    ParamSet param_list() {
        ParamSet ps;
        while (const Token* t = peek()) {
            if (!t->quoted) break;
            Token decl = *next();
            // "type name"
            std::string type_name, name;
            {
                std::size_t a = decl.text.find_first_not_of(" \t");
                std::size_t b = decl.text.find_first_of(" \t", a);
                std::size_t c = decl.text.find_first_not_of(" \t", b);
                std::size_t d = c == std::string::npos ? c : decl.text.find_first_of(" \t", c);
                if (a == std::string::npos || b == std::string::npos || c == std::string::npos ||
                    (d != std::string::npos &&
                     decl.text.find_first_not_of(" \t", d) != std::string::npos))
                    throw SceneError(
                        decl.loc,
                        "expected a parameter declaration \"type name\", got " + q(decl.text));
                type_name = decl.text.substr(a, b - a);
                name = decl.text.substr(c, d == std::string::npos ? std::string::npos : d - c);
            }
            auto type = parse_param_type(type_name);
            if (!type)
                throw SceneError(decl.loc,
                                 "unknown parameter type " + q(type_name) +
                                     " (expected integer, float, point2, vector2, point3, "
                                     "vector3, normal, rgb, spectrum, blackbody, bool, string, "
                                     "texture)");
            Param p;
            p.type = *type;
            p.type_name = type_name;
            p.name = name;
            p.loc = decl.loc;
            auto add_value = [&](const Token& v) {
                bool want_string = p.type == ParamType::String || p.type == ParamType::Texture;
                if (p.type == ParamType::Bool) {
                    if (v.text == "true")
                        p.bools.push_back(true);
                    else if (v.text == "false")
                        p.bools.push_back(false);
                    else
                        throw SceneError(v.loc, "bool parameter " + q(name) +
                                                    " expects \"true\" or \"false\", got " +
                                                    v.text);
                } else if (want_string || (p.type == ParamType::Spectrum && v.quoted)) {
                    if (!v.quoted)
                        throw SceneError(v.loc, std::string(to_string(p.type)) + " parameter " +
                                                    q(name) + " expects a quoted string, got " +
                                                    v.text);
                    p.strings.push_back(v.text);
                } else {
                    p.numbers.push_back(
                        to_number(v, std::string(to_string(p.type)) + " parameter " + q(name)));
                }
            };
            Token v = expect_any(decl, "a value");
            if (v.is("[")) {
                for (;;) {
                    Token e = expect_any(decl, "']'");
                    if (e.is("]")) break;
                    add_value(e);
                }
            } else {
                add_value(v);
            }
            if (p.type == ParamType::Spectrum && !p.strings.empty() && !p.numbers.empty())
                throw SceneError(p.loc, "spectrum " + q(name) + " mixes numbers and strings");
            if (p.type == ParamType::Spectrum && !p.strings.empty()) read_spd(p);
            const FileLoc loc = p.loc;
            if (const auto first = ps.add(std::move(p)))
                warn(loc, "parameter " + q(name) +
                              " given twice; the later value is used (the "
                              "first is at " +
                              first->to_string() + ")");
        }
        return ps;
    }

    Entity entity(const Token& dir) {
        Entity e;
        e.loc = dir.loc;
        e.type = expect_string(dir, "a quoted type name");
        e.params = param_list();
        e.given = true;
        return e;
    }

    void need_world(const Token& dir, bool inside) {
        if (m_world_ended) throw SceneError(dir.loc, dir.text + " after WorldEnd");
        if (inside && !m_world_begun)
            throw SceneError(
                dir.loc, dir.text + " is only allowed inside the world block (after WorldBegin)");
        if (!inside && m_world_begun)
            throw SceneError(
                dir.loc,
                dir.text + " is not allowed inside the world block (before WorldBegin only)");
    }

    void directive(const Token& dir) {
        if (dir.quoted || dir.text == "[" || dir.text == "]")
            throw SceneError(dir.loc,
                             "expected a directive, got " + (dir.quoted ? q(dir.text) : dir.text));
        const std::string& d = dir.text;
        if (d == "Translate") {
            auto v = numbers(dir, 3, false);
            m_gs.ctm = m_gs.ctm * translate(v[0], v[1], v[2]);
        } else if (d == "Scale") {
            auto v = numbers(dir, 3, false);
            m_gs.ctm = m_gs.ctm * scale(v[0], v[1], v[2]);
        } else if (d == "Rotate") {
            auto v = numbers(dir, 4, false);
            if (v[1] == 0 && v[2] == 0 && v[3] == 0)
                throw SceneError(dir.loc, "Rotate axis has zero length");
            m_gs.ctm = m_gs.ctm * rotate(v[0], v[1], v[2], v[3]);
        } else if (d == "LookAt") {
            auto v = numbers(dir, 9, false);
            try {
                m_gs.ctm =
                    m_gs.ctm * look_at({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]});
            } catch (const std::domain_error& e) {
                throw SceneError(dir.loc, e.what());
            }
        } else if (d == "Transform" || d == "ConcatTransform") {
            auto v = numbers(dir, 16, true);
            Mat4 m;
            for (int i = 0; i < 16; ++i) m.m[i / 4][i % 4] = v[i];
            // The file lists the matrix column by column (pbrt-v3 transposes it).
            m = m.transposed();
            m_gs.ctm = d == "Transform" ? m : m_gs.ctm * m;
        } else if (d == "Identity") {
            m_gs.ctm = Mat4::identity();
        } else if (d == "CoordinateSystem") {
            m_coord_systems[expect_string(dir, "a quoted name")] = m_gs.ctm;
        } else if (d == "CoordSysTransform") {
            std::string name = expect_string(dir, "a quoted name");
            auto it = m_coord_systems.find(name);
            if (it == m_coord_systems.end())
                throw SceneError(dir.loc, "coordinate system " + q(name) + " is not defined");
            m_gs.ctm = it->second;
        } else if (d == "ReverseOrientation") {
            m_gs.reverse_orientation = !m_gs.reverse_orientation;
        } else if (d == "WorldBegin") {
            need_world(dir, false);
            m_world_begun = true;
            m_gs.ctm = Mat4::identity();
            m_coord_systems["world"] = m_gs.ctm;
        } else if (d == "WorldEnd") {
            need_world(dir, true);
            if (!m_stack.empty())
                throw SceneError(m_stack.back().loc, std::string(m_stack.back().begin()) +
                                                         " is not closed before WorldEnd");
            m_world_ended = true;
        } else if (d == "AttributeBegin" || d == "TransformBegin") {
            m_stack.push_back(
                {d == "AttributeBegin" ? StackEntry::Kind::Attribute : StackEntry::Kind::Transform,
                 dir.loc, m_gs, m_names.mark()});
        } else if (d == "AttributeEnd" || d == "TransformEnd") {
            bool attr = d == "AttributeEnd";
            if (m_stack.empty())
                throw SceneError(dir.loc, d + " without matching " +
                                              (attr ? "AttributeBegin" : "TransformBegin"));
            if (m_stack.back().kind !=
                (attr ? StackEntry::Kind::Attribute : StackEntry::Kind::Transform))
                throw SceneError(dir.loc, d + " does not match " + m_stack.back().begin() + " at " +
                                              m_stack.back().loc.to_string());
            if (attr)
                restore_attributes();
            else
                m_gs.ctm = m_stack.back().saved.ctm;
            m_stack.pop_back();
        } else if (d == "Include") {
            std::string name = expect_string(dir, "a quoted file name");
            std::string path = resolve_path(m_desc.base_dir, dir.loc, name);
            std::error_code ec;
            std::string canon = std::filesystem::weakly_canonical(path, ec).string();
            for (const auto& f : m_files)
                if (f->canonical == canon)
                    throw SceneError(dir.loc,
                                     "Include cycle: " + q(name) + " is already being read");
            if (m_peeked) throw SceneError(dir.loc, "internal: lookahead across Include");
            push_file(Tokenizer::from_file(path, dir.loc));
        } else if (d == "Camera") {
            need_world(dir, false);
            m_desc.camera = entity(dir);
            m_desc.camera_from_world = m_gs.ctm;
            try {
                m_coord_systems["camera"] = m_gs.ctm.inverse();
            } catch (const std::domain_error&) {
                throw SceneError(dir.loc, "the camera transform is singular");
            }
        } else if (d == "Film") {
            need_world(dir, false);
            m_desc.film = entity(dir);
        } else if (d == "Sampler") {
            need_world(dir, false);
            m_desc.sampler = entity(dir);
        } else if (d == "PixelFilter") {
            need_world(dir, false);
            m_desc.filter = entity(dir);
        } else if (d == "Integrator" || d == "SurfaceIntegrator") {
            need_world(dir, false);
            m_desc.integrator = entity(dir);
        } else if (d == "Accelerator") {
            need_world(dir, false);
            m_desc.accelerator = entity(dir);
        } else if (d == "Texture") {
            need_world(dir, true);
            TextureDesc t;
            t.name = expect_string(dir, "a quoted texture name");
            std::string kind = expect_string(dir, "\"float\" or \"spectrum\"");
            if (kind == "float")
                t.is_float = true;
            else if (kind == "spectrum" || kind == "color" || kind == "rgb")
                t.is_float = false;
            else
                throw SceneError(dir.loc,
                                 "texture type must be \"float\" or \"spectrum\", got " + q(kind));
            t.entity = entity(dir);
            t.world_from_texture = m_gs.ctm;
            t.scope = m_names.scope_for(t.entity.params);
            if (m_names.bind(t.is_float ? m_names.float_textures : m_names.spectrum_textures,
                             t.name, static_cast<int>(m_desc.textures.size()), !m_stack.empty()))
                warn(dir.loc, "texture " + q(t.name) + " redefined");
            m_desc.textures.push_back(std::move(t));
        } else if (d == "Material") {
            need_world(dir, true);
            MaterialDesc m;
            m.entity = entity(dir);
            m.scope = m_names.scope_for(m.entity.params);
            resolve_mix(m);
            m_gs.material = static_cast<int>(m_desc.materials.size());
            m_desc.materials.push_back(std::move(m));
        } else if (d == "MakeNamedMaterial") {
            need_world(dir, true);
            MaterialDesc m;
            m.name = expect_string(dir, "a quoted material name");
            m.entity.loc = dir.loc;
            m.entity.params = param_list();
            m.entity.given = true;
            const Param* type = m.entity.params.find("type");
            if (!type)
                throw SceneError(dir.loc, "MakeNamedMaterial " + q(m.name) +
                                              " needs a \"string type\" parameter");
            m.entity.type = m.entity.params.get_string("type", "");
            m.scope = m_names.scope_for(m.entity.params);
            resolve_mix(m);
            if (m_names.bind(m_names.materials, m.name, static_cast<int>(m_desc.materials.size()),
                             !m_stack.empty()))
                warn(dir.loc, "named material " + q(m.name) + " redefined");
            m_desc.materials.push_back(std::move(m));
        } else if (d == "NamedMaterial") {
            need_world(dir, true);
            std::string name = expect_string(dir, "a quoted material name");
            auto it = m_names.materials.find(name);
            if (it == m_names.materials.end())
                warn(dir.loc, "named material " + q(name) +
                                  " is not defined; the current material is kept (as pbrt-v3 "
                                  "does)");
            else
                m_gs.material = it->second;
        } else if (d == "Shape") {
            need_world(dir, true);
            ShapeDesc s;
            s.entity = entity(dir);
            s.world_from_object = m_gs.ctm;
            s.reverse_orientation = m_gs.reverse_orientation;
            s.material = m_gs.material;
            s.area_light = m_gs.area_light;
            s.scope = m_names.scope_for(s.entity.params);
            if (m_in_object && s.area_light >= 0) {
                warn(dir.loc,
                     "this shape is inside an object definition: pbrt-v3 does not make instanced "
                     "shapes area lights, so it does not emit");
                s.area_light = -1;
            }
            if (m_in_object)
                m_desc.objects[m_objects[m_object_name]].shapes.push_back(std::move(s));
            else
                m_desc.shapes.push_back(std::move(s));
        } else if (d == "LightSource") {
            need_world(dir, true);
            LightDesc l;
            l.entity = entity(dir);
            l.world_from_light = m_gs.ctm;
            m_desc.lights.push_back(std::move(l));
        } else if (d == "ObjectBegin") {
            need_world(dir, true);
            if (m_in_object)
                throw SceneError(dir.loc,
                                 "ObjectBegin inside the definition of object " + q(m_object_name));
            m_object_name = expect_string(dir, "a quoted object name");
            // A redefinition is a new object: instances before it keep the old one (pbrt-v3).
            if (m_objects.count(m_object_name))
                warn(dir.loc, "object " + q(m_object_name) + " redefined");
            m_objects[m_object_name] = static_cast<int>(m_desc.objects.size());
            m_desc.objects.push_back({m_object_name, {}, dir.loc});
            m_in_object = true;
            m_object_loc = dir.loc;
            m_stack.push_back({StackEntry::Kind::Object, dir.loc, m_gs, m_names.mark()});
        } else if (d == "ObjectEnd") {
            if (!m_in_object) throw SceneError(dir.loc, "ObjectEnd without ObjectBegin");
            // Blocks opened inside the object are closed first (the object's own entry is the
            // innermost ObjectBegin: objects do not nest).
            if (m_stack.back().kind != StackEntry::Kind::Object)
                throw SceneError(dir.loc, "ObjectEnd does not match " +
                                              std::string(m_stack.back().begin()) + " at " +
                                              m_stack.back().loc.to_string() + " inside object " +
                                              q(m_object_name));
            restore_attributes();
            m_stack.pop_back();
            m_in_object = false;
        } else if (d == "ObjectInstance") {
            need_world(dir, true);
            std::string name = expect_string(dir, "a quoted object name");
            if (m_in_object)
                throw SceneError(dir.loc, "ObjectInstance inside an object definition");
            auto it = m_objects.find(name);
            if (it == m_objects.end())
                throw SceneError(dir.loc, "object " + q(name) + " is not defined");
            m_desc.instances.push_back({it->second, m_gs.ctm, dir.loc});
        } else if (d == "AreaLightSource") {
            need_world(dir, true);
            m_gs.area_light = static_cast<int>(m_desc.area_lights.size());
            m_desc.area_lights.push_back(entity(dir));
        } else if (d == "ActiveTransform") {
            Token t = expect_any(dir, "All, StartTime or EndTime");
            warn(dir.loc, "ActiveTransform " + t.text + " ignored: cmam renders no motion blur");
        } else if (d == "TransformTimes") {
            numbers(dir, 2, false);
            warn(dir.loc, "TransformTimes ignored: cmam renders no motion blur");
        } else if (d == "MakeNamedMedium") {
            expect_string(dir, "a quoted medium name");
            param_list();
            warn(dir.loc, "MakeNamedMedium ignored: cmam renders no participating media");
        } else if (d == "MediumInterface") {
            expect_string(dir, "a quoted medium name");
            if (peek() && peek()->quoted) next();
            warn(dir.loc, "MediumInterface ignored: cmam renders no participating media");
        } else {
            throw SceneError(
                dir.loc, "unknown directive " + d + " (supported: " + kSupportedDirectives + ")");
        }
    }
};

}  // namespace

SceneDesc parse_file(const std::string& path, const WarningSink& warn) {
    return Parser(warn).run(Tokenizer::from_file(path, FileLoc{}));
}

SceneDesc parse_string(const std::string& text, const std::string& filename,
                       const WarningSink& warn) {
    return Parser(warn).run(Tokenizer(filename, text));
}

}  // namespace cmam::pbrt
