#include "render/image_io.h"

#include <cmam/texture/image.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <mutex>

#include "render/image_codecs.h"
#include "render/memory.h"

namespace cmam::render {

namespace fs = std::filesystem;

namespace {

// What the process may use (memory.h): the machine, its cgroup and ulimit -v.
std::atomic<std::size_t> g_image_memory_limit{memory_limit()};

// A row of `w` pixels of NC bytes each into OUT floats each through the table of the bytes'
// values (OUT = 3 from one or two bytes repeats the first, the grey value).
template <int NC, int OUT>
void decode_row(const unsigned char* b, int w, const float* table, float* row) {
    for (int x = 0; x < w; ++x, b += NC, row += OUT)
        for (int c = 0; c < OUT; ++c) row[c] = table[b[NC >= 3 ? c : 0]];
}

}  // namespace

void set_image_memory_limit(std::size_t bytes) {
    g_image_memory_limit.store(bytes);
}

RawImage read_image(const std::string& path, bool keep_8bit) {
    const std::string where = "cannot read image \"" + path + "\": ";
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (!fs::exists(st)) throw RenderError(where + "file not found");
    if (fs::is_directory(st)) throw RenderError(where + "it is a directory");
    // A FIFO or a device would block or never end: only regular files are read, as for scenes.
    if (!fs::is_regular_file(st)) throw RenderError(where + "it is not a regular file");
    auto check = [&](const RawImage& img) {
        const double bytes = double(img.width) * img.height * img.channels *
                             (keep_8bit && img.is_8bit ? 1 : sizeof(float));
        if (bytes > double(g_image_memory_limit.load()))
            throw RenderError(std::to_string(img.width) + "x" + std::to_string(img.height) +
                              " with " + std::to_string(img.channels) +
                              (img.channels == 1 ? " channel" : " channels") + " needs " +
                              std::to_string(static_cast<long long>(bytes / (1 << 20))) +
                              " MB, over the limit of " +
                              std::to_string(g_image_memory_limit.load() >> 20) + " MB");
    };
    try {
        return codec::decode(path, check, keep_8bit);
    } catch (const RenderError& e) {
        throw RenderError(where + e.what());
    } catch (const std::bad_alloc&) {
        throw RenderError(where + "out of memory");
    }
}

texture::Image load_texture(const std::string& path, bool is_float, std::optional<bool> gamma_opt,
                            float scale, texture::WrapMode wrap, bool* gamma_used, bool keep_grey,
                            std::size_t* non_finite) {
    RawImage raw = read_image(path, true);
    // pbrt-v3's imagemap decodes the files it reads as 8-bit, PNG and TGA, by default: a 16-bit
    // PNG too, which it reads as 8-bit (cmam keeps its 16 bits). Other 8-bit files (JPEG, BMP,
    // ...), which pbrt-v3 cannot read, are decoded too; other files are linear.
    const std::string ext = codec::lower_extension(path);
    const bool gamma = gamma_opt.value_or(raw.is_8bit || ext == ".png" || ext == ".tga");
    if (gamma_used) *gamma_used = gamma;
    const int w = raw.width, h = raw.height, nc = raw.channels;
    const bool grey = !is_float && keep_grey && nc < 3;  // grey, or grey and alpha
    const int out_c = is_float || grey ? 1 : 3;
    // A spectrum texture's channel from one sample; a float texture's value from an RGB sample.
    auto decode = [&](float r) { return scale * (gamma ? texture::srgb_to_linear(r) : r); };
    auto luminance = [&](const float* rgb) {
        float yv = 0.212671f * rgb[0] + 0.715160f * rgb[1] + 0.072169f * rgb[2];
        return scale * (gamma ? texture::srgb_to_linear(yv) : yv);
    };
    // Bytes decode through a table of their 256 values, the same floats as decoding each sample
    // (sRGB decoding costs a pow a sample: seconds for a large texture), except a float texture
    // of an RGB file, whose luminance has too many inputs.
    const bool by_table = !raw.bytes.empty() && !(is_float && nc >= 3);
    float table[256];
    if (by_table)
        for (int b = 0; b < 256; ++b) {
            const float r = float(b) * (1.0f / 255.0f), rgb[3] = {r, r, r};
            table[b] = is_float ? luminance(rgb) : decode(r);
        }
    // Written row by row into the texture: the file's pixels (bytes for 8-bit files) and the
    // texture are the only copies of the image in memory.
    std::size_t bad = 0;  // texel values that are not finite (a table's values all are)
    auto fill = [&](int j, float* row) {
        std::size_t row_bad = 0;
        const int y = h - 1 - j;  // flip: v = 0 is the bottom row (pbrt-v3)
        const std::size_t k0 = static_cast<std::size_t>(y) * w * nc;
        if (by_table) {
            // (One float from one or two bytes: a float or kept-grey texture of a grey file;
            // else three floats.)
            const unsigned char* b = raw.bytes.data() + k0;
            switch (out_c == 1 ? nc : 4 + nc) {
                case 1:
                    return decode_row<1, 1>(b, w, table, row);
                case 2:
                    return decode_row<2, 1>(b, w, table, row);
                case 5:
                    return decode_row<1, 3>(b, w, table, row);
                case 6:
                    return decode_row<2, 3>(b, w, table, row);
                case 7:
                    return decode_row<3, 3>(b, w, table, row);
                case 8:
                    return decode_row<4, 3>(b, w, table, row);
                default:  // any other layout
                    for (int x = 0; x < w; ++x, b += nc)
                        for (int c = 0; c < out_c; ++c)
                            row[static_cast<std::size_t>(x) * out_c + c] =
                                table[b[nc >= 3 ? c : 0]];
                    return;
            }
        }
        for (int x = 0; x < w; ++x) {
            const std::size_t k = k0 + static_cast<std::size_t>(x) * nc;
            const float r = raw.sample(k);
            const float rgb[3] = {r, nc >= 3 ? raw.sample(k + 1) : r,
                                  nc >= 3 ? raw.sample(k + 2) : r};
            float* dst = &row[static_cast<std::size_t>(x) * out_c];
            if (is_float)
                dst[0] = luminance(rgb);
            else
                for (int c = 0; c < out_c; ++c) dst[c] = decode(rgb[c]);
            for (int c = 0; c < out_c; ++c) row_bad += !std::isfinite(dst[c]);
        }
        bad += row_bad;
    };
    texture::Image image = texture::Image::from_rows(w, h, out_c, fill, wrap, wrap);
    if (non_finite) *non_finite = bad;
    return image;
}

namespace {

std::string cannot_write(const std::string& path, const std::string& why) {
    return "cannot write \"" + path + "\": " + why;
}

// The temporary being written, for the signal handler: a fixed buffer, as a handler may only
// read memory and call async-signal-safe functions (unlink, sigaction, raise).
char g_temporary[4096];
volatile std::sig_atomic_t g_have_temporary = 0;
volatile std::sig_atomic_t g_interrupted = 0;
constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
struct sigaction g_previous[std::size(kSignals)];
bool g_installed[std::size(kSignals)];
std::mutex g_write_mutex;  // one write at a time owns the globals above
void (*g_test_hook)() = nullptr;

extern "C" void remove_temporary_and_reraise(int sig) {
    const int saved_errno = errno;
    if (g_have_temporary) ::unlink(g_temporary);
    g_have_temporary = 0;
    g_interrupted = 1;
    for (std::size_t i = 0; i < std::size(kSignals); ++i)
        if (kSignals[i] == sig) ::sigaction(sig, &g_previous[i], nullptr);
    // Delivered when this handler returns: the default action ends the process; a handler of
    // the program's own runs, and the write then fails.
    ::raise(sig);
    errno = saved_errno;
}

// A temporary file beside the target, renamed over it by commit(). Until then SIGINT, SIGTERM
// and SIGHUP remove it before taking effect, and the destructor removes it (any failure).
// Every write, the flush to disk and the close are checked.
class Temporary {
  public:
    Temporary(std::string target, fs::path tmp)
        : m_lock(g_write_mutex), m_target(std::move(target)), m_tmp(std::move(tmp)) {
        const std::string t = m_tmp.string();
        if (t.size() >= sizeof(g_temporary))
            throw RenderError(cannot_write(m_target, "the path is too long"));
        std::copy(t.begin(), t.end(), g_temporary);
        g_temporary[t.size()] = '\0';
        g_interrupted = 0;
        g_have_temporary = 1;
        for (std::size_t i = 0; i < std::size(kSignals); ++i) {
            struct sigaction sa {};
            sa.sa_handler = remove_temporary_and_reraise;
            sigemptyset(&sa.sa_mask);
            ::sigaction(kSignals[i], nullptr, &g_previous[i]);
            // A signal the process ignores stays ignored (it would not end the process).
            g_installed[i] =
                g_previous[i].sa_handler != SIG_IGN && ::sigaction(kSignals[i], &sa, nullptr) == 0;
        }
    }
    Temporary(const Temporary&) = delete;
    Temporary& operator=(const Temporary&) = delete;
    ~Temporary() {
        if (m_fd >= 0) ::close(m_fd);
        if (!m_committed) ::unlink(m_tmp.c_str());
        g_have_temporary = 0;
        for (std::size_t i = 0; i < std::size(kSignals); ++i)
            if (g_installed[i]) ::sigaction(kSignals[i], &g_previous[i], nullptr);
    }
    const fs::path& path() const { return m_tmp; }

