// render — scene building: the Builder's run over the directives and the checks its parts
// share (finite numbers and transforms, parameter locations, warnings).
#include "render/build/builder.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/image_io.h"
#include "render/parallel.h"

namespace cmam::render::build_detail {

std::array<double, 12> to34(const Mat4& m) {
    std::array<double, 12> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) r[4 * i + j] = m.m[i][j];
    return r;
}

std::unique_ptr<Scene> Builder::run() {
    m_scene = std::make_unique<Scene>();
    m_scene->tags = m_opts.tags;
    m_scene->cmam = m_opts.cmam;
    // Each directive's problem is collected and building goes on, so that one run reports
    // every error it can find (up to pbrt::kMaxReportedErrors): a missing file does not hide
    // the next.
    std::vector<SceneError> errors;
    auto attempt = [&](auto&& build) {
        if (errors.size() >= pbrt::kMaxReportedErrors) return;
        try {
            build();
        } catch (const SceneError& e) {
            errors.push_back(e);
        }
    };
    attempt([&] { film(); });
    attempt([&] { camera(); });
    attempt([&] { sampler(); });
    attempt([&] { filter(); });
    attempt([&] { integrator(); });
    attempt([&] { media(); });
    attempt([&] {
        if (m_desc.accelerator.given)
            m_desc.accelerator.params.check_unused("Accelerator", m_warn,
                                                   names_of(m_desc.accelerator));
    });
    read_ahead();
    // A texture, material or area light that fails keeps its index (a placeholder), so
    // that what names it is still checked.
    for (std::size_t i = 0; i < m_desc.textures.size(); ++i) {
        attempt([&] { texture(m_desc.textures[i]); });
        m_scene->textures.resize(i + 1);
    }
    for (const auto& m : m_desc.materials) {
        Material mat;
        attempt([&] { mat = material(m); });
        m_scene->materials.push_back(mat);
    }
    for (const auto& a : m_desc.area_lights) {
        Light l;
        attempt([&] { l = area_light(a); });
        m_area_lights.push_back(l);
    }
    for (const auto& s : m_desc.shapes) attempt([&] { shape(s, m_scene->primitives); });
    attempt([&] { instances(); });
    for (const auto& l : m_desc.lights) attempt([&] { light(l); });
    if (!errors.empty()) throw SceneError(errors);
    if (m_scene->lights.empty() && !m_scene->ambient_occlusion &&  // (which needs none)
        (!m_desc.shapes.empty() || !m_desc.instances.empty()) && m_warn)
        m_warn(pbrt::format_warning(m_desc.camera.loc,
                                    "the scene has no lights; it will render black"));
    m_scene->commit();
    return std::move(m_scene);
}

// The image textures' files, the meshes' PLY files and the lights' maps, read before the
// directives are built, in parallel: decoding them is most of loading a scene that has several. A
// directive whose parameters are in error is left to report it when built (its file is not read
// ahead), and a file's own error is kept for its directive, so that errors and warnings come in the
// order and at the places they would without reading ahead. Meshes read together are checked
// against the memory limit together (check_mesh_memory). Only the objects that instances use are
// read.
void Builder::read_ahead() {
    struct Job {
        const Entity* entity = nullptr;
        ImageRequest image;       // an image texture's, or
        std::string ply;          // a mesh file's path, or
        std::string light_image;  // a light's map's path
    };
    std::vector<Job> jobs;
    for (const pbrt::TextureDesc& t : m_desc.textures) {
        if (t.entity.type != "imagemap") continue;
        try {
            ImageRequest r = image_request(t.entity, t.is_float);
            if (m_read_images.emplace(r.key, ReadImage{}).second)
                jobs.push_back({&t.entity, std::move(r), {}, {}});
        } catch (...) {  // reported when the texture is built
        }
    }
    auto mesh_file = [&](const pbrt::ShapeDesc& s) {
        const auto* fp = s.entity.params.find("filename");
        if (s.entity.type != "plymesh" || !fp) return;
        try {
            std::string path = pbrt::resolve_path(m_desc.base_dir, fp->loc,
                                                  s.entity.params.get_string("filename", ""));
            if (m_read_plys.emplace(path, ReadPly{}).second)
                jobs.push_back({&s.entity, {}, std::move(path), {}});
        } catch (...) {
        }
    };
    for (const pbrt::ShapeDesc& s : m_desc.shapes) mesh_file(s);
    std::vector<bool> used(m_desc.objects.size(), false);
    for (const pbrt::InstanceDesc& d : m_desc.instances)
        if (d.object >= 0 && static_cast<std::size_t>(d.object) < used.size() &&
            !used[static_cast<std::size_t>(d.object)]) {
            used[static_cast<std::size_t>(d.object)] = true;
            for (const pbrt::ShapeDesc& s :
                 m_desc.objects[static_cast<std::size_t>(d.object)].shapes)
                mesh_file(s);
        }
    // The maps of infinite, goniometric and projection lights (light_image).
    for (const pbrt::LightDesc& l : m_desc.lights) {
        const auto* mp = l.entity.params.find("mapname");
        if (!mp || (l.entity.type != "infinite" && l.entity.type != "goniometric" &&
                    l.entity.type != "projection"))
            continue;
        try {
            std::string path = pbrt::resolve_path(m_desc.base_dir, mp->loc,
                                                  l.entity.params.get_string("mapname", ""));
            if (m_read_light_images.emplace(path, ReadImage{}).second)
                jobs.push_back({&l.entity, {}, {}, std::move(path)});
        } catch (...) {
        }
    }
    if (jobs.size() < 2) {  // nothing to read side by side: read where it is used
        m_read_images.clear();
        m_read_plys.clear();
        m_read_light_images.clear();
        return;
    }
    parallel_range_on(static_cast<int>(jobs.size()), m_opts.threads, [&](int begin, int end) {
        for (int i = begin; i < end; ++i) {
            const Job& job = jobs[static_cast<std::size_t>(i)];
            if (!job.light_image.empty()) {
                ReadImage& out = m_read_light_images.at(job.light_image);
                try {
                    out.image = load_light_map(job.light_image);
                } catch (...) {
                    out.error = std::current_exception();
                }
                continue;
            }
            if (job.ply.empty()) {
                const ImageRequest& r = job.image;
                ReadImage& out = m_read_images.at(r.key);
                try {
                    out.image = load_texture(r.path, r.is_float, r.gamma, r.scale, r.wrap, nullptr,
                                             true, &out.bad);
                } catch (...) {
                    out.error = std::current_exception();
                }
                continue;
            }
            ReadPly& out = m_read_plys.at(job.ply);
            const auto* fp = job.entity->params.find("filename");
            const std::string name = in_quotes(std::filesystem::path(job.ply).filename().string());
            double reserved = 0;
            auto check = [&](const pbrt::PlyCounts& c) {
                check_mesh_memory(fp->loc, name, c, true);
                reserved = mesh_memory_need(c);
            };
            try {
                out.mesh = std::make_unique<pbrt::PlyMesh>(pbrt::read_ply(job.ply, check));
            } catch (...) {
                out.error = std::current_exception();
            }
            if (reserved > 0) {
                std::lock_guard<std::mutex> lock(m_mesh_memory_mutex);
                m_mesh_memory_reserved -= reserved;
            }
        }
    });
}

