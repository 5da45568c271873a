// The name tables: each user-facing choice parses its own names, prints them back, and lists them
// for messages in the table's order.
#include <cmam/texture/cmam.h>
#include <cmam/texture/filter.h>
#include <cmam/texture/image.h>
#include <gtest/gtest.h>

#include <set>

namespace cmam::texture {
namespace {

// Every entry's name parses to its value and prints back as the name; names are unique and
// non-empty; text outside the table does not parse.
template <class Table>
void expect_round_trip(const Table& table) {
    std::set<std::string_view> seen;
    for (const auto& e : table.entries) {
        EXPECT_FALSE(e.name.empty());
        EXPECT_TRUE(seen.insert(e.name).second) << "duplicate name " << e.name;
        ASSERT_TRUE(table.parse(e.name).has_value()) << e.name;
        EXPECT_EQ(*table.parse(e.name), e.value) << e.name;
        EXPECT_EQ(table.name(e.value), e.name);
        EXPECT_FALSE(table.parse(std::string(e.name) + " ").has_value());
    }
    EXPECT_FALSE(table.parse("").has_value());
    EXPECT_EQ(table.names().size(), table.entries.size());
}

TEST(NameTables, EveryTableRoundTrips) {
    expect_round_trip(kFilterNames);
    expect_round_trip(kWrapModeNames);
    expect_round_trip(kCmamMissNames);
    expect_round_trip(kCmamEllipseNames);
    expect_round_trip(kCmamSatMissNames);
}

TEST(NameTables, ParsingIsExactAndCaseSensitive) {
    EXPECT_EQ(parse_filter("ewa"), FilterKind::Ewa);
    EXPECT_FALSE(parse_filter("EWA").has_value());
    EXPECT_FALSE(parse_wrap_mode("Repeat").has_value());
    EXPECT_EQ(parse_cmam_sat_miss("paper-literal"), CmamSatMiss::PaperLiteral);
}

TEST(NameTables, EveryFilterKindHasAName) {
    for (int k = 0; k < kFilterKinds; ++k) EXPECT_NE(to_string(FilterKind(k)), "?") << k;
    EXPECT_EQ(to_string(FilterKind(kFilterKinds)), "?");
}

TEST(NameTables, ListsReadAsMessagesDo) {
    EXPECT_EQ(filter_names(), "nearest, bilinear, trilinear, sat, ewa or area");
    EXPECT_EQ(kWrapModeNames.list("\""), "\"repeat\", \"clamp\", \"black\" or \"mirror\"");
    EXPECT_EQ(kCmamMissNames.list(), "average or point");
}

}  // namespace
}  // namespace cmam::texture
