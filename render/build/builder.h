// render — scene building's private header: the Builder that turns a parsed pbrt-v3
// description into a renderable Scene. Its members are defined by responsibility:
// builder.cpp (run, shared checks), film_camera.cpp, textures.cpp, materials.cpp, shapes.cpp
// (shapes, instances, area lights) and lights.cpp.
#pragma once

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pbrt/error.h"
#include "pbrt/ply.h"
#include "pbrt/scene_desc.h"
#include "render/scene.h"
#include "render/tessellate.h"

namespace cmam::render::build_detail {

using pbrt::Entity;
using pbrt::Mat4;
using pbrt::SceneError;
using pbrt::TextureScope;

// `s` in double quotes, as messages name types and parameters.
std::string q(const std::string& s);
// The top three rows of `m`, row by row.
std::array<double, 12> to34(const Mat4& m);

class Builder {
  public:
    Builder(const pbrt::SceneDesc& d, const BuildOptions& o, const pbrt::WarningSink& w)
        : m_desc(d), m_opts(o), m_warn(w) {}

    std::unique_ptr<Scene> run();

  private:
    const pbrt::SceneDesc& m_desc;
    BuildOptions m_opts;
    pbrt::WarningSink m_warn;
    std::unique_ptr<Scene> m_scene;
    std::map<std::string, std::unique_ptr<pbrt::PlyMesh>> m_ply;  // by resolved path
    std::vector<Light> m_area_lights;  // per AreaLightSource: what each shape in its scope emits
    bool m_light_samples = false;      // lights' nsamples are used (directlighting, "all")

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
    static Mat4 inverse_or_error(const Mat4& m, const pbrt::FileLoc& loc, const char* message);
    static void finite_transform(const Mat4& m, const pbrt::FileLoc& loc, const char* what);
    static Vec3 to_vec(const std::array<double, 3>& a);
    static Rgb to_rgb(const pbrt::Rgb& c);

    // --- film, camera, sampler, pixel filter, integrator (film_camera.cpp) -----------------
    void film();
    void camera();
    static void check_camera_rays(const Camera& c, const pbrt::FileLoc& loc);
    void sampler();
    void filter();
    void integrator();

    // --- textures (textures.cpp) ----------------------------------------------------------
    TexInput spectrum_input(const Entity& e, const TextureScope& scope, const std::string& name,
                            Rgb def);
    TexInput float_input(const Entity& e, const TextureScope& scope, const std::string& name,
                         float def, bool positive = false);
    void uv_mapping(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n);
    void texture_space(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n);
    const texture::FilteredTexture* load_image(const Entity& e, bool is_float);
    void texture(const pbrt::TextureDesc& t);

    // --- materials (materials.cpp) --------------------------------------------------------
    TexInput rough_input(const Entity& e, const TextureScope& s, float def);
    Material material(const pbrt::MaterialDesc& d);

    // --- shapes, instances and area lights (shapes.cpp) -----------------------------------
    void shape(const pbrt::ShapeDesc& s, std::vector<std::unique_ptr<Primitive>>& out);
    void instances();
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
};

}  // namespace cmam::render::build_detail
