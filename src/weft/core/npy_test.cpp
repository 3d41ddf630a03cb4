#include "weft/core/npy.h"

#include <gtest/gtest.h>

#include "weft/core/test_util.h"
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>

#include "weft/core/error.h"
#include "weft/core/file.h"

namespace weft {
namespace {

using namespace std::string_view_literals;
namespace fs = std::filesystem;

// A fresh directory per test, removed afterwards.
class NpyTest : public testing::TempDirTest {
protected:
    std::string file(const std::string& name) const { return path(name); }

};

using testing::expectInputError;

// A .npy file assembled by hand: magic, version, header length of the
// version's width, the header text as given, then the data.
std::string handMadeNpy(int major, int minor, std::string_view header, std::string_view data) {
    std::string out = "\x93NUMPY";
    out += static_cast<char>(major);
    out += static_cast<char>(minor);
    const size_t width = major == 1 ? 2 : 4;
    for (size_t i = 0; i < width; ++i) out += static_cast<char>((header.size() >> (8 * i)) & 0xff);
    out += header;
    out += data;
    return out;
}

std::string doubleBytes(std::initializer_list<double> values) {
    std::string out;
    for (double v : values) out.append(reinterpret_cast<const char*>(&v), sizeof v);
    return out;
}

TEST_F(NpyTest, HeaderMatchesNumpyByteForByte) {
    // What numpy.save(f, np.zeros((2, 6))) writes before the data (numpy >=
    // 1.23, with its 21-digit growth padding): 128 bytes in all.
    constexpr std::string_view kExpected =
        "\x93NUMPY\x01\x00\x76\x00"
        "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 6), }"
        "                                                          \n"sv;
    ASSERT_EQ(kExpected.size(), 128u);
    const double data[12] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    const std::string bytes = encodeNpy(data, {2, 6});
    ASSERT_EQ(bytes.size(), 128u + sizeof data);
    EXPECT_EQ(std::string_view(bytes).substr(0, 128), kExpected);
    EXPECT_EQ(std::memcmp(bytes.data() + 128, data, sizeof data), 0);

    // numpy.save(f, np.arange(3, dtype='<i4'))
    constexpr std::string_view kExpected1d =
        "\x93NUMPY\x01\x00\x76\x00"
        "{'descr': '<i4', 'fortran_order': False, 'shape': (3,), }"
        "                                                            \n"sv;
    const int32_t ints[3] = {0, 1, 2};
    EXPECT_EQ(std::string_view(encodeNpy(ints, {3})).substr(0, 128), kExpected1d);

    // numpy.save(f, np.uint8(7)): a 0-d array gets no growth padding.
    constexpr std::string_view kExpected0d =
        "\x93NUMPY\x01\x00\x76\x00"
        "{'descr': '|u1', 'fortran_order': False, 'shape': (), }"
        "                                                              \n"sv;
    const uint8_t scalar = 7;
    const std::string scalarBytes = encodeNpy(&scalar, {});
    EXPECT_EQ(std::string_view(scalarBytes).substr(0, 128), kExpected0d);
    EXPECT_EQ(scalarBytes.size(), 129u);
}

TEST_F(NpyTest, HeaderIsAlwaysAlignedTo64) {
    for (size_t rank = 0; rank <= 40; ++rank) {
        const std::vector<size_t> shape(rank, 1);
        const float v = 1.0f;
        const std::string bytes = encodeNpy(&v, shape);
        const size_t headerLen = static_cast<unsigned char>(bytes[8]) |
                                 (static_cast<size_t>(static_cast<unsigned char>(bytes[9])) << 8);
        EXPECT_EQ((10 + headerLen) % 64, 0u) << "rank " << rank;
        EXPECT_EQ(bytes[10 + headerLen - 1], '\n');
        EXPECT_EQ(bytes.size(), 10 + headerLen + sizeof v);
        const NpyArray back = decodeNpy(bytes, "aligned.npy");
        EXPECT_EQ(back.shape, shape);
    }
}

TEST_F(NpyTest, LongHeaderUsesVersion2) {
    // 30000 dimensions of size 1 ("1, " each) do not fit a 16-bit header length.
    const std::vector<size_t> shape(30000, 1);
    const double v = 2.5;
    const std::string bytes = encodeNpy(&v, shape);
    EXPECT_EQ(bytes[6], 2);
    EXPECT_EQ(bytes[7], 0);
    const NpyArray back = decodeNpy(bytes, "long.npy");
    EXPECT_EQ(back.shape.size(), shape.size());
    EXPECT_EQ(npyToDoubles(back, "long.npy"), std::vector<double>{2.5});
}

template <typename T>
class NpyRoundTrip : public NpyTest {};
using NpyTypes = ::testing::Types<float, double, int32_t, int64_t, uint8_t>;
TYPED_TEST_SUITE(NpyRoundTrip, NpyTypes);

TYPED_TEST(NpyRoundTrip, WriteThenRead) {
    using T = TypeParam;
    std::vector<T> data(24);
    for (size_t i = 0; i < data.size(); ++i)
        data[i] = static_cast<T>(std::is_signed_v<T> ? 3.0 * double(i) - 30.0 : 7.0 * double(i));
    data[5] = std::numeric_limits<T>::max();
    data[6] = std::numeric_limits<T>::lowest();
    const std::string path = this->file("a.npy");
    writeNpy(path, data.data(), {2, 3, 4});

    const NpyArray a = readNpy(path);
    const char* expectedDescr = std::is_same_v<T, float>     ? "<f4"
                                : std::is_same_v<T, double>  ? "<f8"
                                : std::is_same_v<T, int32_t> ? "<i4"
                                : std::is_same_v<T, int64_t> ? "<i8"
                                                             : "|u1";
    EXPECT_EQ(a.descr, expectedDescr);
    EXPECT_EQ(a.shape, (std::vector<size_t>{2, 3, 4}));
    EXPECT_EQ(a.size(), 24u);
    EXPECT_EQ(a.itemSize(), sizeof(T));
    ASSERT_EQ(a.bytes.size(), data.size() * sizeof(T));
    EXPECT_EQ(std::memcmp(a.bytes.data(), data.data(), a.bytes.size()), 0);

    const std::vector<double> d = npyToDoubles(a, path);
    ASSERT_EQ(d.size(), data.size());
    for (size_t i = 0; i < d.size(); ++i) EXPECT_EQ(d[i], static_cast<double>(data[i])) << i;

    // Empty arrays and 1-D arrays round-trip too.
    writeNpy<T>(path, nullptr, {0, 5});
    EXPECT_EQ(readNpy(path).shape, (std::vector<size_t>{0, 5}));
    EXPECT_TRUE(readNpy(path).bytes.empty());
    writeNpy(path, data.data(), {24});
    EXPECT_EQ(npyToDoubles(readNpy(path), path).size(), 24u);
}

TEST_F(NpyTest, ReadsAllVersionsAndHeaderSpellings) {
    const std::string data = doubleBytes({1, 2, 3, 4, 5, 6});
    const char* headers[] = {
        "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }\n",
        "{'shape':(2,3),'descr':'<f8','fortran_order':False}",
        "{ \"fortran_order\" : False , 'shape' : ( 2 , 3 , ) , 'descr' : \"<f8\" }   \n",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (2L, 3L), }\n",  // numpy on Python 2
    };
    for (int major = 1; major <= 3; ++major) {
        for (const char* h : headers) {
            const NpyArray a = decodeNpy(handMadeNpy(major, 0, h, data), "v.npy");
            EXPECT_EQ(a.descr, "<f8");
            EXPECT_EQ(a.shape, (std::vector<size_t>{2, 3})) << h;
            EXPECT_EQ(npyToDoubles(a, "v.npy"), (std::vector<double>{1, 2, 3, 4, 5, 6}));
        }
    }
}

TEST_F(NpyTest, ReadsBoolUint8AndScalar) {
    const NpyArray b =
        decodeNpy(handMadeNpy(1, 0, "{'descr': '|b1', 'fortran_order': False, 'shape': (4,), }\n",
                              "\x01\x00\x00\x01"sv),
                  "b.npy");
    EXPECT_EQ(b.descr, "|b1");
    EXPECT_EQ(npyToDoubles(b, "b.npy"), (std::vector<double>{1, 0, 0, 1}));

    // "<u1" is another spelling of "|u1".
    const NpyArray u =
        decodeNpy(handMadeNpy(1, 0, "{'descr': '<u1', 'fortran_order': False, 'shape': (2,), }\n",
                              "\xff\x03"sv),
                  "u.npy");
    EXPECT_EQ(u.descr, "|u1");
    EXPECT_EQ(npyToDoubles(u, "u.npy"), (std::vector<double>{255, 3}));

    const NpyArray s =
        decodeNpy(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False, 'shape': (), }\n",
                              doubleBytes({-0.25})),
                  "s.npy");
    EXPECT_TRUE(s.shape.empty());
    EXPECT_EQ(s.size(), 1u);
    EXPECT_EQ(npyToDoubles(s, "s.npy"), std::vector<double>{-0.25});
}

