// render — scene building: participating media (MakeNamedMedium) and the integrators that render
// them (docs/algorithms.md §19).
#include <algorithm>

#include "render/build/builder.h"
#include "render/subsurface.h"

namespace cmam::render::build_detail {

// pbrt-v3's defaults, which its MakeNamedMedium takes where "sigma_a" and "sigma_s" are not
// given (per mm: whole milk).
constexpr Rgb kDefaultSigmaA(0.0011f, 0.0024f, 0.014f);
constexpr Rgb kDefaultSigmaS(2.55f, 3.21f, 3.77f);

void Builder::media() {
    m_medium_index.assign(m_desc.media.size(), -1);
    for (std::size_t i = 0; i < m_desc.media.size(); ++i) {
        const pbrt::MediumDesc& d = m_desc.media[i];
        const Entity& e = d.entity;
        Medium m;
        // What pbrt-v3 reports and renders without the medium (vacuum where it is named).
        auto drop = [&](const pbrt::FileLoc& loc, const std::string& why) {
            warn(loc, "medium " + in_quotes(d.name) + ": " + why + "; it is rendered as vacuum");
        };
        if (e.type.empty()) {
            drop(e.loc, "no \"string type\" is given (\"homogeneous\" or \"heterogeneous\")");
            continue;
        }
        if (e.type != "homogeneous" && e.type != "heterogeneous") {
            drop(loc_of(e, "type"), "unknown type " + in_quotes(e.type) +
                                        " (cmam renders \"homogeneous\" and \"heterogeneous\")");
            continue;
        }
        // A preset: pbrt-v3's measured media (subsurface.h), the defaults of sigma_a and
        // sigma_s (the reduced scattering coefficient, as pbrt-v3 takes it).
        Rgb preset_a = kDefaultSigmaA, preset_s = kDefaultSigmaS;
        if (const std::string preset = e.params.get_string("preset", "");
            !preset.empty() && !measured_scattering(preset, preset_a, preset_s))
            warn(loc_of(e, "preset"), "medium preset " + in_quotes(preset) +
                                          " is not one of pbrt-v3's measured media; sigma_a and "
                                          "sigma_s take their defaults where not given");
        auto coefficients = [&](const char* name, const Rgb& def) {
            Rgb c = def;
            if (auto v = e.params.get_rgb(name)) c = to_rgb(finite_values(e, name, *v));
            if (c.r < 0 || c.g < 0 || c.b < 0)
                throw SceneError(loc_of(e, name), std::string(name) + " must not be negative");
            return c;
        };
        const float scale = static_cast<float>(finite_float(e, "scale", 1));
        if (scale < 0) throw SceneError(loc_of(e, "scale"), "scale must not be negative");
        m.sigma_a = coefficients("sigma_a", preset_a) * scale;
        m.sigma_s = coefficients("sigma_s", preset_s) * scale;
        m.sigma_t = m.sigma_a + m.sigma_s;
        m.g = static_cast<float>(finite_float(e, "g", 0));
        if (!(std::abs(m.g) < 1))
            throw SceneError(loc_of(e, "g"),
                             "g must lie strictly between -1 and 1, got " + pbrt::number_text(m.g));
        if (e.type == "heterogeneous") {
            m.type = Medium::Type::Grid;
            const auto dens = e.params.get_floats("density");
            if (!dens) {
                drop(e.loc, "no \"float density\" values are given");
                continue;
            }
            m.nx = e.params.get_int("nx", 1);
            m.ny = e.params.get_int("ny", 1);
            m.nz = e.params.get_int("nz", 1);
            for (const char* n : {"nx", "ny", "nz"})
                if (e.params.get_int(n, 1) < 1)
                    throw SceneError(loc_of(e, n), std::string(n) + " must be at least 1");
            const double cells = double(m.nx) * m.ny * m.nz;
            if (double(dens->size()) != cells) {
                drop(loc_of(e, "density"),
                     "it has " + std::to_string(dens->size()) +
                         " density values; nx*ny*nz = " + pbrt::number_text(cells));
                continue;
            }
            finite_values(e, "density", *dens);
            m.density.assign(dens->begin(), dens->end());
            const float max_density = *std::max_element(m.density.begin(), m.density.end());
            m.inv_max_density = max_density > 0 ? 1 / max_density : 0;
            m.grid_sigma_t = m.sigma_t.r;
            m.build_majorants();
            if (m.sigma_t.g != m.sigma_t.r || m.sigma_t.b != m.sigma_t.r)
                warn(e.loc, "medium " + in_quotes(d.name) +
                                ": a heterogeneous medium needs sigma_a + sigma_s equal in every "
                                "channel; its first channel is used, as in pbrt-v3");
            const auto p0 = finite_point(e, "p0", {0, 0, 0}), p1 = finite_point(e, "p1", {1, 1, 1});
            const Mat4 world_from_grid = d.world_from_medium *
                                         pbrt::translate(p0[0], p0[1], p0[2]) *
                                         pbrt::scale(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]);
            finite_transform(d.world_from_medium, e.loc, "medium");
            m.grid_from_world = to34(inverse_or_error(
                world_from_grid, e.loc,
                "the medium's grid has no volume (p0 and p1 must differ in x, y and z, and its "
                "transform must be invertible)"));
        }
        e.params.check_unused("MakeNamedMedium " + in_quotes(d.name), m_warn);
        m_medium_index[i] = static_cast<int>(m_scene->media.size());
        m_scene->media.push_back(std::move(m));
    }
    m_scene->camera_medium = medium(m_desc.camera_medium);
    // pbrt-v3's volpath, bdpt and mlt render media; its other integrators leave them out.
    const std::string& integ = m_desc.integrator.given ? m_desc.integrator.type : "path";
    const bool renders = integ == "volpath" || integ == "bdpt" || integ == "mlt";
    const bool used = m_desc.medium_interface.line != 0;
    m_scene->volumetric = renders && used && !m_scene->media.empty();
    if (m_scene->volumetric && m_scene->light_tracing) {
        // (The light paths do not cross media.)
        m_scene->light_tracing = false;
        warn(m_desc.medium_interface,
             "the caustics of point, spot and distant lights through mirrors and glass are left "
             "out: the light paths of " +
                 in_quotes(integ) + " are not traced through participating media");
    }
    if (used && !renders)
        warn(m_desc.medium_interface,
             "the scene has participating media, which the " + in_quotes(integ) +
                 " integrator does not render (as in pbrt-v3; \"volpath\" renders them)");
}

int Builder::medium(int desc_index) const {
    return desc_index >= 0 && static_cast<std::size_t>(desc_index) < m_medium_index.size()
               ? m_medium_index[static_cast<std::size_t>(desc_index)]
               : -1;
}

}  // namespace cmam::render::build_detail
