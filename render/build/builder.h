// render — scene building's private header: the Builder that turns a parsed pbrt-v3
// description into a renderable Scene. Its members are defined by responsibility:
// builder.cpp (run, shared checks), film_camera.cpp, textures.cpp, materials.cpp, shapes.cpp
// (shapes, instances, area lights) and lights.cpp.
#pragma once

#include <array>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pbrt/error.h"
#include "pbrt/ply.h"
#include "pbrt/scene_desc.h"
#include "render/build_scene.h"
#include "render/scene.h"
#include "render/subdivide.h"
#include "render/tessellate.h"

namespace cmam::render::build_detail {

using pbrt::Entity;
using pbrt::in_quotes;
using pbrt::Mat4;
using pbrt::SceneError;
using pbrt::TextureScope;

// The top three rows of `m`, row by row.
std::array<double, 12> to34(const Mat4& m);

// A type a directive renders and the member that builds it. One table per directive gives both
// the dispatch and the list of supported types in the error for any other.
template <class Build>
struct TypeBuilder {
    std::string_view name;
    Build build;
};

// The member that builds `type`; nullptr when the table does not name it.
template <class Build, std::size_t N>
Build find_builder(const TypeBuilder<Build> (&table)[N], const std::string& type) {
    for (const TypeBuilder<Build>& t : table)
        if (t.name == type) return t.build;
    return nullptr;
}

// The table's names in double quotes, separated by ", ".
template <class Build, std::size_t N>
std::string quoted_names(const TypeBuilder<Build> (&table)[N]) {
    std::string out;
    for (const TypeBuilder<Build>& t : table) {
        if (!out.empty()) out += ", ";
        out += in_quotes(std::string(t.name));
    }
    return out;
}

// The member that builds `e`'s type, or an error at `e` naming the types the table supports.
template <class Build, std::size_t N>
Build builder_for(const TypeBuilder<Build> (&table)[N], const Entity& e, const char* what) {
    if (const Build build = find_builder(table, e.type)) return build;
    throw SceneError(e.loc, std::string("unsupported ") + what + " " + in_quotes(e.type) +
                                " (supported: " + quoted_names(table) + ")");
}

class Builder {
  public:
    Builder(const pbrt::SceneDesc& d, const BuildOptions& o, const pbrt::WarningSink& w)
        : m_desc(d), m_opts(o), m_warn(w) {}

    std::unique_ptr<Scene> run();

  private:
    const pbrt::SceneDesc& m_desc;
    BuildOptions m_opts;
    pbrt::WarningSink m_warn;
    const pbrt::Mat4* m_placement = nullptr;  // the instance being built in place (instances())
    std::unique_ptr<Scene> m_scene;
    std::map<std::string, std::unique_ptr<pbrt::PlyMesh>> m_ply;           // by resolved path
    std::map<std::string, std::shared_ptr<const FourierTable>> m_fourier;  // by resolved path
    // Subsurface materials' profile tables, by (g, eta).
    std::map<std::pair<float, float>, std::shared_ptr<const BssrdfTable>> m_bssrdf_tables;
    std::map<std::string, std::string> m_fourier_errors;  // files that could not be read: why

    // Files read ahead, in parallel, before the directives are built in order (read_ahead):
    // each is taken by the directive that reads it, which reports its error (or warning) where
    // and when reading it there would have. A file not read ahead is read there.
    struct ReadImage {
        texture::Image image;
        std::size_t bad = 0;  // texel values that are not finite
        std::exception_ptr error;
    };
    std::map<std::string, ReadImage> m_read_images;        // by ImageRequest::key
    std::map<std::string, ReadImage> m_read_light_images;  // lights' maps, by resolved path
    struct ReadPly {
        std::unique_ptr<pbrt::PlyMesh> mesh;
        std::exception_ptr error;
    };
    std::map<std::string, ReadPly> m_read_plys;  // by resolved path
    // What mesh files being read ahead may still take (check_mesh_memory counts it as used).
    std::mutex m_mesh_memory_mutex;
    double m_mesh_memory_reserved = 0;
    void read_ahead();
    // What read_ahead read for `key` in `read`, taken out of it (a reading error rethrown
    // here, for the directive's own handling), or nullopt when it read nothing for it.
    template <class Read>
    static std::optional<Read> take_read_ahead(std::map<std::string, Read>& read,
                                               const std::string& key) {
        auto it = read.find(key);
        if (it == read.end()) return std::nullopt;
        Read r = std::move(it->second);
        read.erase(it);
        if (r.error) std::rethrow_exception(r.error);
        return r;
    }
    // A light's map as light_image reads it (8-bit files decoded from sRGB, repeated).
    static texture::Image load_light_map(const std::string& path);
    // Per texture node: how many nodes deep its evaluation recurses (itself included).
    std::vector<int> m_texture_depth;
    std::vector<Light> m_area_lights;  // per AreaLightSource: what each shape in its scope emits
    bool m_light_samples = false;      // lights' nsamples are used (directlighting, "all")
    double m_film_diagonal = 35;       // Film "diagonal" (mm): a realistic camera's film size

