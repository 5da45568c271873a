// render — paraxial optics of pbrt-v3 lens systems (algorithms.md §7.2).
#include "render/lens.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "pbrt/error.h"
#include "pbrt/input_file.h"
#include "render/error.h"

namespace cmam::render {

namespace {

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

// `word` as a number; throws naming `subject` and `line` when it is not a finite one. A leading
// '+' is accepted, as pbrt-v3's reader does.
double lens_number(std::string_view word, const std::string& subject, int line) {
    const std::string_view digits = word.starts_with('+') ? word.substr(1) : word;
    double v = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    const std::string at =
        subject + ", line " + std::to_string(line) + ": \"" + std::string(word) + "\" is not a ";
    if (digits.empty() || end != digits.data() + digits.size() ||
        (ec != std::errc() && ec != std::errc::result_out_of_range))
        throw RenderError(at + "number");
    if (ec == std::errc::result_out_of_range || !std::isfinite(v))
        throw RenderError(at + "finite number");
    return v;
}

}  // namespace

std::vector<LensInterface> parse_lens(std::string_view text, const std::string& subject) {
    std::vector<double> values;
    int line = 1;
    std::size_t i = 0;
    while (i < text.size()) {
        const char c = text[i];
        if (c == '#') {
            i = text.find('\n', i);
            if (i == std::string_view::npos) break;
        } else if (is_space(c)) {
            line += c == '\n';
            ++i;
        } else {
            std::size_t end = i;
            while (end < text.size() && !is_space(text[end]) && text[end] != '#') ++end;
            values.push_back(lens_number(text.substr(i, end - i), subject, line));
            i = end;
        }
    }
    if (values.size() % 4 != 0)
        throw RenderError(subject + " holds " + std::to_string(values.size()) +
                          " numbers, not a multiple of 4 (each interface is a curvature radius, "
                          "a thickness, an index of refraction and an aperture diameter)");
    if (values.empty()) throw RenderError(subject + " lists no lens interfaces");
    std::vector<LensInterface> lens(values.size() / 4);
    for (std::size_t k = 0; k < lens.size(); ++k)
        lens[k] = {values[4 * k], values[4 * k + 1], values[4 * k + 2], values[4 * k + 3]};
    return lens;
}

std::vector<LensInterface> read_lens_file(const std::string& path) {
    const std::string cannot = "cannot read lens file \"" + path + "\": ";
    if (std::string why = pbrt::not_a_regular_file(path); !why.empty())
        throw RenderError(cannot + why);
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw RenderError(cannot + "file not found");
    const auto bytes = std::filesystem::file_size(path, ec);
    if (!ec && bytes > kMaxLensFileBytes)
        throw RenderError(cannot + "it is " + std::to_string(bytes) +
                          " bytes, above cmam's limit of " + std::to_string(kMaxLensFileBytes) +
                          " for a lens file");
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw RenderError(cannot + (errno ? std::strerror(errno) : "it cannot be opened"));
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (in.bad()) throw RenderError(cannot + "reading it failed");
    return parse_lens(text, "lens file \"" + path + "\"");
}

// A paraxial ray is (height y, reduced angle n·u). Refraction at a surface of power
// P = (n' − n)/R is [[1, 0], [−P, 1]]; a gap t in a medium of index n is [[1, t/n], [0, 1]]. Their
// product from the first interface to the last is the system matrix [[A, B], [C, D]].
ParaxialLens paraxial_lens(const std::vector<LensInterface>& lens) {
    double a = 1, b = 0, c = 0, d = 1;
    double n = 1;            // index in front of the interface
    double length = 0;       // first interface to last
    double total_power = 0;  // sum of the surfaces' |P|: the scale C is compared with
    for (std::size_t i = 0; i < lens.size(); ++i) {
        const LensInterface& s = lens[i];
        const double n2 = s.eta == 0 ? 1 : s.eta;
        if (s.radius != 0) {
            const double p = (n2 - n) / s.radius;
            c -= p * a;
            d -= p * b;
            total_power += std::abs(p);
        }
        if (i + 1 < lens.size()) {
            a += s.thickness / n2 * c;
            b += s.thickness / n2 * d;
            length += s.thickness;
        }
        n = n2;
    }
    if (n != 1)
        throw RenderError("the last interface's index of refraction is " + pbrt::number_text(n) +
                          ": the film side of the lens system must be air (0 or 1)");
    if (!(std::abs(c) > 1e-9 * total_power) || !std::isfinite(c))
        throw RenderError("the lens system has no focusing power (its ray-transfer matrix's C is " +
                          pbrt::number_text(c, 7) +
                          "): an afocal system forms no image on the film");
    if (c > 0)
        throw RenderError("the lens system diverges (effective focal length " +
                          pbrt::number_text(-1 / c, 6) + " mm): it forms no image on the film");
    return {-1 / c, (d - 1) / c, length + (1 - a) / c};
}

// The object at distance s from the front principal plane and its image at s' from the rear one
// satisfy 1/s + 1/s' = 1/f and s + s' = L, L the focus distance less the principal planes'
// separation. So s'² − L·s' + f·L = 0, and s' = 2fL / (L + sqrt(L(L − 4f))), the root nearer f
// (the other swaps object and image), written so that it does not cancel when L ≫ f.
double image_distance(const ParaxialLens& lens, double focus_distance) {
    const double f = lens.focal_length;
    const double separation = lens.rear_principal - lens.front_principal;
    const double l = focus_distance - separation;
    if (!(l > 4 * f))
        throw RenderError("the lens system (effective focal length " + pbrt::number_text(f, 6) +
                          " mm) focuses no nearer than " +
                          pbrt::number_text(4 * f + separation, 6) +
                          " mm in front of the film, and focusdistance asks for " +
                          pbrt::number_text(focus_distance, 6) + " mm");
    return 2 * f * l / (l + std::sqrt(l * (l - 4 * f)));
}

}  // namespace cmam::render
