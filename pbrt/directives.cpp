// pbrt — what each directive does to the graphics state and the scene description, and the
// table that names them.
#include "pbrt/parser_impl.h"

namespace cmam::pbrt::detail {

namespace {

// Every name has a directive's shape (so error recovery stops at it) and is given once.
constexpr bool well_formed(std::span<const Directive> table) {
    for (std::size_t i = 0; i < table.size(); ++i) {
        if (!is_directive_shape(table[i].name)) return false;
        for (std::size_t k = 0; k < i; ++k)
            if (table[k].name == table[i].name) return false;
    }
    return true;
}

}  // namespace

std::span<const Directive> Parser::directives() {
    using B = Block;
    using S = Support;
    static constexpr Directive kTable[] = {
        {"LookAt", &Parser::look_at, B::Anywhere, S::Full},
        {"Translate", &Parser::translate, B::Anywhere, S::Full},
        {"Rotate", &Parser::rotate, B::Anywhere, S::Full},
        {"Scale", &Parser::scale, B::Anywhere, S::Full},
        {"Transform", &Parser::transform, B::Anywhere, S::Full},
        {"ConcatTransform", &Parser::concat_transform, B::Anywhere, S::Full},
        {"Identity", &Parser::identity, B::Anywhere, S::Full},
        {"CoordinateSystem", &Parser::coordinate_system, B::Anywhere, S::Full},
        {"CoordSysTransform", &Parser::coord_sys_transform, B::Anywhere, S::Full},
        {"ReverseOrientation", &Parser::reverse_orientation, B::Anywhere, S::Full},
        {"WorldBegin", &Parser::world_begin, B::Options, S::Full},
        {"WorldEnd", &Parser::world_end, B::World, S::Full},
        {"AttributeBegin", &Parser::attribute_begin, B::Anywhere, S::Full},
        {"AttributeEnd", &Parser::attribute_end, B::Anywhere, S::Full},
        {"TransformBegin", &Parser::transform_begin, B::Anywhere, S::Full},
        {"TransformEnd", &Parser::transform_end, B::Anywhere, S::Full},
        {"Include", &Parser::include, B::Anywhere, S::Full},
        {"MakeNamedMaterial", &Parser::make_named_material, B::World, S::Full},
        {"NamedMaterial", &Parser::named_material, B::World, S::Full},
        {"Material", &Parser::material, B::World, S::Full},
        {"Texture", &Parser::texture, B::World, S::Full},
        {"Shape", &Parser::shape, B::World, S::Full},
        {"LightSource", &Parser::light_source, B::World, S::Full},
        {"AreaLightSource", &Parser::area_light_source, B::World, S::Full},
        {"Camera", &Parser::camera, B::Options, S::Full},
        {"Film", &Parser::film, B::Options, S::Full},
        {"Sampler", &Parser::sampler, B::Options, S::Full},
        {"PixelFilter", &Parser::pixel_filter, B::Options, S::Full},
        {"Integrator", &Parser::integrator, B::Options, S::Full},
        {"Accelerator", &Parser::accelerator, B::Options, S::Full},
        {"ObjectBegin", &Parser::object_begin, B::World, S::Full},
        {"ObjectEnd", &Parser::object_end, B::Anywhere, S::Full},
        {"ObjectInstance", &Parser::object_instance, B::World, S::Full},
        {"SurfaceIntegrator", &Parser::integrator, B::Options, S::Alias},
        {"MakeNamedMedium", &Parser::make_named_medium, B::Anywhere, S::Full},
        {"MediumInterface", &Parser::medium_interface, B::Anywhere, S::Full},
        {"ActiveTransform", &Parser::active_transform, B::Anywhere, S::Ignored},
        {"TransformTimes", &Parser::transform_times, B::Anywhere, S::Ignored},
    };
    static_assert(well_formed(kTable));
    return kTable;
}

// Transforms.

void Parser::look_at(const Token& dir) {
    auto v = numbers(dir, 9, false);
    try {
        m_gs.ctm =
            m_gs.ctm * pbrt::look_at({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]});
    } catch (const SceneError& e) {
        throw SceneError(dir.loc, e.message());
    }
}

void Parser::translate(const Token& dir) {
    auto v = numbers(dir, 3, false);
    m_gs.ctm = m_gs.ctm * pbrt::translate(v[0], v[1], v[2]);
}

