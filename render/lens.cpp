// render — paraxial optics of pbrt-v3 lens systems (algorithms.md §7.2).
#include "render/lens.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include "pbrt/error.h"
#include "pbrt/input_file.h"
#include "render/error.h"
#include "render/parallel.h"

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
    if (values.size() / 4 > RealisticLens::kMaxInterfaces)
        throw RenderError(subject + " lists " + std::to_string(values.size() / 4) +
                          " interfaces; cmam traces lens systems of at most " +
                          std::to_string(RealisticLens::kMaxInterfaces));
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

// ---------------------------------------------------------------------------------------------
// pbrt-v3's realistic camera (algorithms.md §7.3).

namespace {

using V3 = RealisticLens::V3;

V3 normalized(V3 a) {
    return (1 / std::sqrt(dot(a, a))) * a;
}
V3 flip_z(V3 a) {
    return {a.x, a.y, -a.z};
}  // camera space <-> the lens system's

// The intersection of the ray with the sphere of `radius` centred on the axis at z_centre, on
// the side the element's surface is (the nearer root when the ray travels towards the centre's
// side of the vertex, as pbrt-v3 chooses it), and the normal there turned against the ray.
bool intersect_element(double radius, double z_centre, const RealisticLens::Ray& r, double& t,
                       V3& n) {
    const V3 o = r.o - V3{0, 0, z_centre};
    const double a = dot(r.d, r.d), b = 2 * dot(r.d, o), c = dot(o, o) - radius * radius;
    const double disc = b * b - 4 * a * c;
    if (!(disc >= 0)) return false;
    const double root = std::sqrt(disc);
    // (Numerically stable: the root of larger magnitude from q, the other from c / q.)
    const double q = b < 0 ? -0.5 * (b - root) : -0.5 * (b + root);
    double t0 = q / a, t1 = c / q;
    if (t0 > t1) std::swap(t0, t1);
    const bool closer = (r.d.z > 0) != (radius < 0);
    t = closer ? t0 : t1;
    if (!(t >= 0)) return false;
    n = normalized(o + t * r.d);
    if (dot(n, r.d) > 0) n = -1.0 * n;  // faces -d
    return true;
}

// Snell's law for the unit direction wi (pointing away from the surface, on n's side) into the
// medium of relative index eta = eta_i / eta_t; false on total internal reflection.
bool refract(V3 wi, V3 n, double eta, V3& wt) {
    const double cos_i = dot(n, wi);
    const double sin2_t = eta * eta * std::max(0.0, 1 - cos_i * cos_i);
    if (sin2_t >= 1) return false;
    const double cos_t = std::sqrt(1 - sin2_t);
    wt = eta * (-1.0 * wi) + (eta * cos_i - cos_t) * n;
    return true;
}

// The Halton sequence's first two dimensions at index i < 2^30: the binary digits of i
// reversed after the point, and the ternary ones (six at a time, from a table of each block of
// six digits reversed).
double radical_inverse_2(uint32_t i) {
    uint32_t r = i;
    r = ((r & 0x55555555u) << 1) | ((r >> 1) & 0x55555555u);
    r = ((r & 0x33333333u) << 2) | ((r >> 2) & 0x33333333u);
    r = ((r & 0x0f0f0f0fu) << 4) | ((r >> 4) & 0x0f0f0f0fu);
    r = ((r & 0x00ff00ffu) << 8) | ((r >> 8) & 0x00ff00ffu);
    r = (r << 16) | (r >> 16);
    return r * 0x1p-32;
}
double radical_inverse_3(uint32_t i) {
    static const std::array<uint16_t, 729> reversed = [] {
        std::array<uint16_t, 729> t{};
        for (int k = 0; k < 729; ++k) {
            int v = k, r = 0;
            for (int d = 0; d < 6; ++d, v /= 3) r = 3 * r + v % 3;
            t[static_cast<std::size_t>(k)] = static_cast<uint16_t>(r);
        }
        return t;
    }();
    double out = 0, scale = 1.0 / 729;
    for (; i > 0; i /= 729, scale /= 729) out += reversed[i % 729] * scale;
    return std::min(out, 1 - 0x1p-53);
}

}  // namespace

