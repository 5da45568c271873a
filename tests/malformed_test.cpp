// Every file in tests/data/malformed states on its first line the exact located error the
// parser and scene builder must report ("# expect: ..." or "# expect-prefix: ...").
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "pbrt/parser.h"
#include "render/build_scene.h"
#include "render/scene.h"

using namespace cmam;
namespace fs = std::filesystem;

namespace {
std::string replace_all(std::string s, const std::string& from, const std::string& to) {
    for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
        s.replace(p, from.size(), to);
    return s;
}
}  // namespace

TEST(Malformed, EachFileReportsItsExactLocatedError) {
    fs::path dir = fs::path(CMAM_TEST_DATA_DIR) / "malformed";
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (e.path().extension() != ".pbrt") continue;
        std::string file = e.path().string();
        SCOPED_TRACE(file);
        std::ifstream in(file);
        std::string first;
        std::getline(in, first);
        bool prefix = first.rfind("# expect-prefix: ", 0) == 0;
        ASSERT_TRUE(prefix || first.rfind("# expect: ", 0) == 0)
            << "first line must state the expected error";
        std::string expected = first.substr(prefix ? 17 : 10);
        expected = replace_all(replace_all(expected, "{file}", file), "{dir}", dir.string());
        try {
            pbrt::SceneDesc d = pbrt::parse_file(file);
            render::build_scene(d, {}, {});
            ADD_FAILURE() << "no error reported";
        } catch (const pbrt::SceneError& err) {
            if (prefix)
                EXPECT_EQ(std::string(err.what()).substr(0, expected.size()), expected);
            else
                EXPECT_EQ(std::string(err.what()), expected);
        }
        ++n;
    }
    EXPECT_GE(n, 25);
}