void Parser::rotate(const Token& dir) {
    auto v = numbers(dir, 4, false);
    if (v[1] == 0 && v[2] == 0 && v[3] == 0)
        throw SceneError(dir.loc, "Rotate axis has zero length");
    m_gs.ctm = m_gs.ctm * pbrt::rotate(v[0], v[1], v[2], v[3]);
}

void Parser::scale(const Token& dir) {
    auto v = numbers(dir, 3, false);
    m_gs.ctm = m_gs.ctm * pbrt::scale(v[0], v[1], v[2]);
}

void Parser::transform(const Token& dir) {
    m_gs.ctm = matrix(dir);
}

void Parser::concat_transform(const Token& dir) {
    m_gs.ctm = m_gs.ctm * matrix(dir);
}

// The 16 numbers of Transform and ConcatTransform, which list the matrix column by column
// (pbrt-v3 transposes them).
Mat4 Parser::matrix(const Token& dir) {
    auto v = numbers(dir, 16, true);
    Mat4 m;
    for (int i = 0; i < 16; ++i) m.m[i / 4][i % 4] = v[i];
    return m.transposed();
}

void Parser::identity(const Token&) {
    m_gs.ctm = Mat4::identity();
}

void Parser::coordinate_system(const Token& dir) {
    m_coord_systems[expect_string(dir, "a quoted name")] = m_gs.ctm;
}

void Parser::coord_sys_transform(const Token& dir) {
    std::string name = expect_string(dir, "a quoted name");
    auto it = m_coord_systems.find(name);
    if (it == m_coord_systems.end())
        throw SceneError(dir.loc, "coordinate system " + in_quotes(name) + " is not defined");
    m_gs.ctm = it->second;
}

void Parser::reverse_orientation(const Token&) {
    m_gs.reverse_orientation = !m_gs.reverse_orientation;
}

// The world block and the blocks that restore the graphics state.

void Parser::world_begin(const Token&) {
    m_world_begun = true;
    m_gs.ctm = Mat4::identity();
    m_coord_systems["world"] = m_gs.ctm;
}

void Parser::world_end(const Token& dir) {
    if (!m_stack.empty())
        throw SceneError(m_stack.back().loc,
                         std::string(m_stack.back().begin()) + " is not closed before WorldEnd");
    m_world_ended = true;
    // pbrt-v3 makes the camera when the world ends, in the medium outside the interface then.
    m_desc.camera_medium = medium_index(m_gs.outside_medium, dir.loc);
}

void Parser::attribute_begin(const Token& dir) {
    open_block(dir, StackEntry::Kind::Attribute);
}

void Parser::attribute_end(const Token& dir) {
    close_block(dir, StackEntry::Kind::Attribute);
}

void Parser::transform_begin(const Token& dir) {
    open_block(dir, StackEntry::Kind::Transform);
}

void Parser::transform_end(const Token& dir) {
    close_block(dir, StackEntry::Kind::Transform);
}

void Parser::open_block(const Token& dir, StackEntry::Kind kind) {
    m_stack.push_back({kind, dir.loc, m_gs, m_names.mark()});
}

// AttributeEnd or TransformEnd: the innermost block must be its Begin.
void Parser::close_block(const Token& dir, StackEntry::Kind kind) {
    if (m_stack.empty())
        throw SceneError(dir.loc, dir.text + " without matching " + StackEntry::begin(kind));
    if (m_stack.back().kind != kind)
        throw SceneError(dir.loc, dir.text + " does not match " + m_stack.back().begin() + " at " +
                                      m_stack.back().loc.to_string());
    if (kind == StackEntry::Kind::Attribute)
        restore_attributes();
    else
        m_gs.ctm = m_stack.back().saved.ctm;
    m_stack.pop_back();
}

// AttributeEnd or ObjectEnd: the state and the names as the innermost block found them.
void Parser::restore_attributes() {
    m_gs = m_stack.back().saved;
    m_names.undo_to(m_stack.back().names_mark);
}

// Materials and textures.

void Parser::make_named_material(const Token& dir) {
    MaterialDesc m;
    m.name = expect_string(dir, "a quoted material name");
    m.entity.loc = dir.loc;
    m.entity.params = param_list();
    m.entity.given = true;
    if (!m.entity.params.find("type"))
        throw SceneError(dir.loc, "MakeNamedMaterial " + in_quotes(m.name) +
                                      " needs a \"string type\" parameter");
    m.entity.type = m.entity.params.get_string("type", "");
    m.scope = m_names.scope_for(m.entity.params);
    resolve_mix(m);
    if (m_names.bind(m_names.materials, m.name, static_cast<int>(m_desc.materials.size()),
                     !m_stack.empty()))
        warn(dir.loc, "named material " + in_quotes(m.name) + " redefined");
    m_desc.materials.push_back(std::move(m));
}

