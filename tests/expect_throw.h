// For tests: expectations that a statement throws a given exception type with a given text
// (exactly, or containing it), so a test pins the message as well as the type.
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace cmam::test {

/// The what() of the `E` that `f` throws; "no exception" when it returns, "an exception of
/// another type" when it throws something else.
template <class E, class F>
std::string thrown_text(F&& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    } catch (...) {
        return "an exception of another type";
    }
    return "no exception";
}

/// gtest predicate-formatter: `text` contains `part`.
inline ::testing::AssertionResult contains(const char*, const char*, const std::string& text,
                                           const std::string& part) {
    if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << "message: " << text << "\nexpected to contain: " << part;
}

}  // namespace cmam::test

/// Expects `statement` to throw a `Type` whose what() is exactly `text`.
#define EXPECT_THROW_MSG(statement, Type, text) \
    EXPECT_EQ(::cmam::test::thrown_text<Type>([&] { statement; }), std::string(text))

/// Expects `statement` to throw a `Type` whose what() contains `text`.
#define EXPECT_THROW_CONTAINS(statement, Type, text) \
    EXPECT_PRED_FORMAT2(::cmam::test::contains,      \
                        ::cmam::test::thrown_text<Type>([&] { statement; }), std::string(text))
