// Tokenizer: strings, brackets, comments, locations, escapes.
#include "pbrt/tokenizer.h"

#include <gtest/gtest.h>

#include "expect_throw.h"

using namespace cmam::pbrt;

namespace {
std::vector<Token> all(const std::string& text) {
    Tokenizer t("f.pbrt", text);
    std::vector<Token> out;
    while (auto tok = t.next()) out.push_back(*tok);
    return out;
}
}  // namespace

TEST(Tokenizer, TokensAndLocations) {
    auto t = all("Shape \"sphere\" # comment [\n  \"float radius\" [ 2.5 ]");
    ASSERT_EQ(t.size(), 6u);
    EXPECT_EQ(t[0].text, "Shape");
    EXPECT_FALSE(t[0].quoted);
    EXPECT_EQ(t[1].text, "sphere");
    EXPECT_TRUE(t[1].quoted);
    EXPECT_EQ(t[1].loc.col, 7);
    EXPECT_EQ(t[2].text, "float radius");
    EXPECT_EQ(t[2].loc.line, 2);
    EXPECT_EQ(t[2].loc.col, 3);
    EXPECT_TRUE(t[3].is("["));
    EXPECT_EQ(t[4].text, "2.5");
    EXPECT_TRUE(t[5].is("]"));
    EXPECT_EQ(t[5].loc.to_string(), "f.pbrt:2:24");
}

TEST(Tokenizer, BracketsNeedNoSpaces) {
    auto t = all("[1 2]\"a\"[\"b\"]");
    ASSERT_EQ(t.size(), 8u);
    EXPECT_TRUE(t[0].is("["));
    EXPECT_EQ(t[1].text, "1");
    EXPECT_TRUE(t[3].is("]"));
    EXPECT_EQ(t[4].text, "a");
    EXPECT_EQ(t[6].text, "b");
}

TEST(Tokenizer, Escapes) {
    auto t = all(R"("a\"b\\c\n")");
    ASSERT_EQ(t.size(), 1u);
    EXPECT_EQ(t[0].text, "a\"b\\c\n");
}

TEST(Tokenizer, UnterminatedStringIsLocated) {
    EXPECT_THROW_MSG(all("Shape\n  \"sphere"), SceneError,
                     "f.pbrt:2:3: error: unterminated string");
    // A string ends on its line, and a backslash at the end of the text escapes nothing.
    EXPECT_THROW_MSG(all("Shape \"sph\nere\""), SceneError,
                     "f.pbrt:1:7: error: unterminated string");
    EXPECT_THROW_MSG(all("\n \"a\\"), SceneError, "f.pbrt:2:2: error: unterminated string");
}

TEST(Tokenizer, BadEscape) {
    EXPECT_THROW_MSG(all(R"("a\q")"), SceneError,
                     "f.pbrt:1:1: error: unknown escape \\q in string");
}