TEST_F(NpyTest, RejectsMalformedFilesNamingThem) {
    const std::string good = "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }\n";
    const std::string data = doubleBytes({1, 2});
    const std::string path = file("bad.npy");
    // Writes bytes to bad.npy and expects readNpy to fail naming it.
    const auto check = [&](std::string_view bytes, std::initializer_list<std::string> parts) {
        writeFileAtomic(path, bytes);
        SCOPED_TRACE(::testing::Message() << "case expecting '" << *parts.begin() << "'");
        expectInputError([&] { readNpy(path); }, {path});
        expectInputError([&] { readNpy(path); }, parts);
    };

    check(""sv, {"bad magic"});
    check("PK\x03\x04 not an npy at all"sv, {"bad magic"});
    check("\x93NUMP"sv, {"bad magic"});
    check("\x93NUMPY"sv, {"truncated"});
    check("\x93NUMPY\x01\x00\x10"sv, {"truncated"});
    check(handMadeNpy(4, 0, good, data), {"unsupported .npy format version 4.0"});
    check(handMadeNpy(1, 1, good, data), {"unsupported .npy format version 1.1"});
    check(handMadeNpy(0, 0, good, data), {"unsupported .npy format version 0.0"});
    // Header length beyond the end of the file.
    check(handMadeNpy(1, 0, good, "").substr(0, 30), {"truncated", "header"});

    check(handMadeNpy(1, 0, "'descr': '<f8'", data), {"malformed", "'{'"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False}\n", data),
          {"malformed", "missing key 'shape'"});
    check(handMadeNpy(1, 0, "{'shape': (2,), 'fortran_order': False}\n", data),
          {"malformed", "missing key 'descr'"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'shape': (2,)}\n", data),
          {"malformed", "missing key 'fortran_order'"});
    check(
        handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), 'x': 1}", data),
        {"malformed", "unexpected key 'x'"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'descr': '<f8', 'fortran_order': False}", data),
          {"malformed", "duplicate key 'descr'"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': Nope, 'shape': (2,)}", data),
          {"malformed", "True or False"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, -1)}", data),
          {"malformed", "integer"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False, 'shape': [2]}", data),
          {"malformed", "'('"});
    check(handMadeNpy(1, 0, "{'descr': '<f8, 'fortran_order': False, 'shape': (2,)}", data),
          {"malformed"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False, 'shape': (2,)", data),
          {"malformed"});
    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': False, 'shape': (2,)} x", data),
          {"malformed", "after the closing"});
    check(
        handMadeNpy(1, 0, "{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (2,)}", data),
        {"malformed", "structured"});
    check(handMadeNpy(1, 0,
                      "{'descr': '<f8', 'fortran_order': False, 'shape': "
                      "(99999999999999999999999,)}",
                      data),
          {"too large"});
    check(handMadeNpy(1, 0,
                      "{'descr': '<f8', 'fortran_order': False, 'shape': "
                      "(4294967296, 4294967296)}",
                      data),
          {"too large"});

    check(handMadeNpy(1, 0, "{'descr': '<f8', 'fortran_order': True, 'shape': (2,), }", data),
          {"fortran_order True"});
    check(handMadeNpy(1, 0, "{'descr': '>f8', 'fortran_order': False, 'shape': (2,), }", data),
          {"big-endian", "'>f8'"});
    check(handMadeNpy(1, 0, "{'descr': '<c16', 'fortran_order': False, 'shape': (1,), }", data),
          {"unsupported dtype '<c16'", "<f4 <f8 <i4 <i8 |u1 |b1"});
    check(handMadeNpy(1, 0, "{'descr': '|O', 'fortran_order': False, 'shape': (2,), }", data),
          {"unsupported dtype '|O'"});
    check(handMadeNpy(1, 0, good, data.substr(0, 15)), {"truncated", "16", "15"});
    check(handMadeNpy(1, 0, good, data + "xyz"), {"3 unexpected bytes"});
}