// Shadow rays per shading point for a light: under pbrt-v3's directlighting integrator, which
// reads them, its "samples", or else its "nsamples" (pbrt-v3's infinite and diffuse area lights
// read both, "samples" first); 1 otherwise, as pbrt-v3's whitted and path take. Read either way
// (no warning): pbrt-v3 reads it whatever the integrator.
int Builder::light_samples(const Entity& e) const {
    const char* name = e.params.find("samples") ? "samples" : "nsamples";
    if (!e.params.find(name)) return 1;
    const int n = std::clamp(e.params.get_int(name, 1), 1, 1 << 16);
    return m_light_samples ? n : 1;
}

void Builder::warn(const pbrt::FileLoc& loc, const std::string& msg) {
    if (m_warn) m_warn(pbrt::format_warning(loc, msg));
}

// Where a parameter was written, or the directive's location when it was not.
const pbrt::FileLoc& Builder::loc_of(const Entity& e, const std::string& name) {
    const pbrt::Param* p = e.params.find(name);
    return p ? p->loc : e.loc;
}

std::vector<std::string> Builder::names_of(const Entity& e) {
    std::vector<std::string> n;
    for (const auto& p : e.params.params()) n.push_back(p.name);
    return n;
}

// Numbers the renderer uses must be finite in single precision (a NaN or infinite light,
// material or shape parameter would render black without a word).
bool Builder::is_finite_float(double v) {
    return std::abs(v) <= std::numeric_limits<float>::max();
}

double Builder::finite(const pbrt::FileLoc& loc, const std::string& name, double v, bool positive) {
    if (!is_finite_float(v) || (positive && !(v > 0)))
        throw SceneError(loc, name + " must be a " + (positive ? "positive " : "") +
                                  "finite number, got " + pbrt::number_text(v));
    return v;
}

double Builder::finite_float(const Entity& e, const std::string& name, double def, bool positive) {
    return finite(loc_of(e, name), name, e.params.get_float(name, def), positive);
}

// The point3 parameter `name` (`def` when not given), every coordinate finite.
std::array<double, 3> Builder::finite_point(const Entity& e, const std::string& name,
                                            const std::array<double, 3>& def) {
    return finite_values(e, name, e.params.get_point3(name, def));
}

// The inverse of `m`, or `message` at `loc` when m is singular.
Mat4 Builder::inverse_or_error(const Mat4& m, const pbrt::FileLoc& loc, const char* message) {
    try {
        return m.inverse();
    } catch (const SceneError&) {
        throw SceneError(loc, message);
    }
}

// A shape's or light's transform: every entry finite (NaN or infinite transforms would give
// black images).
void Builder::finite_transform(const Mat4& m, const pbrt::FileLoc& loc, const char* what) {
    for (const auto& row : m.m)
        for (double v : row)
            if (!is_finite_float(v))
                throw SceneError(loc, std::string("the ") + what +
                                          "'s transform must be finite, got an entry of " +
                                          pbrt::number_text(v));
}

Vec3 Builder::to_vec(const std::array<double, 3>& a) {
    return Vec3(float(a[0]), float(a[1]), float(a[2]));
}

Rgb Builder::to_rgb(const pbrt::Rgb& c) {
    return Rgb(c[0], c[1], c[2]);
}

}  // namespace cmam::render::build_detail

namespace cmam::render {

std::unique_ptr<Scene> build_scene(const pbrt::SceneDesc& desc, const BuildOptions& options,
                                   const pbrt::WarningSink& warn) {
    return build_detail::Builder(desc, options, warn).run();
}

}  // namespace cmam::render
