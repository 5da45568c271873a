// For tests: an expectation that a statement throws a given exception type with a given text.
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

}  // namespace cmam::test

/// Expects `statement` to throw a `Type` whose what() is exactly `text`.
#define EXPECT_THROW_MSG(statement, Type, text) \
    EXPECT_EQ(::cmam::test::thrown_text<Type>([&] { statement; }), std::string(text))