void Parser::named_material(const Token& dir) {
    std::string name = expect_string(dir, "a quoted material name");
    auto it = m_names.materials.find(name);
    if (it == m_names.materials.end())
        warn(dir.loc, "named material " + in_quotes(name) +
                          " is not defined; the current material is kept (as pbrt-v3 does)");
    else
        m_gs.material = it->second;
}

void Parser::material(const Token& dir) {
    MaterialDesc m;
    m.entity = entity(dir);
    m.scope = m_names.scope_for(m.entity.params);
    resolve_mix(m);
    m_gs.material = static_cast<int>(m_desc.materials.size());
    m_desc.materials.push_back(std::move(m));
}

// A "mix" material's two named materials, resolved where it is declared (as pbrt-v3 does).
void Parser::resolve_mix(MaterialDesc& m) {
    if (m.entity.type != "mix") return;
    for (int k = 0; k < 2; ++k) {
        const std::string param = "namedmaterial" + std::to_string(k + 1);
        if (!m.entity.params.find(param)) continue;  // the builder reports it
        const std::string name = m.entity.params.get_string(param, "");
        auto it = m_names.materials.find(name);
        if (it != m_names.materials.end()) m.mix[k] = it->second;
    }
}

void Parser::texture(const Token& dir) {
    TextureDesc t;
    t.name = expect_string(dir, "a quoted texture name");
    std::string kind = expect_string(dir, "\"float\" or \"spectrum\"");
    if (kind == "float")
        t.is_float = true;
    else if (kind == "spectrum" || kind == "color" || kind == "rgb")
        t.is_float = false;
    else
        throw SceneError(dir.loc,
                         "texture type must be \"float\" or \"spectrum\", got " + in_quotes(kind));
    t.entity = entity(dir);
    t.world_from_texture = m_gs.ctm;
    t.scope = m_names.scope_for(t.entity.params);
    if (m_names.bind(t.is_float ? m_names.float_textures : m_names.spectrum_textures, t.name,
                     static_cast<int>(m_desc.textures.size()), !m_stack.empty()))
        warn(dir.loc, "texture " + in_quotes(t.name) + " redefined");
    m_desc.textures.push_back(std::move(t));
}

// Shapes and lights.

void Parser::shape(const Token& dir) {
    ShapeDesc s;
    s.entity = entity(dir);
    s.world_from_object = m_gs.ctm;
    s.reverse_orientation = m_gs.reverse_orientation;
    s.material = m_gs.material;
    s.area_light = m_gs.area_light;
    s.scope = m_names.scope_for(s.entity.params);
    s.medium_inside = medium_index(m_gs.inside_medium, dir.loc);
    s.medium_outside = medium_index(m_gs.outside_medium, dir.loc);
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
}

void Parser::light_source(const Token& dir) {
    LightDesc l;
    l.entity = entity(dir);
    l.world_from_light = m_gs.ctm;
    m_desc.lights.push_back(std::move(l));
}

void Parser::area_light_source(const Token& dir) {
    m_gs.area_light = static_cast<int>(m_desc.area_lights.size());
    m_desc.area_lights.push_back(entity(dir));
}

// Rendering options (before WorldBegin).

void Parser::camera(const Token& dir) {
    m_desc.camera = entity(dir);
    m_desc.camera_from_world = m_gs.ctm;
    try {
        m_coord_systems["camera"] = m_gs.ctm.inverse();
    } catch (const SceneError&) {
        throw SceneError(dir.loc, "the camera transform is singular");
    }
}

void Parser::film(const Token& dir) {
    m_desc.film = entity(dir);
}

void Parser::sampler(const Token& dir) {
    m_desc.sampler = entity(dir);
}

void Parser::pixel_filter(const Token& dir) {
    m_desc.filter = entity(dir);
}

void Parser::integrator(const Token& dir) {
    m_desc.integrator = entity(dir);
}

void Parser::accelerator(const Token& dir) {
    m_desc.accelerator = entity(dir);
}

// Objects and instances.

