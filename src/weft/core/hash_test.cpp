#include "weft/core/hash.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "weft/core/image.h"

namespace weft {
namespace {

// The published FNV-1a 64-bit test vectors (Fowler, Noll and Vo).
TEST(Hash, Fnv1a64KnownValues) {
    EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ULL);
    EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
    EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ULL);
    // Piece by piece is the same as at once.
    EXPECT_EQ(fnv1a64("bar", fnv1a64("foo")), fnv1a64("foobar"));
    EXPECT_EQ(hex16(0x85944171f73967e8ULL), "85944171f73967e8");
    EXPECT_EQ(hex16(0xabcULL), "0000000000000abc");
}

// A render part's checksum: the pixels' float32 values as little-endian
// bytes, written out here by hand.
TEST(Hash, PixelChecksumIsOfTheLittleEndianFloats) {
    Image image(2, 1);
    image.pixels = {1.0f, -2.0f, 0.5f, 0.0f, -0.0f, 3.0f};
    const std::string bytes("\x00\x00\x80\x3f"   // 1
                            "\x00\x00\x00\xc0"   // -2
                            "\x00\x00\x00\x3f"   // 0.5
                            "\x00\x00\x00\x00"   // 0
                            "\x00\x00\x00\x80"   // -0
                            "\x00\x00\x40\x40",  // 3
                            24);
    EXPECT_EQ(pixelChecksum(image), "fnv1a64:" + hex16(fnv1a64(bytes)));
    Image other = image;
    other.pixels[3] = -0.0f;  // one bit
    EXPECT_NE(pixelChecksum(other), pixelChecksum(image));
}

}  // namespace
}  // namespace weft
