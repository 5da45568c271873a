// Exception checks for the filtering library's tests: the exception's type and its message.
#pragma once

#include <gtest/gtest.h>

#include <string>

/// Expects `statement` to throw a `Type` whose what() contains `substring`.
#define TEXTURE_EXPECT_THROW_MSG(statement, Type, substring)                                       \
    do {                                                                                           \
        bool texture_thrown = false;                                                               \
        try {                                                                                      \
            statement;                                                                             \
        } catch (const Type& texture_error) {                                                      \
            texture_thrown = true;                                                                 \
            EXPECT_NE(std::string(texture_error.what()).find(substring), std::string::npos)        \
                << #statement " threw \"" << texture_error.what() << "\", without \"" << substring \
                << "\"";                                                                           \
        } catch (...) {                                                                            \
            texture_thrown = true;                                                                 \
            ADD_FAILURE() << #statement " threw an exception other than " #Type;                   \
        }                                                                                          \
        if (!texture_thrown) ADD_FAILURE() << #statement " threw nothing";                         \
    } while (false)
