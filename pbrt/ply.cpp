#include "pbrt/ply.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "pbrt/error.h"
#include "pbrt/input_file.h"

namespace cmam::pbrt {

namespace {

// An error of the file at `path`: its message names the file first.
SceneError ply_error(const std::string& path, const std::string& why) {
    return SceneError(path + ": " + why);
}

enum class Scalar { I8, U8, I16, U16, I32, U32, F32, F64 };

bool parse_scalar(const std::string& s, Scalar* out) {
    if (s == "char" || s == "int8")
        *out = Scalar::I8;
    else if (s == "uchar" || s == "uint8")
        *out = Scalar::U8;
    else if (s == "short" || s == "int16")
        *out = Scalar::I16;
    else if (s == "ushort" || s == "uint16")
        *out = Scalar::U16;
    else if (s == "int" || s == "int32")
        *out = Scalar::I32;
    else if (s == "uint" || s == "uint32")
        *out = Scalar::U32;
    else if (s == "float" || s == "float32")
        *out = Scalar::F32;
    else if (s == "double" || s == "float64")
        *out = Scalar::F64;
    else
        return false;
    return true;
}

int size_of(Scalar s) {
    switch (s) {
        case Scalar::I8:
        case Scalar::U8:
            return 1;
        case Scalar::I16:
        case Scalar::U16:
            return 2;
        case Scalar::I32:
        case Scalar::U32:
        case Scalar::F32:
            return 4;
        case Scalar::F64:
            return 8;
    }
    return 0;
}

struct Property {
    std::string name;
    bool is_list = false;
    Scalar count_type{}, type{};
};

struct Element {
    std::string name;
    std::size_t count = 0;
    std::vector<Property> props;
};

enum class Format { Ascii, BinaryLE, BinaryBE };

// Longest list accepted: in a face (its vertices, read into memory) and in anything else (read
// and dropped; a longer one would be a corrupt count, read until the data ran out).
constexpr double kMaxFaceList = 1 << 20;
constexpr double kMaxSkippedList = 2147483647.0;

class Reader {
  public:
    Reader(std::istream& in, Format f, const std::string& path)
        : m_in(in), m_format(f), m_path(path) {}

    double read(Scalar s) {
        if (m_format == Format::Ascii) {
            double v;
            if (!(m_in >> v)) fail("unexpected end of data or malformed number");
            return v;
        }
        unsigned char buf[8];
        int n = size_of(s);
        if (!m_in.read(reinterpret_cast<char*>(buf), n)) fail("unexpected end of data");
        bool swap = (m_format == Format::BinaryBE) == (std::endian::native == std::endian::little);
        if (swap) std::reverse(buf, buf + n);
        switch (s) {
            case Scalar::I8: {
                int8_t v;
                std::memcpy(&v, buf, 1);
                return v;
            }
            case Scalar::U8:
                return buf[0];
            case Scalar::I16: {
                int16_t v;
                std::memcpy(&v, buf, 2);
                return v;
            }
            case Scalar::U16: {
                uint16_t v;
                std::memcpy(&v, buf, 2);
                return v;
            }
            case Scalar::I32: {
                int32_t v;
                std::memcpy(&v, buf, 4);
                return v;
            }
            case Scalar::U32: {
                uint32_t v;
                std::memcpy(&v, buf, 4);
                return v;
            }
            case Scalar::F32: {
                float v;
                std::memcpy(&v, buf, 4);
                return v;
            }
            case Scalar::F64: {
                double v;
                std::memcpy(&v, buf, 8);
                return v;
            }
        }
        return 0;
    }
    // A list's length: a whole number from 0 to `max`, whatever type holds it (floats included).
    std::size_t read_count(Scalar s, double max) {
        const double n = read(s);
        if (!(n >= 0 && n <= max && n == std::floor(n)))
            fail("invalid list length " + number(n) + " (at most " + number(max) + ")");
        return static_cast<std::size_t>(n);
    }
    // A vertex index: a whole number in int's range (whether it names a vertex is checked once
    // all vertices are read).
    int read_index(Scalar s) {
        const double v = read(s);
        if (!(v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max() &&
              v == std::floor(v)))
            fail("vertex index " + number(v) + " is not a whole number in int's range");
        return static_cast<int>(v);
    }
    // A list read and dropped.
    void skip_list(const Property& p) {
        const std::size_t n = read_count(p.count_type, kMaxSkippedList);
        for (std::size_t c = 0; c < n; ++c) read(p.type);
    }
    // A vertex attribute as stored: a finite single-precision number.
    float to_float(double v, std::size_t vertex, const std::string& property) {
        if (!(std::abs(v) <= std::numeric_limits<float>::max()))
            fail("vertex " + std::to_string(vertex) + " property \"" + property + "\" is " +
                 number(v) + ", not a finite single-precision number");
        return static_cast<float>(v);
    }
    static std::string number(double v) { return number_text(v); }
    [[noreturn]] void fail(const std::string& why) { throw ply_error(m_path, why); }