    // Creates the temporary and writes `bytes` to it, flushed to disk.
    void write(const std::vector<unsigned char>& bytes) {
        m_fd = ::open(m_tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        if (m_fd < 0) fail();
        if (g_test_hook) g_test_hook();
        for (std::size_t done = 0; done < bytes.size();) {
            errno = 0;
            const ssize_t n = ::write(m_fd, bytes.data() + done, bytes.size() - done);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) fail();
            done += static_cast<std::size_t>(n);
        }
        sync_and_close();
    }
    // The temporary was written by a library through its own file: flushed to disk here.
    void sync_written() {
        m_fd = ::open(m_tmp.c_str(), O_WRONLY | O_CLOEXEC);
        if (m_fd < 0) fail();
        sync_and_close();
    }
    void commit() {
        if (g_interrupted) throw RenderError(cannot_write(m_target, "interrupted by a signal"));
        if (::rename(m_tmp.c_str(), m_target.c_str()) != 0) fail();
        m_committed = true;
    }

  private:
    std::lock_guard<std::mutex> m_lock;
    std::string m_target;
    fs::path m_tmp;
    int m_fd = -1;
    bool m_committed = false;

    [[noreturn]] void fail() {
        // errno of the failed call; a write that wrote nothing without an error is a full disk.
        const int e = errno != 0 ? errno : ENOSPC;
        throw RenderError(cannot_write(m_target, std::strerror(e)));
    }
    void sync_and_close() {
        errno = 0;
        if (::fsync(m_fd) != 0) fail();
        const int fd = m_fd;
        m_fd = -1;
        if (::close(fd) != 0) fail();
    }
};

// The temporary's name: hidden, beside the target, with the target's extension (format
// plug-ins check it).
fs::path temporary_for(const fs::path& target, const std::string& ext) {
    fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::string name = ".";
    name += target.filename().string();
    name += ".tmp";
    name += std::to_string(::getpid());
    name += ext;
    return dir / name;
}

}  // namespace

void set_write_test_hook(void (*hook)()) {
    g_test_hook = hook;
}

namespace {

// Encodes with `encode` (which throws RenderError) and writes the bytes atomically.
template <class Encode>
void write_encoded(const std::string& path, const std::string& ext, Encode&& encode) {
    std::vector<unsigned char> bytes;
    try {
        bytes = encode();
    } catch (const RenderError& e) {
        throw RenderError(cannot_write(path, e.what()));
    }
    Temporary tmp(path, temporary_for(fs::path(path), ext));
    tmp.write(bytes);
    tmp.commit();
}

}  // namespace

void write_image(const std::string& path, int w, int h, const std::vector<float>& rgb,
                 const std::vector<std::string>& channel_names) {
    const std::string ext = codec::lower_extension(path);
    const fs::path target(path);
    const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw RenderError("cannot write \"" + path + "\": directory \"" + dir.string() +
                          "\" does not exist");
    const codec::Output format = codec::output_format(ext);
    if (format == codec::Output::Unsupported)
        throw RenderError("cannot write \"" + path + "\": unsupported output format \"" + ext +
                          "\" (use .exr, .pfm or .png)");
    if (format == codec::Output::Tiff) {
        // libtiff writes the temporary itself; it is flushed to disk before the rename.
        Temporary tmp(path, temporary_for(target, ext));
        try {
            codec::write_tiff(tmp.path().string(), w, h, rgb.data());
        } catch (const RenderError& e) {
            throw RenderError(cannot_write(path, e.what()));
        }
        tmp.sync_written();
        tmp.commit();
        return;
    }
    if (codec::stores_float(format)) {
        const std::vector<std::string> names =
            channel_names.size() == 3 ? channel_names : std::vector<std::string>{"R", "G", "B"};
        write_encoded(path, ext,
                      [&] { return codec::encode_float(format, w, h, rgb.data(), names); });
        return;
    }
    std::vector<unsigned char> bytes(rgb.size());
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        const float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
        const float e = texture::linear_to_srgb(v);
        bytes[i] = static_cast<unsigned char>(std::clamp(e * 255.0f + 0.5f, 0.0f, 255.0f));
    }
    write_encoded(path, ext, [&] { return codec::encode_8bit(format, w, h, bytes.data()); });
}

void write_png8(const std::string& path, int w, int h, const std::vector<unsigned char>& rgb) {
    write_encoded(path, ".png",
                  [&] { return codec::encode_8bit(codec::Output::Png, w, h, rgb.data()); });
}

}  // namespace cmam::render
