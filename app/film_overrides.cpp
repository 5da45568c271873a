#include "app/film_overrides.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string_view>

#include "app/common.h"
#include "render/scene.h"

namespace cmam::app {

namespace {

pbrt::Param film_param(const char* type, const char* name, std::vector<double> values) {
    pbrt::Param p;
    p.type = std::string(type) == "integer" ? pbrt::ParamType::Integer : pbrt::ParamType::Float;
    p.type_name = type;
    p.name = name;
    p.numbers = std::move(values);
    return p;
}

void check_limits(long long w, long long h) {
    if (w > render::kMaxFilmSide || h > render::kMaxFilmSide || w * h > render::kMaxFilmPixels)
        throw UsageError("--resolution " + std::to_string(w) + "x" + std::to_string(h) +
                         " is above cmam's limits of " + std::to_string(render::kMaxFilmSide) +
                         " pixels a side and " + std::to_string(render::kMaxFilmPixels) +
                         " in all");
}

}  // namespace

FilmOverrides::FilmOverrides(const std::string& resolution, const std::string& crop) {
    if (!resolution.empty()) {
        // Whole numbers read without wrapping around (sscanf's %d once made 4294967328 a width
        // of 32).
        auto whole = [](std::string_view s, long long& v) {
            const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
            return ec == std::errc() && end == s.data() + s.size() && v > 0;
        };
        const std::size_t cut = resolution.find_first_of("xX");
        const std::string_view text = resolution;
        if (!(cut == std::string::npos
                  ? whole(text, m_width)
                  : whole(text.substr(0, cut), m_width) && whole(text.substr(cut + 1), m_height)))
            throw UsageError("--resolution: expected WIDTHxHEIGHT or WIDTH, got \"" + resolution +
                             "\"");
        if (m_height > 0) check_limits(m_width, m_height);
    }
    if (!crop.empty()) {
        m_crop = parse_numbers(crop, "--crop");
        if (m_crop.size() != 4) throw UsageError("--crop needs four numbers: X0,X1,Y0,Y1");
        for (double v : m_crop)
            if (!(v >= 0 && v <= 1))
                throw UsageError("--crop: values are fractions of the image, in [0, 1]");
        if (!(m_crop[0] < m_crop[1] && m_crop[2] < m_crop[3]))
            throw UsageError("--crop: needs X0 < X1 and Y0 < Y1");
    }
}

void FilmOverrides::apply(pbrt::SceneDesc& desc, const pbrt::WarningSink& warn) const {
    if (m_width > 0) {
        const int xres = desc.film.params.get_int("xresolution", render::kDefaultFilmWidth),
                  yres = desc.film.params.get_int("yresolution", render::kDefaultFilmHeight);
        const long long w = m_width, h = m_height > 0
                                             ? m_height
                                             : std::max(1LL, std::llround(double(w) * yres / xres));
        check_limits(w, h);
        if (warn && std::abs(double(w) / h - double(xres) / yres) > 1.0 / std::min(w, h))
            warn("warning: --resolution " + std::to_string(w) + "x" + std::to_string(h) +
                 " has another aspect ratio than the scene's " + std::to_string(xres) + "x" +
                 std::to_string(yres) + " film: the camera frames " +
                 (double(w) / h > double(xres) / yres ? "more" : "less") +
                 " of the scene horizontally (give the width alone to keep the aspect)");
        desc.film.params.add(film_param("integer", "xresolution", {double(w)}));
        desc.film.params.add(film_param("integer", "yresolution", {double(h)}));
    }
    if (!m_crop.empty()) desc.film.params.add(film_param("float", "cropwindow", m_crop));
}

}  // namespace cmam::app