  private:
    std::istream& m_in;
    Format m_format;
    const std::string& m_path;
};

struct Header {
    Format format = Format::Ascii;
    std::vector<Element> elements;
};

Format parse_format(const std::string& f, const std::string& path) {
    if (f == "ascii") return Format::Ascii;
    if (f == "binary_little_endian") return Format::BinaryLE;
    if (f == "binary_big_endian") return Format::BinaryBE;
    throw ply_error(path, "unknown PLY format \"" + f + "\"");
}

// The property a header line declares; `words` is the line after "property".
Property parse_property(std::istringstream& words, const std::string& line,
                        const std::string& path) {
    Property p;
    std::string t;
    words >> t;
    if (t == "list") {
        std::string ct, it;
        words >> ct >> it >> p.name;
        p.is_list = true;
        if (!parse_scalar(ct, &p.count_type) || !parse_scalar(it, &p.type))
            throw ply_error(path, "unknown property type in \"" + line + "\"");
    } else {
        words >> p.name;
        if (!parse_scalar(t, &p.type)) throw ply_error(path, "unknown property type \"" + t + "\"");
    }
    return p;
}

// The header lines after "ply", up to end_header.
Header read_header(std::istream& in, const std::string& path) {
    Header h;
    bool have_format = false;
    std::string line;
    for (;;) {
        if (!std::getline(in, line)) throw ply_error(path, "PLY header has no end_header");
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::string word;
        words >> word;
        if (word == "end_header") break;
        if (word == "comment" || word == "obj_info" || word.empty()) continue;
        if (word == "format") {
            std::string f;
            words >> f;
            h.format = parse_format(f, path);
            have_format = true;
        } else if (word == "element") {
            Element e;
            long long count = -1;
            if (!(words >> e.name >> count) || count < 0)  // a count beyond long long fails too
                throw ply_error(path, "malformed element line \"" + line + "\"");
            e.count = static_cast<std::size_t>(count);
            h.elements.push_back(std::move(e));
        } else if (word == "property") {
            if (h.elements.empty()) throw ply_error(path, "property before any element");
            h.elements.back().props.push_back(parse_property(words, line, path));
        } else {
            throw ply_error(path, "unexpected PLY header line \"" + line + "\"");
        }
    }
    if (!have_format) throw ply_error(path, "PLY header has no format line");
    return h;
}

// Where a vertex element holds each attribute: the index of its property, -1 when absent.
struct VertexLayout {
    int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, u = -1, v = -1;