RealisticLens::RealisticLens(const Settings& s)
    : m_diagonal(s.film_diagonal * 0.001),
      m_xres(s.xres),
      m_yres(s.yres),
      m_simple(s.simple_weighting) {
    for (const LensInterface& li : s.interfaces) {
        double aperture = li.aperture;
        if (li.radius == 0) {
            // pbrt-v3 takes "aperturediameter" for the stop, clamped to the file's.
            if (s.aperture_diameter > aperture)
                m_clamped = aperture;
            else
                aperture = s.aperture_diameter;
        }
        m_el.push_back({li.radius * 0.001, li.thickness * 0.001, li.eta, aperture * 0.001 / 2});
    }
    if (m_el.empty()) throw RenderError("the lens system has no interfaces");
    // (Its exit pupil is bounded by 2^26 rays through every interface: a real lens has a few
    // dozen, and a file of thousands would take hours.)
    if (m_el.size() > kMaxInterfaces)
        throw RenderError("the lens system has " + std::to_string(m_el.size()) +
                          " interfaces; cmam traces at most " + std::to_string(kMaxInterfaces));
    // The film's physical extent: the diagonal, at the image's aspect ratio.
    const double aspect = double(m_yres) / m_xres;
    const double x = std::sqrt(m_diagonal * m_diagonal / (1 + aspect * aspect));
    m_half_x = x / 2;
    m_half_y = aspect * x / 2;

    // Focus (pbrt-v3's FocusThickLens): cardinal points from a ray parallel to the axis traced
    // through the system each way, then the film moved by the thick lens equation's delta.
    const double h = 0.001 * m_diagonal;
    auto cardinal = [](const Ray& in, const Ray& out, double& pz, double& fz) {
        const double tf = -out.o.x / out.d.x;
        fz = -(out.o.z + tf * out.d.z);
        const double tp = (in.o.x - out.o.x) / out.d.x;
        pz = -(out.o.z + tp * out.d.z);
    };
    double pz[2], fz[2];
    Ray scene{{h, 0, front_z() + 1}, {0, 0, -1}}, film;
    if (!trace_from_scene(scene, &film))
        throw RenderError(
            "a ray parallel to the axis does not pass the lens system (is the "
            "aperture stop too small?)");
    cardinal(scene, film, pz[0], fz[0]);
    film = {{h, 0, rear_z() - 1}, {0, 0, 1}};
    if (!trace_from_film(film, &scene))
        throw RenderError(
            "a ray parallel to the axis does not pass the lens system (is the "
            "aperture stop too small?)");
    cardinal(film, scene, pz[1], fz[1]);
    const double f = fz[0] - pz[0], z = -s.focus_distance;
    const double c = (pz[1] - z - pz[0]) * (pz[1] - z - 4 * f - pz[0]);
    if (!(c > 0))
        throw RenderError("the lens system cannot focus " + pbrt::number_text(s.focus_distance) +
                          " m in front of the film (too near for its focal length of " +
                          pbrt::number_text(f * 1000, 4) + " mm)");
    // pbrt-v3's delta = (pz1 - z + pz0 - sqrt(c)) / 2, in a form that does not cancel for a
    // distant focus: with A = pz1 - z - pz0, delta = pz0 + 2 f A / (A + sqrt(A (A - 4 f))).
    const double A = pz[1] - z - pz[0];
    const double delta = pz[0] + 2 * f * A / (A + std::sqrt(c));
    m_el.back().thickness += delta;
    if (!(m_el.back().thickness > 0 && std::isfinite(m_el.back().thickness)))
        throw RenderError("focused " + pbrt::number_text(s.focus_distance) +
                          " m in front of the film, the lens system would lie behind it");

    // The exit pupil's bounds at 64 distances from the film's centre, as pbrt-v3 finds them.
    parallel_range(kPupilBounds, 0, [&](int b, int e) {
        for (int i = b; i < e; ++i)
            m_pupil[static_cast<std::size_t>(i)] =
                bound_exit_pupil(double(i) / kPupilBounds * m_diagonal / 2,
                                 double(i + 1) / kPupilBounds * m_diagonal / 2, s.pupil_rays);
    });
}

double RealisticLens::front_z() const {
    double z = 0;
    for (const Element& e : m_el) z += e.thickness;
    return z;
}

// The ray (in the lens system's frame) through interface e, whose vertex is at z, from the medium
// of index eta_i into eta_t (0 is air): its hit on the sphere (or the stop's plane), within the
// aperture, refracted. False where it misses, is stopped or is totally reflected.
bool RealisticLens::pass(const Element& e, double z, double eta_i, double eta_t, Ray& r) {
    double t;
    V3 n;
    const bool stop = e.radius == 0;
    if (stop) {
        t = (z - r.o.z) / r.d.z;
        if (!(t >= 0)) return false;  // (a ray turned back: pbrt-v3 stops it too)
    } else if (!intersect_element(e.radius, z + e.radius, r, t, n)) {
        return false;
    }
    const V3 p = r.o + t * r.d;
    if (p.x * p.x + p.y * p.y > e.aperture_radius * e.aperture_radius) return false;
    r.o = p;
    if (stop) return true;
    V3 w;
    if (!refract(normalized(-1.0 * r.d), n, (eta_i != 0 ? eta_i : 1) / (eta_t != 0 ? eta_t : 1), w))
        return false;
    r.d = w;
    return true;
}

bool RealisticLens::trace_from_film(const Ray& in, Ray* out) const {
    double z = 0;
    Ray r{flip_z(in.o), flip_z(in.d)};
    for (std::size_t i = m_el.size(); i-- > 0;) {
        z -= m_el[i].thickness;
        // From this interface's medium (towards the film) into the one in front of it.
        if (!pass(m_el[i], z, m_el[i].eta, i > 0 ? m_el[i - 1].eta : 0, r)) return false;
    }
    if (out) *out = {flip_z(r.o), flip_z(r.d)};
    return true;
}