void Parser::object_begin(const Token& dir) {
    if (m_in_object)
        throw SceneError(dir.loc,
                         "ObjectBegin inside the definition of object " + in_quotes(m_object_name));
    m_object_name = expect_string(dir, "a quoted object name");
    // A redefinition is a new object: instances before it keep the old one (pbrt-v3).
    if (m_objects.count(m_object_name))
        warn(dir.loc, "object " + in_quotes(m_object_name) + " redefined");
    m_objects[m_object_name] = static_cast<int>(m_desc.objects.size());
    m_desc.objects.push_back({m_object_name, {}, dir.loc});
    m_in_object = true;
    m_object_loc = dir.loc;
    m_stack.push_back({StackEntry::Kind::Object, dir.loc, m_gs, m_names.mark()});
}

void Parser::object_end(const Token& dir) {
    if (!m_in_object) throw SceneError(dir.loc, "ObjectEnd without ObjectBegin");
    // Blocks opened inside the object are closed first (the object's own entry is the
    // innermost ObjectBegin: objects do not nest).
    if (m_stack.back().kind != StackEntry::Kind::Object)
        throw SceneError(dir.loc, "ObjectEnd does not match " +
                                      std::string(m_stack.back().begin()) + " at " +
                                      m_stack.back().loc.to_string() + " inside object " +
                                      in_quotes(m_object_name));
    restore_attributes();
    m_stack.pop_back();
    m_in_object = false;
}

void Parser::object_instance(const Token& dir) {
    std::string name = expect_string(dir, "a quoted object name");
    if (m_in_object) throw SceneError(dir.loc, "ObjectInstance inside an object definition");
    auto it = m_objects.find(name);
    if (it == m_objects.end())
        throw SceneError(dir.loc, "object " + in_quotes(name) + " is not defined");
    m_desc.instances.push_back({it->second, m_gs.ctm, dir.loc});
}

// Directives read and dropped: cmam renders no motion blur.

void Parser::active_transform(const Token& dir) {
    Token t = expect_any(dir, "All, StartTime or EndTime");
    warn(dir.loc, "ActiveTransform " + t.text + " ignored: cmam renders no motion blur");
}

void Parser::transform_times(const Token& dir) {
    numbers(dir, 2, false);
    warn(dir.loc, "TransformTimes ignored: cmam renders no motion blur");
}

// Participating media. A medium is named globally (AttributeEnd does not scope it) and its
// "type" parameter says what it is; the builder reads the rest. MediumInterface names the media
// inside and outside the shapes that follow (one name: both), looked up at each shape, as pbrt-v3
// does; "" is vacuum.

void Parser::make_named_medium(const Token& dir) {
    MediumDesc m;
    m.name = expect_string(dir, "a quoted medium name");
    m.entity.params = param_list();
    m.entity.loc = dir.loc;
    m.entity.given = true;
    m.entity.type = m.entity.params.get_string("type", "");
    m.world_from_medium = m_gs.ctm;
    m_media[m.name] = static_cast<int>(m_desc.media.size());
    m_desc.media.push_back(std::move(m));
}

void Parser::medium_interface(const Token& dir) {
    m_gs.inside_medium = expect_string(dir, "a quoted medium name");
    m_gs.outside_medium = peek() && peek()->quoted ? next()->text : m_gs.inside_medium;
    if (m_desc.medium_interface.line == 0) m_desc.medium_interface = dir.loc;
}

// The medium named `name` as defined so far (-1 for "" and, with a warning at `loc` the first
// time, for a name not defined: pbrt-v3 reports it and takes vacuum).
int Parser::medium_index(const std::string& name, const FileLoc& loc) {
    if (name.empty()) return -1;
    if (auto it = m_media.find(name); it != m_media.end()) return it->second;
    if (m_undefined_media.insert(name).second)
        warn(loc, "medium " + in_quotes(name) + " is not defined; vacuum is used there");
    return -1;
}

// The named textures and materials.

bool NamedTables::bind(std::map<std::string, int>& table, const std::string& name, int index,
                       bool in_block) {
    auto [it, added] = table.try_emplace(name, index);
    if (in_block)
        m_undo.push_back({&table, name, added ? std::nullopt : std::optional(it->second)});
    it->second = index;
    return !added;
}

void NamedTables::undo_to(std::size_t mark) {
    for (; m_undo.size() > mark; m_undo.pop_back()) {
        const Change& c = m_undo.back();
        if (c.previous)
            (*c.table)[c.name] = *c.previous;
        else
            c.table->erase(c.name);
    }
}

TextureScope NamedTables::scope_for(const ParamSet& params) const {
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

}  // namespace cmam::pbrt::detail