    explicit VertexLayout(const Element& e) {
        for (int k = 0; k < static_cast<int>(e.props.size()); ++k) {
            const std::string& n = e.props[k].name;
            if (n == "x")
                x = k;
            else if (n == "y")
                y = k;
            else if (n == "z")
                z = k;
            else if (n == "nx")
                nx = k;
            else if (n == "ny")
                ny = k;
            else if (n == "nz")
                nz = k;
            else if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s")
                u = k;
            else if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t")
                v = k;
        }
    }
};

void read_vertices(Reader& r, const Element& e, PlyMesh& mesh) {
    const VertexLayout at(e);
    if (at.x < 0 || at.y < 0 || at.z < 0) r.fail("vertex element lacks x, y, z properties");
    const bool normals = at.nx >= 0 && at.ny >= 0 && at.nz >= 0;
    const bool uvs = at.u >= 0 && at.v >= 0;
    std::vector<double> vals(e.props.size());
    for (std::size_t i = 0; i < e.count; ++i) {
        for (std::size_t k = 0; k < e.props.size(); ++k) {
            const Property& p = e.props[k];
            if (p.is_list) {
                r.skip_list(p);
                vals[k] = 0;
            } else {
                vals[k] = r.read(p.type);
            }
        }
        auto get = [&](int k) { return r.to_float(vals[k], i, e.props[k].name); };
        mesh.positions.insert(mesh.positions.end(), {get(at.x), get(at.y), get(at.z)});
        if (normals) mesh.normals.insert(mesh.normals.end(), {get(at.nx), get(at.ny), get(at.nz)});
        if (uvs) mesh.uvs.insert(mesh.uvs.end(), {get(at.u), get(at.v)});
    }
}

void read_faces(Reader& r, const Element& e, PlyMesh& mesh) {
    for (std::size_t i = 0; i < e.count; ++i) {
        for (const Property& p : e.props) {
            if (!p.is_list) {
                r.read(p.type);
                continue;
            }
            // Other lists of a face (texture coordinates, say) are read and dropped.
            if (p.name != "vertex_indices" && p.name != "vertex_index") {
                r.skip_list(p);
                continue;
            }
            const std::size_t n = r.read_count(p.count_type, kMaxFaceList);
            std::vector<int> f(n);
            for (auto& x : f) x = r.read_index(p.type);
            if (n == 3)
                mesh.indices.insert(mesh.indices.end(), {f[0], f[1], f[2]});
            else if (n == 4)
                mesh.indices.insert(mesh.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
            else if (mesh.skipped_faces++ == 0)
                mesh.first_skipped_size = n;
        }
    }
}

void skip_element(Reader& r, const Element& e) {
    for (std::size_t i = 0; i < e.count; ++i)
        for (const Property& p : e.props) {
            if (p.is_list)
                r.skip_list(p);
            else
                r.read(p.type);
        }
}

// Several vertex elements may each have normals or texture coordinates or not: the mesh needs
// them for every vertex or for none. Every face index names a vertex.
void check_mesh(const PlyMesh& mesh, const std::string& path) {
    const std::size_t nv = mesh.positions.size() / 3;
    auto per_vertex = [&](const std::vector<float>& a, std::size_t k, const char* what) {
        if (!a.empty() && a.size() != k * nv)
            throw ply_error(path, std::string(what) + " given for " + std::to_string(a.size() / k) +
                                      " of " + std::to_string(nv) +
                                      " vertices (give them for every vertex or none)");
    };
    per_vertex(mesh.normals, 3, "normals (nx ny nz)");
    per_vertex(mesh.uvs, 2, "texture coordinates (u v)");
    for (int idx : mesh.indices)
        if (idx < 0 || static_cast<std::size_t>(idx) >= nv)
            throw ply_error(path, "face index " + std::to_string(idx) + " out of range (" +
                                      std::to_string(nv) + " vertices)");
}

}  // namespace

PlyMesh read_ply(const std::string& path, const PlyCheck& check) {
    if (std::string why = not_a_regular_file(path); !why.empty())
        throw ply_error(path, "cannot read PLY file: " + why);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ply_error(path, std::string("cannot open PLY file: ") + std::strerror(errno));
    std::string line;
    if (!std::getline(in, line) || line.substr(0, 3) != "ply")
        throw ply_error(path, "not a PLY file (missing \"ply\" magic)");
    const Header header = read_header(in, path);
    if (check) {
        PlyCounts counts;
        for (const Element& e : header.elements) {
            if (e.name == "vertex") {
                const VertexLayout at(e);
                counts.vertices += e.count;
                counts.normals = counts.normals || (at.nx >= 0 && at.ny >= 0 && at.nz >= 0);
                counts.uvs = counts.uvs || (at.u >= 0 && at.v >= 0);
            } else if (e.name == "face" && !e.props.empty()) {
                counts.faces += e.count;
            }
        }
        check(counts);
    }
    PlyMesh mesh;
    Reader r(in, header.format, path);
    bool have_vertices = false;
    for (const Element& e : header.elements) {
        if (e.name == "vertex") {
            have_vertices = true;
            read_vertices(r, e, mesh);
            continue;
        }
        // Without properties there is nothing to read, however large the count.
        if (e.props.empty()) continue;
        if (e.name == "face")
            read_faces(r, e, mesh);
        else
            skip_element(r, e);
    }
    if (!have_vertices) throw ply_error(path, "PLY file has no vertex element");
    check_mesh(mesh, path);
    return mesh;
}

}  // namespace cmam::pbrt