bool RealisticLens::trace_from_scene(const Ray& in, Ray* out) const {
    double z = -front_z();
    Ray r{flip_z(in.o), flip_z(in.d)};
    for (std::size_t i = 0; i < m_el.size(); ++i) {
        if (!pass(m_el[i], z, i > 0 ? m_el[i - 1].eta : 0, m_el[i].eta, r)) return false;
        z += m_el[i].thickness;
    }
    if (out) *out = {flip_z(r.o), flip_z(r.d)};
    return true;
}

// The bounds, on the rear element's plane, of the points through which rays from the film
// between x0 and x1 (on its x axis) leave the lens: 2^20 points of the Halton sequence over a
// square 1.5 times the rear element's radius each way, each ray from its own point of the film
// range; the bounds of those that pass, widened by twice the square's diagonal over the square
// root of their number (pbrt-v3's BoundExitPupil). A point already within the bounds needs no
// ray: it cannot widen them.
RealisticLens::Bounds RealisticLens::bound_exit_pupil(double x0, double x1, int rays) const {
    const Element& last = m_el.back();
    const double r = last.aperture_radius, rear = rear_z();
    // Rays the rear element's aperture stops, known without tracing them: where a ray passes
    // that aperture it meets the element within `sag` of its vertex plane along the axis (the
    // cap of the vertex's side, the side the trace takes), so at least |q| - |q - film| sag / rear
    // from the axis; beyond the aperture radius (with a margin for rounding) the trace would stop
    // it there. (No such bound for an element whose aperture is wider than its sphere: sag -1.)
    const double radius = std::abs(last.radius);
    const double sag = last.radius == 0 ? 0
                       : r < radius     ? radius - std::sqrt(radius * radius - r * r)
                                        : -1;
    Bounds b{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
             std::numeric_limits<double>::lowest(), std::numeric_limits<double>::lowest()};
    bool any = false;
    for (int i = 0; i < rays; ++i) {
        const V3 film{x0 + (x1 - x0) * ((i + 0.5) / rays), 0, 0};
        const double u = radical_inverse_2(static_cast<uint32_t>(i)),
                     v = radical_inverse_3(static_cast<uint32_t>(i));
        const V3 q{-1.5 * r + u * 3 * r, -1.5 * r + v * 3 * r, rear};
        const bool inside = q.x >= b.x0 && q.x <= b.x1 && q.y >= b.y0 && q.y <= b.y1;
        if (!inside && sag >= 0 &&
            std::sqrt(q.x * q.x + q.y * q.y) -
                    std::sqrt((q.x - film.x) * (q.x - film.x) + q.y * q.y) * sag / rear >
                r * (1 + 1e-9))
            continue;
        if (inside || trace_from_film({film, q - film}, nullptr)) {
            b.x0 = std::min(b.x0, q.x);
            b.y0 = std::min(b.y0, q.y);
            b.x1 = std::max(b.x1, q.x);
            b.y1 = std::max(b.y1, q.y);
            any = true;
        }
    }
    if (!any) return {-1.5 * r, -1.5 * r, 1.5 * r, 1.5 * r};
    const double grow = 2 * std::sqrt(2.0) * 3 * r / std::sqrt(double(rays));
    return {b.x0 - grow, b.y0 - grow, b.x1 + grow, b.y1 + grow};
}

double RealisticLens::generate(double px, double py, double lu, double lv, Ray& ray) const {
    // The film point (x mirrored: the lens inverts the image, and pbrt-v3's raster x runs the
    // other way to its film's).
    const V3 film{-(-m_half_x + 2 * m_half_x * (px / m_xres)),
                  -m_half_y + 2 * m_half_y * (py / m_yres), 0};
    // The pupil bound of the film point's distance from the centre, turned to its direction.
    const double r_film = std::sqrt(film.x * film.x + film.y * film.y);
    const int index =
        std::min(kPupilBounds - 1, static_cast<int>(r_film / (m_diagonal / 2) * kPupilBounds));
    const Bounds& b = m_pupil[static_cast<std::size_t>(index)];
    const double lx = b.x0 + lu * (b.x1 - b.x0), ly = b.y0 + lv * (b.y1 - b.y0);
    const double sin_t = r_film != 0 ? film.y / r_film : 0,
                 cos_t = r_film != 0 ? film.x / r_film : 1;
    const V3 rear{cos_t * lx - sin_t * ly, sin_t * lx + cos_t * ly, rear_z()};
    const Ray from_film{film, rear - film};
    if (!trace_from_film(from_film, &ray)) return 0;
    const double cos_theta = normalized(from_film.d).z,
                 cos4 = (cos_theta * cos_theta) * (cos_theta * cos_theta);
    return m_simple ? cos4 * b.area() / m_pupil[0].area() : cos4 * b.area() / (rear_z() * rear_z());
}

}  // namespace cmam::render