    // --- shared checks (builder.cpp) ------------------------------------------------------
    int light_samples(const Entity& e) const;
    void warn(const pbrt::FileLoc& loc, const std::string& msg);
    static const pbrt::FileLoc& loc_of(const Entity& e, const std::string& name);
    static std::vector<std::string> names_of(const Entity& e);
    static bool is_finite_float(double v);
    static double finite(const pbrt::FileLoc& loc, const std::string& name, double v,
                         bool positive = false);
    static double finite_float(const Entity& e, const std::string& name, double def,
                               bool positive = false);
    // `values`, or an error at the parameter naming the first that is not finite in single
    // precision.
    template <class Values>
    static const Values& finite_values(const Entity& e, const std::string& name,
                                       const Values& values) {
        for (double v : values)
            if (!is_finite_float(v))
                throw SceneError(loc_of(e, name), name + " values must be finite numbers, got " +
                                                      pbrt::number_text(v));
        return values;
    }
    static std::array<double, 3> finite_point(const Entity& e, const std::string& name,
                                              const std::array<double, 3>& def);
    static Mat4 inverse_or_error(const Mat4& m, const pbrt::FileLoc& loc, const char* message);
    static void finite_transform(const Mat4& m, const pbrt::FileLoc& loc, const char* what);
    static Vec3 to_vec(const std::array<double, 3>& a);
    static Rgb to_rgb(const pbrt::Rgb& c);

    // --- film, camera, sampler, pixel filter, integrator (film_camera.cpp) -----------------
    void film();
    void camera();
    void realistic_camera(const Entity& e, Camera& c);
    static void check_camera_rays(const Camera& c, const pbrt::FileLoc& loc);
    void sampler();
    void check_samples_per_row(const pbrt::FileLoc& loc) const;
    void filter();
    void integrator();
    void sppm_integrator(const Entity& e);
    void mlt_samples(const Entity& e);

    // --- participating media (media.cpp) -------------------------------------------------
    void media();
    int medium(int desc_index) const;  // the scene's medium of a MakeNamedMedium (-1: vacuum)
    std::vector<int> m_medium_index;   // per MakeNamedMedium: its index in Scene::media, or -1

    // --- textures (textures.cpp) ----------------------------------------------------------
    TexInput spectrum_input(const Entity& e, const TextureScope& scope, const std::string& name,
                            Rgb def);
    TexInput float_input(const Entity& e, const TextureScope& scope, const std::string& name,
                         float def, bool positive = false);
    void uv_mapping(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n);
    void texture_space(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n);
    // An image texture's file and the settings it is loaded under; `key` names the pair (the
    // same file under the same settings is loaded once). Throws for parameters in error.
    struct ImageRequest {
        std::string name, path, key;
        bool is_float = false;
        std::optional<bool> gamma;
        float scale = 1;
        texture::WrapMode wrap = texture::WrapMode::Repeat;
    };
    ImageRequest image_request(const Entity& e, bool is_float) const;
    const texture::FilteredTexture* load_image(const Entity& e, bool is_float);
    void texture(const pbrt::TextureDesc& t);
    // Each fills in the node of its texture class (or classes).
    using TextureBuild = void (Builder::*)(const pbrt::TextureDesc& t, TextureNode& n);
    TexInput texture_input(const pbrt::TextureDesc& t, const std::string& name, float def);
    void image_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void constant_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void checkerboard_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void scale_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void mix_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void bilerp_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void uv_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void dots_texture(const pbrt::TextureDesc& t, TextureNode& n);
    void noise_texture(const pbrt::TextureDesc& t, TextureNode& n);

