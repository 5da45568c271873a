// cmam::texture — one name table per user-facing choice.
// Each enum a user names on a command line or in a scene file (a filter, a wrap mode, a CMAM
// policy, a footprint method) has exactly one table of (value, name) pairs; parsing, printing
// and the list of valid choices in messages and --help all come from it, so they cannot drift.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cmam::texture {

template <class E>
struct Named {
    E value;
    std::string_view name;
};
/// Spelled out for compilers without deduction for aggregates (Clang before 17).
template <class E, class S>
Named(E, S) -> Named<E>;

template <class E, std::size_t N>
struct NameTable {
    std::array<Named<E>, N> entries;

    /// The value named `name` (exact, case-sensitive); nullopt for any other text.
    constexpr std::optional<E> parse(std::string_view name) const {
        for (const Named<E>& e : entries)
            if (e.name == name) return e.value;
        return std::nullopt;
    }
    /// The name of `value`; "?" for a value outside the table.
    constexpr std::string_view name(E value) const {
        for (const Named<E>& e : entries)
            if (e.value == value) return e.name;
        return "?";
    }
    /// Every name, in the table's order (for CLI11's IsMember and the like).
    std::vector<std::string> names() const {
        std::vector<std::string> out;
        out.reserve(N);
        for (const Named<E>& e : entries) out.emplace_back(e.name);
        return out;
    }
    /// The names as a message lists them: "a, b or c", each inside `quote`.
    std::string list(std::string_view quote = "") const {
        std::string out;
        for (std::size_t k = 0; k < N; ++k) {
            if (k > 0) out += k + 1 == N ? " or " : ", ";
            out += quote;
            out += entries[k].name;
            out += quote;
        }
        return out;
    }
};

template <class E, class... Rest>
NameTable(Named<E>, Rest...) -> NameTable<E, 1 + sizeof...(Rest)>;

}  // namespace cmam::texture
