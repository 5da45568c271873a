// tiny_tracer — how another ray tracer uses the CMAM. Its own camera, its own intersection code
// (a textured ground plane and a mirror sphere), no scene parser; the only thing it takes from
// cmam is the public filtering API: build a FilteredTexture, keep a Cmam per textured object,
// and hand it a ray tag and a (u,v) for every texture lookup. The tracer stays a point sampler.
//
//   usage: tiny_tracer [OUTPUT_PREFIX]   writes PREFIX-off.ppm and PREFIX-cmam.ppm
#include <cmam/texture/cmam.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace {

struct V {
    double x, y, z;
    V operator+(V o) const { return {x + o.x, y + o.y, z + o.z}; }
    V operator-(V o) const { return {x - o.x, y - o.y, z - o.z}; }
    V operator*(double s) const { return {x * s, y * s, z * s}; }
};
double dot(V a, V b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
V unit(V a) {
    return a * (1 / std::sqrt(dot(a, a)));
}

// A 256x256 linear-RGB texture with fine stripes and checks: it aliases badly when minified.
cmam::texture::Image make_texture() {
    const int n = 256;
    std::vector<float> px(n * n * 3);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            bool check = ((i / 32) + (j / 32)) % 2 == 0;
            bool stripe = (i % 8) < 2;
            float* p = &px[(j * n + i) * 3];
            p[0] = check ? 0.8f : 0.15f;
            p[1] = stripe ? 0.9f : (check ? 0.6f : 0.1f);
            p[2] = check ? 0.3f : 0.5f;
        }
    return cmam::texture::Image(n, n, 3, std::move(px));
}

struct Hit {
    double t;
    V p, n;
    int object;  // 0 plane, 1 sphere
};

bool intersect(V o, V d, Hit* h) {
    h->t = 1e30;
    if (d.y < 0) {  // plane y = 0
        double t = -o.y / d.y;
        if (t > 1e-6) *h = {t, o + d * t, {0, 1, 0}, 0};
    }
    V c{0, 1, 6};  // unit sphere
    V oc = o - c;
    double b = dot(oc, d), disc = b * b - (dot(oc, oc) - 1);
    if (disc > 0) {
        double t = -b - std::sqrt(disc);
        if (t > 1e-6 && t < h->t) *h = {t, o + d * t, unit(o + d * t - c), 1};
    }
    return h->t < 1e30;
}

struct Tracer {
    const cmam::texture::FilteredTexture& tex;
    cmam::texture::Cmam* plane_cmam;  // null: point sampling

    // Radiance along a ray; `tag` is the CMAM's (scanline ID, recursion level, sample number).
    std::array<float, 3> trace(V o, V d, cmam::texture::RayTag tag, int depth) {
        Hit h;
        if (!intersect(o, d, &h)) return {0.2f, 0.25f, 0.35f};
        if (h.object == 1 && depth < 4) {  // mirror: the reflected ray keeps the ID, level + 1
            V r = d - h.n * (2 * dot(d, h.n));
            tag.level += 1;
            auto c = trace(h.p + h.n * 1e-6, r, tag, depth + 1);
            return {0.9f * c[0], 0.9f * c[1], 0.9f * c[2]};
        }
        double u = h.p.x / 4, v = h.p.z / 4;  // the plane's parameterization, tiled
        cmam::texture::Texel k = plane_cmam
                                     ? plane_cmam->lookup(tag, u, v)
                                     : tex.lookup(u, v, cmam::texture::Footprint::none(), {});
        float light = float(std::max(0.0, dot(h.n, unit(V{0.4, 1, -0.3}))));
        return {k[0] * light, k[1] * light, k[2] * light};
    }
};

void write_ppm(const std::string& path, int w, int h, const std::vector<float>& rgb) {
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << w << " " << h << "\n255\n";
    for (float x : rgb) {
        float e = cmam::texture::linear_to_srgb(std::min(1.0f, std::max(0.0f, x)));
        out.put(static_cast<char>(static_cast<unsigned char>(e * 255 + 0.5f)));
    }
}

}  // namespace

int main(int argc, char** argv) {
    const std::string prefix = argc > 1 ? argv[1] : "tiny_tracer";
    const int w = 320, h = 200;
    cmam::texture::FilteredTexture tex(make_texture());
    double mean_abs_diff = 0;
    std::vector<float> images[2];
    for (int use_cmam = 0; use_cmam < 2; ++use_cmam) {
        std::vector<float>& img = images[use_cmam];
        img.resize(w * h * 3);
        for (int y = 0; y < h; ++y) {
            // One Cmam per textured object; the scanline is the tag ID, so a new row starts anew.
            cmam::texture::Cmam cmam(tex, {cmam::texture::FilterKind::Trilinear});
            Tracer tracer{tex, use_cmam ? &cmam : nullptr};
            for (int x = 0; x < w; ++x) {
                V d = unit(V{(x + 0.5 - w / 2.0) / h, -(y + 0.5 - h / 2.0) / h, 1.2});
                cmam::texture::RayTag tag{static_cast<uint32_t>(y), 0, static_cast<uint32_t>(x)};
                auto c = tracer.trace(V{0, 1.2, 0}, d, tag, 0);
                for (int k = 0; k < 3; ++k) img[(y * w + x) * 3 + k] = c[k];
            }
        }
        write_ppm(prefix + (use_cmam ? "-cmam.ppm" : "-off.ppm"), w, h, img);
    }
    for (std::size_t i = 0; i < images[0].size(); ++i) {
        if (!std::isfinite(images[1][i])) return 1;
        mean_abs_diff += std::abs(images[0][i] - images[1][i]);
    }
    mean_abs_diff /= images[0].size();
    std::printf("wrote %s-off.ppm and %s-cmam.ppm; mean |difference| %.4f\n", prefix.c_str(),
                prefix.c_str(), mean_abs_diff);
    return mean_abs_diff > 1e-3 ? 0 : 1;  // the CMAM must have changed the distant texture
}
