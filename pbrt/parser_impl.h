// pbrt — the parser's own parts, private to the library: the state pbrt-v3 keeps while reading a
// file, and the table of directives. parser.cpp reads tokens, parameter lists and Included
// files and recovers from errors; directives.cpp holds the table and what each directive does.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "pbrt/error.h"
#include "pbrt/scene_desc.h"
#include "pbrt/tokenizer.h"

namespace cmam::pbrt::detail {

// The part of pbrt-v3's graphics state copied at each AttributeBegin. Named textures and
// materials, also scoped by AttributeBegin/End, are kept in NamedTables instead.
struct GraphicsState {
    Mat4 ctm = Mat4::identity();
    bool reverse_orientation = false;
    int material = -1;
    int area_light = -1;  // the AreaLightSource in effect (index into SceneDesc::area_lights)
    // The MediumInterface in effect: names, looked up when a shape uses them (as pbrt-v3 does).
    std::string inside_medium, outside_medium;
};

// The named textures and materials visible at the current point of the file: one table each,
// changed in place. Each change made inside a block is logged with the value it replaced, so
// AttributeEnd undoes the block's declarations; nothing is copied per block or per directive.
class NamedTables {
  public:
    std::map<std::string, int> float_textures, spectrum_textures, materials;

    // Binds `name` to `index`; true when it was bound already (a redefinition).
    bool bind(std::map<std::string, int>& table, const std::string& name, int index, bool in_block);
    std::size_t mark() const { return m_undo.size(); }
    void undo_to(std::size_t mark);
    // The textures `params` name, as visible now (what the builder resolves them against).
    TextureScope scope_for(const ParamSet& params) const;

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

    static const char* begin(Kind k) {
        return k == Kind::Attribute   ? "AttributeBegin"
               : k == Kind::Transform ? "TransformBegin"
                                      : "ObjectBegin";
    }
    const char* begin() const { return begin(kind); }
};

// A bare word starting with a capital letter: the shape of every directive name (parameters
// are quoted, values quoted or numbers). Error recovery skips to the next such word.
constexpr bool is_directive_shape(std::string_view word) {
    return !word.empty() && word[0] >= 'A' && word[0] <= 'Z';
}

class Parser;

// Where a directive may stand relative to the world block.
enum class Block {
    Anywhere,
    Options,  // before WorldBegin only
    World,    // inside WorldBegin ... WorldEnd only
};

// How much of a directive cmam takes.
enum class Support {
    Full,     // read as pbrt-v3 reads it; listed when an unknown directive is reported
    Alias,    // another name of a listed directive (pbrt-v2's SurfaceIntegrator)
    Ignored,  // read and dropped with a warning (motion blur)
};

struct Directive {
    std::string_view name;
    void (Parser::*handle)(const Token& dir);
    Block block;
    Support support;
};

class Parser {
  public:
    explicit Parser(const WarningSink& warn) : m_warn(warn) {}

    SceneDesc run(Tokenizer root);

    /// Every directive the parser reads, the fully supported ones first, in the order the
    /// unknown-directive error lists them.
    static std::span<const Directive> directives();

  private:
    struct Source {
        Tokenizer tokens;
        std::string canonical;
    };
    std::vector<std::unique_ptr<Source>> m_files;
    std::unordered_set<std::string> m_reading;  // the canonical names of m_files: the cycle check
    std::optional<Token> m_peeked;
    WarningSink m_warn;
    SceneDesc m_desc;
    GraphicsState m_gs;
    NamedTables m_names;
    std::vector<StackEntry> m_stack;
    std::map<std::string, Mat4> m_coord_systems;
    std::map<std::string, int> m_objects;     // name -> index in m_desc.objects (the latest)
    std::map<std::string, int> m_media;       // name -> index in m_desc.media (the latest)
    std::set<std::string> m_undefined_media;  // names warned about as undefined (once each)
    int medium_index(const std::string& name, const FileLoc& loc);
    bool m_world_begun = false, m_world_ended = false;
    bool m_in_object = false;
    std::string m_object_name;
    FileLoc m_object_loc, m_last_loc;

    // Reading (parser.cpp).
    static bool is_directive_word(const Token& t) {
        return !t.quoted && is_directive_shape(t.text);
    }
    bool skip_to_directive(std::vector<SceneError>& errors);
    void push_file(Tokenizer t);
    std::optional<Token> next();
    const Token* peek();
    Token expect_any(const Token& after, const char* what);
    std::string expect_string(const Token& dir, const char* what);
    double expect_number(const Token& dir);
    // A number token's value: number_of says whether there is one, to_number throws when not,
    // naming `context`.
    static bool number_of(const Token& t, double& v);
    static double to_number(const Token& t, const std::string& context);
    std::vector<double> numbers(const Token& dir, int n, bool allow_brackets);
    ParamSet param_list();
    Param param_declaration(const Token& decl);
    void add_value(Param& p, const Token& v);
    void read_spd(Param& p);
    Entity entity(const Token& dir);
    void warn(const FileLoc& loc, const std::string& msg);
    void directive(const Token& dir);
    void check_block(const Token& dir, Block block) const;
    static const std::string& supported_list();
    void include(const Token& dir);

    // The directives (directives.cpp).
    void look_at(const Token& dir);
    void translate(const Token& dir);
    void rotate(const Token& dir);
    void scale(const Token& dir);
    void transform(const Token& dir);
    void concat_transform(const Token& dir);
    Mat4 matrix(const Token& dir);
    void identity(const Token& dir);
    void coordinate_system(const Token& dir);
    void coord_sys_transform(const Token& dir);
    void reverse_orientation(const Token& dir);
    void world_begin(const Token& dir);
    void world_end(const Token& dir);
    void attribute_begin(const Token& dir);
    void attribute_end(const Token& dir);
    void transform_begin(const Token& dir);
    void transform_end(const Token& dir);
    void open_block(const Token& dir, StackEntry::Kind kind);
    void close_block(const Token& dir, StackEntry::Kind kind);
    void restore_attributes();
    void make_named_material(const Token& dir);
    void named_material(const Token& dir);
    void material(const Token& dir);
    void resolve_mix(MaterialDesc& m);
    void texture(const Token& dir);
    void shape(const Token& dir);
    void light_source(const Token& dir);
    void area_light_source(const Token& dir);
    void camera(const Token& dir);
    void film(const Token& dir);
    void sampler(const Token& dir);
    void pixel_filter(const Token& dir);
    void integrator(const Token& dir);
    void accelerator(const Token& dir);
    void object_begin(const Token& dir);
    void object_end(const Token& dir);
    void object_instance(const Token& dir);
    void active_transform(const Token& dir);
    void transform_times(const Token& dir);
    void make_named_medium(const Token& dir);
    void medium_interface(const Token& dir);
};

}  // namespace cmam::pbrt::detail
