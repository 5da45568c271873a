// For the evaluation's tests: an exception's type and its message in one expectation.
#pragma once

#include <gtest/gtest.h>

#include <string>

/// Expects `statement` to throw `type` whose what() contains `text`.
#define EVAL_EXPECT_THROW_MSG(statement, type, text)                                       \
    do {                                                                                   \
        bool eval_thrown_ = false;                                                         \
        try {                                                                              \
            statement;                                                                     \
        } catch (const type& eval_error_) {                                                \
            eval_thrown_ = true;                                                           \
            EXPECT_NE(std::string(eval_error_.what()).find(text), std::string::npos)       \
                << "message: " << eval_error_.what() << "\nexpected to contain: " << text; \
        } catch (...) {                                                                    \
            ADD_FAILURE() << #statement " threw another type than " #type;                 \
            eval_thrown_ = true;                                                           \
        }                                                                                  \
        if (!eval_thrown_) ADD_FAILURE() << #statement " did not throw " #type;            \
    } while (false)