TEST_F(NpyTest, MissingFileAndDirectoryAreInputErrors) {
    const std::string missing = file("nope.npy");
    expectInputError([&] { readNpy(missing); }, {missing});
    const std::string noDir = file("no/such/dir/out.npy");
    const double v = 1;
    expectInputError([&] { writeNpy(noDir, &v, {1}); }, {noDir, "No such file or directory"});
}

TEST_F(NpyTest, NpyToDoublesRejectsInconsistentArrays) {
    NpyArray a;
    a.descr = "<f8";
    a.shape = {3};
    a.bytes.resize(16);
    expectInputError([&] { npyToDoubles(a, "mem.npy"); }, {"mem.npy", "do not match"});
    a.descr = "<c8";
    expectInputError([&] { npyToDoubles(a, "mem.npy"); }, {"mem.npy", "unsupported dtype"});
}

TEST_F(NpyTest, ReadNpyMatrix) {
    const std::string path = file("PAIRS.npy");
    const float f[12] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    writeNpy(path, f, {2, 6});
    NpyMatrix m = readNpyMatrix(path, 6, "fiber pairs");
    EXPECT_EQ(m.rows, 2u);
    EXPECT_EQ(m.cols, 6u);
    EXPECT_EQ(m(1, 2), 8.0);
    ASSERT_EQ(m.values.size(), 12u);

    const double d[6] = {1, 2, 3, 4, 5, 6};
    writeNpy(path, d, {3, 2});
    m = readNpyMatrix(path, 2, "");
    EXPECT_EQ(m.rows, 3u);
    EXPECT_EQ(m(2, 1), 6.0);
    writeNpy<double>(path, nullptr, {0, 6});
    EXPECT_EQ(readNpyMatrix(path, 6, "").rows, 0u);

    const std::vector<int64_t> ints(60, 1);
    writeNpy(path, ints.data(), {10, 6});
    try {
        readNpyMatrix(path, 6, "");
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()),
                  path + ": expected a float32 or float64 array of shape (n, 6), got <i8 (10, 6)");
    }
    writeNpy(path, d, {6});
    expectInputError([&] { readNpyMatrix(path, 6, "fiber pairs"); },
                     {path, "(n, 6) for fiber pairs", "got <f8 (6,)"});
    writeNpy(path, d, {2, 3});
    expectInputError([&] { readNpyMatrix(path, 6, ""); }, {path, "got <f8 (2, 3)"});
}

TEST(NpyShapeString, MatchesPythonRepr) {
    EXPECT_EQ(npyShapeString({}), "()");
    EXPECT_EQ(npyShapeString({3}), "(3,)");
    EXPECT_EQ(npyShapeString({2, 6}), "(2, 6)");
    EXPECT_EQ(npyShapeString({1, 2, 3}), "(1, 2, 3)");
}

}  // namespace
}  // namespace weft