    // --- materials (materials.cpp) --------------------------------------------------------
    // How a material falls back where "uroughness" or "vroughness" is absent (materials.cpp).
    enum class RoughFallback { Uber, Metal, Substrate };
    void rough_inputs(const Entity& e, const TextureScope& s, float def, RoughFallback f,
                      Material& m);
    Material material(const pbrt::MaterialDesc& d);
    // Each fills in the material of its type (or types).
    using MaterialBuild = void (Builder::*)(const pbrt::MaterialDesc& d, Material& m);
    void matte_material(const pbrt::MaterialDesc& d, Material& m);
    void mirror_material(const pbrt::MaterialDesc& d, Material& m);
    void glass_material(const pbrt::MaterialDesc& d, Material& m);
    void plastic_material(const pbrt::MaterialDesc& d, Material& m);
    void uber_material(const pbrt::MaterialDesc& d, Material& m);
    void substrate_material(const pbrt::MaterialDesc& d, Material& m);
    void translucent_material(const pbrt::MaterialDesc& d, Material& m);
    void metal_material(const pbrt::MaterialDesc& d, Material& m);
    void no_material(const pbrt::MaterialDesc& d, Material& m);
    void mix_material(const pbrt::MaterialDesc& d, Material& m);
    void fourier_material(const pbrt::MaterialDesc& d, Material& m);
    void hair_material(const pbrt::MaterialDesc& d, Material& m);
    void disney_material(const pbrt::MaterialDesc& d, Material& m);
    void subsurface_material(const pbrt::MaterialDesc& d, Material& m);
    void kd_subsurface_material(const pbrt::MaterialDesc& d, Material& m);
    void subsurface_common(const pbrt::MaterialDesc& d, Material& m);
    Material unrendered_material(const pbrt::MaterialDesc& d);

    // --- shapes, instances and area lights (shapes.cpp) -----------------------------------
    void shape(const pbrt::ShapeDesc& s, std::vector<std::unique_ptr<Primitive>>& out);
    // Each fills in the primitive of its shape (or shapes); false when it has no surface.
    using ShapeBuild = bool (Builder::*)(const pbrt::ShapeDesc& s, Primitive& prim);
    bool analytic_quadric(const pbrt::ShapeDesc& s, Primitive& prim);
    bool tessellated_quadric(const pbrt::ShapeDesc& s, Primitive& prim);
    bool ply_mesh(const pbrt::ShapeDesc& s, Primitive& prim);
    // `reserve`: the mesh is being read ahead; what it needs is counted as used until it is
    // read (read_ahead releases it), so that meshes read side by side are checked together.
    void check_mesh_memory(const pbrt::FileLoc& loc, const std::string& name,
                           const pbrt::PlyCounts& counts, bool reserve = false);
    static double mesh_memory_need(const pbrt::PlyCounts& counts);
    bool triangle_mesh(const pbrt::ShapeDesc& s, Primitive& prim);
    bool curve(const pbrt::ShapeDesc& s, Primitive& prim);
    bool heightfield(const pbrt::ShapeDesc& s, Primitive& prim);
    bool nurbs(const pbrt::ShapeDesc& s, Primitive& prim);
    bool subdivided_mesh(const pbrt::ShapeDesc& s, const std::vector<float>& P,
                         const std::vector<int>& idx, Primitive& prim);
    void mesh_primitive(const pbrt::ShapeDesc& s, Primitive& prim);
    bool degenerate_uvs(const pbrt::Entity& e, const std::vector<float>& P,
                        const std::vector<float>& N, const std::vector<float>& UV,
                        const std::vector<int>& idx);
    // How a placed mesh's normals turn with the shape's orientation: as a quadric's (every
    // flip of Primitive::flip), or as normals a mesh was given (ReverseOrientation alone).
    enum class NormalSide { Quadric, Given };
    bool place_mesh(const pbrt::ShapeDesc& s, const std::vector<float>& P,
                    const std::vector<float>& N, const std::vector<float>& UV,
                    const std::vector<int>& idx, Primitive& prim,
                    NormalSide side = NormalSide::Given);
    void emit_area_light(const pbrt::ShapeDesc& s, Primitive& prim);
    void instances();
    // The shape's world_from_object, placed by the instance being built in place (instances()).
    pbrt::Mat4 world_from(const pbrt::ShapeDesc& s) const {
        return m_placement ? *m_placement * s.world_from_object : s.world_from_object;
    }
    QuadricParams quadric_params(const Entity& e);
    static void round_sphere(Primitive& prim);
    Light area_light(const Entity& e);

    // --- lights (lights.cpp) --------------------------------------------------------------
    std::shared_ptr<const texture::FilteredTexture> light_image(const Entity& e,
                                                                const pbrt::Param& p);
    static std::array<float, 9> light_from_world(const Entity& e, const Mat4& world_from_light);
    std::shared_ptr<const EnvironmentMap> environment_map(const Entity& e, const pbrt::Param& p,
                                                          const Mat4& world_from_light);
    void light(const pbrt::LightDesc& d);
    // Each fills in the light of its type (or types).
    using LightBuild = void (Builder::*)(const pbrt::LightDesc& d, const Rgb& scale, Light& l);
    static Rgb light_scale(const Entity& e);
    static Rgb light_intensity(const Entity& e, const char* name, const Rgb& scale);
    void point_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l);
    void spot_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l);
    void distant_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l);
    void infinite_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l);
    void image_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l);
};

}  // namespace cmam::render::build_detail
