#include "weft/core/json_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "weft/core/error.h"
#include "weft/core/test_util.h"

namespace weft {
namespace {

using nlohmann::json;
using testing::expectInputError;

// The exact message of the InputError f throws ("" and a failure if none).
template <typename F>
std::string messageOf(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected an InputError";
    return "";
}

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

TEST(JsonReader, RangesPrintAsInMessages) {
    EXPECT_EQ(NumberRange().text(), "");
    EXPECT_EQ(NumberRange::closed(0, 1).text(), "[0, 1]");
    EXPECT_EQ(NumberRange::open(0, 180).text(), "(0, 180)");
    EXPECT_EQ(NumberRange::openClosed(0, 90).with("degrees").text(), "(0, 90] degrees");
    EXPECT_EQ(NumberRange::closedOpen(0, 0.5).text(), "[0, 0.5)");
    EXPECT_EQ(NumberRange::atLeast(0).text(), ">= 0");
    EXPECT_EQ(NumberRange::greaterThan(0).text(), "> 0");
    EXPECT_EQ(NumberRange::closed(0, 1).expectation(), "in [0, 1]");
    EXPECT_EQ(NumberRange::greaterThan(0).expectation(), "> 0");
    EXPECT_EQ((IntegerRange{0, 1024, "(0: all cores)"}).text(), "[0, 1024] (0: all cores)");

    EXPECT_TRUE(NumberRange::closed(0, 1).contains(0));
    EXPECT_TRUE(NumberRange::closed(0, 1).contains(1));
    EXPECT_FALSE(NumberRange::openClosed(0, 1).contains(0));
    EXPECT_TRUE(NumberRange::openClosed(0, 1).contains(1));
    EXPECT_FALSE(NumberRange::closedOpen(0, 1).contains(1));
    EXPECT_FALSE(NumberRange::greaterThan(0).contains(0));
    EXPECT_TRUE(NumberRange::greaterThan(0).contains(1e-300));
    EXPECT_FALSE(NumberRange().contains(kNan));
}

TEST(JsonReader, EveryMessageNamesSourceAndPath) {
    EXPECT_EQ(messageOf([] { throwJsonError("f.json", "a.b[2]", "went wrong"); }),
              "f.json: a.b[2]: went wrong");
    EXPECT_EQ(messageOf([] { throwJsonError("f.json", "", "went wrong"); }), "f.json: went wrong");
    EXPECT_EQ(messageOf([] { throwJsonOutOfRange("f.json", "a.x", "2", "[0, 1]"); }),
              "f.json: a.x = 2 is out of range: allowed [0, 1]");

    const json j = {{"a", {{"x", 1}}}};
    const JsonObjectReader r(j, "f.json");
    EXPECT_EQ(r.pathOf("a"), "a");
    const JsonObjectReader a = r.object("a");
    EXPECT_EQ(a.path(), "a");
    EXPECT_EQ(a.pathOf("x"), "a.x");
    EXPECT_EQ(messageOf([&] { a.fail("bad"); }), "f.json: a: bad");
    EXPECT_EQ(messageOf([&] { a.fail("x", "bad"); }), "f.json: a.x: bad");
    EXPECT_EQ(messageOf([&] { a.failOutOfRange("x", "1", "anything else"); }),
              "f.json: a.x = 1 is out of range: allowed anything else");
}

TEST(JsonReader, ObjectsAreChecked) {
    EXPECT_EQ(messageOf([] { JsonObjectReader(json::array({1}), "f.json"); }),
              "f.json: expected an object, got an array of 1");
    EXPECT_EQ(messageOf([] { JsonObjectReader(json("x"), "f.json", "camera"); }),
              "f.json: camera: expected an object, got the string \"x\"");
    const json j = {{"camera", 3}};
    const JsonObjectReader r(j, "s.json");
    EXPECT_EQ(messageOf([&] { r.object("camera"); }),
              "s.json: camera: expected an object, got 3");
}

TEST(JsonReader, UnknownKeysListTheAllowedOnes) {
    const json j = {{"from", 1}, {"fov", 2}};
    JsonObjectReader top(j, "s.json");
    EXPECT_EQ(messageOf([&] { top.allowKeys({"from", "to", "fov_deg"}); }),
              "s.json: unknown key \"fov\" (allowed: from, to, fov_deg)");

    const json nested = {{"camera", j}};
    const JsonObjectReader root(nested, "s.json");
    EXPECT_EQ(messageOf([&] { root.object("camera", {"from", "to", "up"}); }),
              "s.json: camera: unknown key \"fov\" (allowed: from, to, up)");

    // A key is quoted as JSON: escapes, and a cut for a long one.
    const json odd = {{"a\"b\n", 1}, {std::string(100, 'k'), 2}};
    JsonObjectReader oddReader(odd, "s.json");
    const std::string message = messageOf([&] { oddReader.allowKeys({"x"}); });
    EXPECT_EQ(message, "s.json: unknown key \"a\\\"b\\n\" (allowed: x)");

    // Every key allowed: reading goes on.
    JsonObjectReader ok(j, "s.json");
    ok.allowKeys({"from", "fov"});
    EXPECT_EQ(ok.number("fov"), 2);
}

TEST(JsonReader, ReadingAKeyOutsideTheAllowedOnesIsABug) {
    const json j = {{"a", 1}};
    JsonObjectReader r(j, "s.json");
    r.allowKeys({"a"});
    EXPECT_THROW(r.has("b"), std::logic_error);
    EXPECT_THROW(r.number("b"), std::logic_error);
}

TEST(JsonReader, MissingKeysNameTheirObject) {
    const json j = {{"camera", json::object()}};
    const JsonObjectReader r(j, "s.json");
    EXPECT_EQ(messageOf([&] { r.value("film"); }), "s.json: missing key \"film\"");
    const JsonObjectReader camera = r.object("camera");
    EXPECT_FALSE(camera.has("from"));
    EXPECT_EQ(messageOf([&] { camera.number("from"); }), "s.json: camera: missing key \"from\"");
    EXPECT_EQ(messageOf([&] { camera.boolean("flag"); }), "s.json: camera: missing key \"flag\"");
}

TEST(JsonReader, NumbersAreFiniteAndInRange) {
    const json j = {{"x", 0.5},  {"s", "30"},  {"n", nullptr}, {"b", true}, {"nan", kNan},
                    {"inf", kInf}, {"big", 2.5}, {"i", 7},      {"u", 1u}};
    const JsonObjectReader r(j, "f.json", "p");
    EXPECT_EQ(r.number("x"), 0.5);
    EXPECT_EQ(r.number("x", NumberRange::closed(0, 1)), 0.5);
    EXPECT_EQ(r.number("i"), 7);
    EXPECT_EQ(r.number("u", NumberRange::greaterThan(0)), 1);
    EXPECT_EQ(messageOf([&] { r.number("s", NumberRange::open(0, 180)); }),
              "f.json: p.s: expected a number in (0, 180), got the string \"30\"");
    EXPECT_EQ(messageOf([&] { r.number("n"); }), "f.json: p.n: expected a number, got null");
    EXPECT_EQ(messageOf([&] { r.number("b", NumberRange::atLeast(0)); }),
              "f.json: p.b: expected a number >= 0, got true");
    EXPECT_EQ(messageOf([&] { r.number("nan"); }),
              "f.json: p.nan: expected a finite number, got nan");
    EXPECT_EQ(messageOf([&] { r.number("inf", NumberRange::closed(0, 1)); }),
              "f.json: p.inf: expected a finite number in [0, 1], got inf");
    // Non-finite is rejected even where the range has no bound.
    EXPECT_THROW(r.number("inf", NumberRange::atLeast(0)), InputError);
    EXPECT_EQ(messageOf([&] { r.number("big", NumberRange::openClosed(0, 1).with("degrees")); }),
              "f.json: p.big = 2.5 is out of range: allowed (0, 1] degrees");
    EXPECT_EQ(messageOf([&] { r.number("x", NumberRange::greaterThan(0.5)); }),
              "f.json: p.x = 0.5 is out of range: allowed > 0.5");

    EXPECT_EQ(readJsonNumber(json(0.25), "f.json", "a[1][2]"), 0.25);
    EXPECT_EQ(messageOf([] { readJsonNumber(json(kNan), "f.json", "a[1][2]"); }),
              "f.json: a[1][2]: expected a finite number, got nan");
}

TEST(JsonReader, StrictIntegersAreJsonIntegers) {
    const json j = {{"n", 3},
                    {"neg", -2},
                    {"f", 3.0},
                    {"half", 2.5},
                    {"s", "3"},
                    {"huge", std::numeric_limits<uint64_t>::max()}};
    const JsonObjectReader r(j, "f.json", "t_net");
    EXPECT_EQ(r.integer("n", {1, 8}), 3);
    EXPECT_EQ(r.integer("neg", {-2, 8}), -2);
    EXPECT_EQ(r.integer("n"), 3);
    EXPECT_EQ(messageOf([&] { r.integer("f", {1, 8}); }),
              "f.json: t_net.f: expected an integer in [1, 8], got 3 (written as a "
              "floating-point number)");
    EXPECT_EQ(messageOf([&] { r.integer("half", {1, 8}); }),
              "f.json: t_net.half: expected an integer in [1, 8], got 2.5");
    EXPECT_EQ(messageOf([&] { r.integer("s"); }),
              "f.json: t_net.s: expected an integer, got the string \"3\"");
    EXPECT_EQ(messageOf([&] { r.integer("n", {4, 8, "(4: least)"}); }),
              "f.json: t_net.n = 3 is out of range: allowed [4, 8] (4: least)");
    EXPECT_EQ(messageOf([&] { r.integer("neg", {0, 8}); }),
              "f.json: t_net.neg = -2 is out of range: allowed [0, 8]");
    // Beyond int64_t: out of range, never wrapped round.
    EXPECT_EQ(messageOf([&] { r.integer("huge", {1, 64}); }),
              "f.json: t_net.huge = 18446744073709551615 is out of range: allowed [1, 64]");
    EXPECT_THROW(r.integer("huge"), InputError);
}

TEST(JsonReader, WholeNumbersAcceptIntegralFloats) {
    const json j = {{"a", 64.0}, {"b", 6.4e1}, {"c", 2.5}, {"d", 1e30}, {"e", 0x1p63}, {"n", kNan}};
    const JsonObjectReader r(j, "s.json", "film", JsonIntegers::WholeNumbers);
    EXPECT_EQ(r.integer("a", {1, 100}), 64);
    EXPECT_EQ(r.integer("b", {1, 100}), 64);
    EXPECT_EQ(messageOf([&] { r.integer("c", {1, 100}); }),
              "s.json: film.c: expected an integer in [1, 100], got 2.5");
    EXPECT_EQ(messageOf([&] { r.integer("d", {1, 100}); }),
              "s.json: film.d = 1e+30 is out of range: allowed [1, 100]");
    EXPECT_THROW(r.integer("e"), InputError);  // 2^63: past INT64_MAX
    EXPECT_THROW(r.integer("n"), InputError);
    // Children inherit the policy.
    const json nested = {{"film", j}};
    const JsonObjectReader root(nested, "s.json", "", JsonIntegers::WholeNumbers);
    EXPECT_EQ(root.object("film").integer("a"), 64);
    const JsonObjectReader strict(nested, "s.json");
    EXPECT_THROW(strict.object("film").integer("a"), InputError);
}

TEST(JsonReader, UnsignedIntegersCoverTheFullRange) {
    const json j = {{"max", std::numeric_limits<uint64_t>::max()},
                    {"neg", -1},
                    {"f", 7.0},
                    {"f64", 0x1p64},
                    {"half", 0.5}};
    const JsonObjectReader whole(j, "s.json", "render", JsonIntegers::WholeNumbers);
    EXPECT_EQ(whole.unsignedInteger("max"), std::numeric_limits<uint64_t>::max());
    EXPECT_EQ(whole.unsignedInteger("f"), 7u);
    EXPECT_EQ(messageOf([&] { whole.unsignedInteger("neg"); }),
              "s.json: render.neg = -1 is out of range: allowed [0, 18446744073709551615]");
    EXPECT_EQ(messageOf([&] { whole.unsignedInteger("f64"); }),
              "s.json: render.f64 = 18446744073709551616 is out of range: allowed [0, "
              "18446744073709551615]");
    EXPECT_EQ(messageOf([&] { whole.unsignedInteger("half"); }),
              "s.json: render.half: expected an integer in [0, 18446744073709551615], got 0.5");
    const JsonObjectReader strict(j, "s.json", "render");
    EXPECT_THROW(strict.unsignedInteger("f"), InputError);
}

TEST(JsonReader, BooleansStringsAndNames) {
    const json j = {{"t", true}, {"one", 1}, {"s", "mse"}, {"x", "relu"}, {"n", 5}};
    const JsonObjectReader r(j, "c.json", "t_net");
    EXPECT_TRUE(r.boolean("t"));
    EXPECT_EQ(messageOf([&] { r.boolean("one"); }),
              "c.json: t_net.one: expected true or false, got 1");
    EXPECT_EQ(r.string("s"), "mse");
    EXPECT_EQ(messageOf([&] { r.string("n"); }), "c.json: t_net.n: expected a string, got 5");
    EXPECT_EQ(r.oneOf("s", {"mse", "log-mse"}), 0u);
    EXPECT_EQ(messageOf([&] { r.oneOf("x", {"mse", "log-mse"}); }),
              "c.json: t_net.x: expected one of \"mse\", \"log-mse\", got the string \"relu\"");
    EXPECT_EQ(messageOf([&] { r.oneOf("n", {"mse", "log-mse"}); }),
              "c.json: t_net.n: expected one of \"mse\", \"log-mse\", got 5");
    EXPECT_EQ(messageOf([&] { r.oneOf("s", {"weft-yarn-model"}); }),
              "c.json: t_net.s: expected \"weft-yarn-model\", got the string \"mse\"");
}

TEST(JsonReader, ArraysHaveTheirLengthAndElementPaths) {
    const json j = {{"v", {1, 2, 3}},          {"short", {1, 2}},       {"s", "x"},
                    {"neg", {0.5, -1, 0.5}},   {"nan", {0, kNan, 0}},   {"w", {7, 7}},
                    {"empty", json::array()},  {"wide", {1, 2, 3, 4}},  {"wf", {7, 7.5}}};
    const JsonObjectReader r(j, "s.json", "camera");
    EXPECT_EQ(r.numbers("v", 3), (std::vector<double>{1, 2, 3}));
    EXPECT_EQ(messageOf([&] { r.numbers("short", 3); }),
              "s.json: camera.short: expected an array of 3 numbers, got an array of 2");
    EXPECT_EQ(messageOf([&] { r.numbers("s", 3, NumberRange::atLeast(0), "(r, g, b)"); }),
              "s.json: camera.s: expected an array of 3 numbers >= 0 (r, g, b), got the string "
              "\"x\"");
    EXPECT_EQ(messageOf([&] { r.numbers("neg", 3, NumberRange::atLeast(0)); }),
              "s.json: camera.neg[1] = -1 is out of range: allowed >= 0");
    EXPECT_EQ(messageOf([&] { r.numbers("nan", 3); }),
              "s.json: camera.nan[1]: expected a finite number, got nan");
    EXPECT_EQ(messageOf([&] { r.numbers("v", 1); }),
              "s.json: camera.v: expected an array of 1 number, got an array of 3");

    EXPECT_EQ(r.integers("w", 1, 3, {1, 256}), (std::vector<int64_t>{7, 7}));
    EXPECT_EQ(messageOf([&] { r.integers("empty", 1, 3, {1, 256}, "(layer widths)"); }),
              "s.json: camera.empty: expected an array of 1 to 3 integers in [1, 256] (layer "
              "widths), got an array of 0");
    EXPECT_EQ(messageOf([&] { r.integers("wide", 1, 3, {1, 256}); }),
              "s.json: camera.wide: expected an array of 1 to 3 integers in [1, 256], got an "
              "array of 4");
    EXPECT_EQ(messageOf([&] { r.integers("wf", 1, 3, {1, 256}); }),
              "s.json: camera.wf[1]: expected an integer in [1, 256], got 7.5");
    EXPECT_EQ(messageOf([&] { r.integers("v", 3, 3, {2, 3}); }),
              "s.json: camera.v[0] = 1 is out of range: allowed [2, 3]");
}

TEST(JsonReader, NestedPathsExtendAsAnyJsonPath) {
    const json j = json::parse(R"({"a": {"b": [{"c": 1}, {"c": 2}, {"c": "x"}]}, "l": 3})");
    const JsonObjectReader root(j, "n.json");
    const JsonObjectReader a = root.object("a", {"b"});
    std::vector<JsonObjectReader> bs = a.objects("b");
    ASSERT_EQ(bs.size(), 3u);
    EXPECT_EQ(bs[1].path(), "a.b[1]");
    EXPECT_EQ(bs[1].number("c"), 2);
    EXPECT_EQ(messageOf([&] { bs[2].number("c", NumberRange::closed(0, 1)); }),
              "n.json: a.b[2].c: expected a number in [0, 1], got the string \"x\"");
    EXPECT_EQ(messageOf([&] { bs[0].allowKeys({"d"}); }),
              "n.json: a.b[0]: unknown key \"c\" (allowed: d)");
    EXPECT_EQ(messageOf([&] { root.objects("l"); }),
              "n.json: l: expected an array of objects, got 3");
    const json mixed = json::parse(R"({"b": [{}, 4]})");
    EXPECT_EQ(messageOf([&] { JsonObjectReader(mixed, "m.json").objects("b"); }),
              "m.json: b[1]: expected an object, got 4");
}

TEST(JsonReader, NullAndOptionalKeys) {
    const json j = {{"masking", nullptr}, {"tilt", 1}};
    const JsonObjectReader r(j, "m.json", "r_lobe");
    EXPECT_TRUE(r.isNull("masking"));
    EXPECT_FALSE(r.isNull("tilt"));
    EXPECT_FALSE(r.isNull("absent"));
    EXPECT_TRUE(r.has("tilt"));
    EXPECT_FALSE(r.has("absent"));
}

// The reader sees the parsed object: which copy of a repeated key wins (or
// whether it is an error, as in scene.json) stays the parser's choice.
TEST(JsonReader, DuplicateKeysAreTheParsersBusiness) {
    const json j = json::parse(R"({"a": 1, "a": 2})");
    JsonObjectReader r(j, "d.json");
    r.allowKeys({"a"});
    EXPECT_EQ(r.number("a"), 2);
}

}  // namespace
}  // namespace weft
