#include "weft/core/image_io.h"

#include <OpenEXR/IexBaseExc.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStdIO.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/limits.h"

namespace weft {

namespace {

[[noreturn]] void failRead(const std::string& path, const std::string& reason) {
    throw InputError("cannot read image '" + path + "': " + reason);
}

}  // namespace

void checkImageSize(const std::string& path, int64_t width, int64_t height) {
    if (width < 1 || height < 1 || width > kMaxImagePixels / height)
        failRead(path, "size " + std::to_string(width) + " x " + std::to_string(height) +
                           " is empty or larger than " + std::to_string(kMaxImagePixels) +
                           " texels (corrupt header?)");
    // The float RGB image and the decoder's own buffer (up to as much again).
    checkMemoryBudget(static_cast<double>(width) * height * 24.0,
                      "reading image '" + path + "' (" + std::to_string(width) + " x " +
                          std::to_string(height) + ")");
}

namespace {

constexpr size_t kMalformed = ~size_t{0};

// The OpenEXR header's unsigned 32-bit little-endian number at `at`.
uint32_t littleEndian32(const std::string& bytes, size_t at) {
    uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<unsigned char>(bytes[at + k]);
    return v;
}

// The bytes OpenEXR 3.1 reads for an attribute value of `type` at `at` (at
// most `size` of them are there): fixed for the fixed-size types, parsed for
// the channel list, the preview and string vectors (whose readers ignore the
// size field or allocate what the value claims), `size` for the others
// (strings, opaque and unknown types, read as `size` bytes); kMalformed for a
// value that runs past `size`.
size_t exrAttributeBytes(const std::string& type, const std::string& bytes, size_t at, size_t size,
                         size_t maxName, size_t* channels) {
    static const std::pair<const char*, size_t> kFixed[] = {
        {"box2i", 16},      {"box2f", 16},   {"chromaticities", 32},
        {"compression", 1}, {"double", 8},   {"envmap", 1},
        {"float", 4},       {"int", 4},      {"keycode", 28},
        {"lineOrder", 1},   {"m33f", 36},    {"m33d", 72},
        {"m44f", 64},       {"m44d", 128},   {"rational", 8},
        {"tiledesc", 9},    {"timecode", 8}, {"v2i", 8},
        {"v2f", 8},         {"v2d", 16},     {"v3i", 12},
        {"v3f", 12},        {"v3d", 24},     {"deepImageState", 1}};
    for (const auto& [name, fixed] : kFixed)
        if (type == name) return fixed;
    const size_t end = at + size;
    const auto u32 = [&](size_t k) { return littleEndian32(bytes, k); };
    if (type == "chlist") {
        // Entries: name, then pixel type, linear flag, 3 reserved, x and y
        // sampling (16 bytes); an empty name ends the list.
        size_t p = at;
        for (;;) {
            const size_t nul = bytes.find('\0', p);
            if (nul == std::string::npos || nul >= end || nul - p > maxName) return kMalformed;
            if (nul == p) return nul + 1 - at;
            ++*channels;
            p = nul + 1 + 16;
            if (p > end) return kMalformed;
        }
    }
    if (type == "preview") {
        // Width and height, then 4 bytes per texel, which OpenEXR allocates.
        if (size < 8) return kMalformed;
        const uint64_t texels = uint64_t{u32(at)} * u32(at + 4);
        return texels <= (size - 8) / 4 ? static_cast<size_t>(8 + 4 * texels) : kMalformed;
    }
    if (type == "stringvector") {
        // Strings with an int32 length each, which OpenEXR allocates.
        size_t p = at;
        while (p < end) {
            if (p + 4 > end) return kMalformed;
            const uint32_t length = u32(p);
            if (length > end - p - 4) return kMalformed;
            p += 4 + length;
        }
        return size;
    }
    if (type == "floatvector") return size % 4 == 0 ? size : kMalformed;
    return size;
}

// Walks the OpenEXR header(s) before OpenEXR reads them: OpenEXR allocates
// what an attribute's size field and the data window claim (its line-offset
// table has one entry per scanline block), so a corrupt header could ask for
// gigabytes. Every attribute must fit in the file, and each part's data window
// must pass checkImageSize, before any of that is allocated.
void checkExrHeaders(const std::string& path, const std::string& bytes) {
    const auto corrupt = [&](const std::string& why) { failRead(path, "corrupt header: " + why); };
    if (bytes.size() < 8 || static_cast<unsigned char>(bytes[0]) != 0x76 ||
        static_cast<unsigned char>(bytes[1]) != 0x2f ||
        static_cast<unsigned char>(bytes[2]) != 0x31 ||
        static_cast<unsigned char>(bytes[3]) != 0x01)
        failRead(path, "not an OpenEXR file (bad magic number)");
    const auto u32 = [&](size_t at) { return littleEndian32(bytes, at); };
    const bool multipart = (u32(4) & 0x1000) != 0;
    // Names and types are at most 31 characters, 255 with the long-names flag;
    // OpenEXR reads a longer one in pieces, so such a file is refused here.
    const size_t maxName = (u32(4) & 0x400) != 0 ? 255 : 31;
    size_t at = 8;
    // A null-terminated string of at most maxName characters starting at `at`.
    const auto readString = [&](const char* what) {
        const size_t end = bytes.find('\0', at);
        if (end == std::string::npos || end - at > maxName)
            corrupt(std::string(what) + " unterminated or longer than " + std::to_string(maxName) +
                    " characters");
        std::string text = bytes.substr(at, end - at);
        at = end + 1;
        return text;
    };
    for (int part = 0;; ++part) {
        if (part > 0 && (!multipart || (at < bytes.size() && bytes[at] == '\0'))) break;
        int64_t width = 0, height = 0;
        size_t channels = 0;
        double tileArea = 0;
        for (;;) {
            const std::string name = readString("attribute name");
            if (name.empty()) break;
            const std::string type = readString("attribute type");
            if (at + 4 > bytes.size()) corrupt("attribute '" + name + "' has no size");
            const uint32_t size = u32(at);
            at += 4;
            if (size > bytes.size() - at)
                corrupt("attribute '" + name + "' claims " + std::to_string(size) +
                        " bytes, the file has " + std::to_string(bytes.size() - at) + " left");
            const size_t used = exrAttributeBytes(type, bytes, at, size, maxName, &channels);
            if (used != size)
                corrupt("attribute '" + name + "' of type '" + type + "' has size " +
                        std::to_string(size) + " but holds " +
                        (used == kMalformed ? std::string("a malformed value")
                                            : std::to_string(used) + " bytes"));
            if (name == "dataWindow" && type == "box2i") {
                const auto i32 = [&](size_t k) { return static_cast<int32_t>(u32(at + 4 * k)); };
                width = int64_t{i32(2)} - i32(0) + 1;
                height = int64_t{i32(3)} - i32(1) + 1;
                checkImageSize(path, width, height);
            }
            if (name == "tiles" && type == "tiledesc")
                tileArea = static_cast<double>(u32(at)) * static_cast<double>(u32(at + 4));
            at += size;
        }
        // OpenEXR's decompressor holds up to 256 scanlines (DWAB) of every
        // channel (4 bytes a sample), twice, whatever the image's height; a
        // tiled file one tile, whatever its claimed size.
        checkMemoryBudget(std::max(static_cast<double>(width) *
                                       static_cast<double>(std::max<int64_t>(height, 256)),
                                   tileArea) *
                              static_cast<double>(std::max<size_t>(channels, 1)) * 8.0,
                          "reading image '" + path + "' (" + std::to_string(width) + " x " +
                              std::to_string(height) + ", " + std::to_string(channels) +
                              " channels, OpenEXR's buffers)");
        if (!multipart) break;
    }
}

Image readExr(const std::string& path, const std::string& bytes) {
    checkExrHeaders(path, bytes);
    try {
        Imf::StdISStream stream;
        stream.str(bytes);
        Imf::InputFile file(stream);
        const Imath::Box2i dataWindow = file.header().dataWindow();
        const int64_t width = int64_t(dataWindow.max.x) - dataWindow.min.x + 1;
        const int64_t height = int64_t(dataWindow.max.y) - dataWindow.min.y + 1;
        checkImageSize(path, width, height);

        const Imf::ChannelList& channels = file.header().channels();
        const bool hasRgb =
            channels.findChannel("R") || channels.findChannel("G") || channels.findChannel("B");
        const bool hasY = channels.findChannel("Y") != nullptr;
        if (!hasRgb && !hasY) failRead(path, "no R, G, B or Y channel");
        if (!hasRgb && (channels.findChannel("RY") || channels.findChannel("BY")))
            failRead(path, "luminance/chroma (Y, RY, BY) files are not supported; save as RGB");
        const std::vector<const char*> names =
            hasRgb ? std::vector<const char*>{"R", "G", "B"} : std::vector<const char*>{"Y"};
        for (const char* name : names) {
            const Imf::Channel* c = channels.findChannel(name);
            if (c && (c->xSampling != 1 || c->ySampling != 1))
                failRead(path, std::string("channel ") + name + " is subsampled (unsupported)");
        }

        Image image(static_cast<int>(width), static_cast<int>(height));
        const size_t xStride = 3 * sizeof(float), yStride = xStride * image.width;
        Imf::FrameBuffer frameBuffer;
        // Missing R, G or B channels read as 0 (the slice's fill value); any
        // pixel type converts to float.
        for (size_t c = 0; c < names.size(); ++c)
            frameBuffer.insert(names[c], Imf::Slice::Make(Imf::FLOAT, &image.pixels[c], dataWindow,
                                                          xStride, yStride));
        file.setFrameBuffer(frameBuffer);
        file.readPixels(dataWindow.min.y, dataWindow.max.y);
        if (!hasRgb)
            for (size_t i = 0; i < image.pixels.size(); i += 3)
                image.pixels[i + 1] = image.pixels[i + 2] = image.pixels[i];
        return image;
    } catch (const Iex::BaseExc& e) {
        // Corrupt, truncated or non-EXR data: OpenEXR reports it by exception.
        failRead(path, std::string("not a readable OpenEXR file (") + e.what() + ")");
    }
}

// stb_image reads through these callbacks from memory and they note a read
// past the end: stb's HDR decoder fills missing bytes with zeros instead of
// failing, so this is how a truncated file is told from a complete one. (A
// file cut inside its last texel, whose missing bytes stb asks for in one
// short read, escapes this; the size check in readHdr catches it for files
// narrower than 8 texels, which are never run-length encoded.)
struct HdrReader {
    const std::string* bytes;
    size_t pos = 0;
    bool pastEnd = false;

    static int read(void* user, char* data, int size) {
        auto* r = static_cast<HdrReader*>(user);
        if (size <= 0) return 0;
        const size_t n = std::min(static_cast<size_t>(size), r->bytes->size() - r->pos);
        if (n == 0) r->pastEnd = true;
        std::memcpy(data, r->bytes->data() + r->pos, n);
        r->pos += n;
        return static_cast<int>(n);
    }
    static void skip(void* user, int n) {
        auto* r = static_cast<HdrReader*>(user);
        const int64_t pos = std::clamp<int64_t>(int64_t(r->pos) + n, 0, r->bytes->size());
        r->pos = static_cast<size_t>(pos);
    }
    static int eof(void* user) {
        const auto* r = static_cast<HdrReader*>(user);
        return r->pos >= r->bytes->size();
    }
};

// Walks the run-length encoded scanlines of a Radiance file the way stb's
// decoder does, from the first texel byte at `pos`, and returns why the data
// is unusable ("" when stb can be given it). The stb of Debian 12 (2022-09)
// loops forever on a record of length 0, which upstream rejects since
// stb_image 2.28; such a record, or data cut short, is refused here first.
// Where stb stops by itself (a flat scanline, from which on the rest of the
// image is flat, or a record overrunning the scanline) the walk stops too.
std::string checkRleScanlines(const std::string& bytes, size_t pos, int width, int height) {
    if (width < 8 || width >= 32768) return "";  // flat texels only: stb's loop ends
    const std::string truncated = "truncated: the file ends before its last scanline";
    const auto byte = [&](size_t i) { return static_cast<unsigned char>(bytes[i]); };
    for (int y = 0; y < height; ++y) {
        if (pos + 4 > bytes.size()) return truncated;
        if (byte(pos) != 2 || byte(pos + 1) != 2 || (byte(pos + 2) & 0x80)) return "";
        if ((byte(pos + 2) << 8 | byte(pos + 3)) != width) return "";
        pos += 4;
        for (int channel = 0; channel < 4; ++channel) {
            for (int filled = 0; filled < width;) {
                if (pos >= bytes.size()) return truncated;
                int count = byte(pos++);
                if (count > 128) {
                    count -= 128;  // a run: count copies of the next byte
                    pos += 1;
                } else if (count == 0) {
                    return "corrupt run-length data (a record of length 0)";
                } else {
                    pos += count;  // count literal bytes
                }
                if (count > width - filled) return "";
                filled += count;
            }
        }
    }
    return pos > bytes.size() ? truncated : "";
}

// The resolution line of a Radiance header as stb_image reads it: lines of
// at most 1023 characters, the header up to an empty line, then
// "-Y <height> +X <width>", each number as strtol takes it (leading spaces, a
// sign, digits). stb casts strtol's long to int, so that "-Y 4294967312"
// became 16; here the numbers are kept as written. nullopt where stb finds
// no such line (it then says why).
struct HdrResolution {
    std::string width, height;  // as written: a sign and digits
    size_t dataStart = 0;       // the first byte after the resolution line
};

std::optional<HdrResolution> hdrResolution(const std::string& bytes) {
    size_t pos = 0;
    const auto nextLine = [&] {
        const size_t end = std::min(bytes.find('\n', pos), bytes.size());
        std::string line = bytes.substr(pos, std::min<size_t>(end - pos, 1023));
        pos = std::min(end + 1, bytes.size());
        return line;
    };
    nextLine();  // #?RADIANCE or #?RGBE
    for (;;) {
        if (pos >= bytes.size()) return std::nullopt;
        if (nextLine().empty()) break;
    }
    const std::string line = nextLine();
    size_t at = 0;
    // strtol's number: spaces, a sign, digits ("" when there are none).
    const auto number = [&] {
        while (at < line.size() && std::isspace(static_cast<unsigned char>(line[at]))) ++at;
        const size_t start = at;
        if (at < line.size() && (line[at] == '+' || line[at] == '-')) ++at;
        const size_t digits = at;
        while (at < line.size() && std::isdigit(static_cast<unsigned char>(line[at]))) ++at;
        return at > digits ? line.substr(start, at - start) : std::string();
    };
    HdrResolution r;
    if (line.compare(0, 3, "-Y ") != 0) return std::nullopt;
    at = 3;
    r.height = number();
    while (at < line.size() && line[at] == ' ') ++at;
    if (line.compare(at, 3, "+X ") != 0 || r.height.empty()) return std::nullopt;
    at += 3;
    r.width = number();
    if (r.width.empty()) return std::nullopt;
    r.dataStart = pos;
    return r;
}

// A number of hdrResolution as int64_t, saturating beyond +-2^62.
int64_t saturatingInteger(const std::string& text) {
    const bool negative = text[0] == '-';
    int64_t v = 0;
    for (const char c : text) {
        if (!std::isdigit(static_cast<unsigned char>(c))) continue;
        v = v > (int64_t{1} << 62) / 10 ? int64_t{1} << 62 : 10 * v + (c - '0');
    }
    return negative ? -v : v;
}

Image readHdr(const std::string& path, const std::string& bytes) {
    if (bytes.size() > static_cast<size_t>(INT_MAX)) failRead(path, "file larger than 2 GiB");
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
    const int size = static_cast<int>(bytes.size());
    if (!stbi_is_hdr_from_memory(data, size))
        failRead(path, "not a Radiance RGBE file (no #?RADIANCE or #?RGBE header)");
    // The size as written, checked against the limits before stb reads it
    // (and wraps it at 2^32).
    const std::optional<HdrResolution> resolution = hdrResolution(bytes);
    if (resolution) {
        const int64_t w = saturatingInteger(resolution->width);
        const int64_t h = saturatingInteger(resolution->height);
        if (w < 1 || h < 1 || w > kMaxImagePixels / h)
            failRead(path, "size " + resolution->width + " x " + resolution->height +
                               " (the resolution line \"-Y " + resolution->height + " +X " +
                               resolution->width + "\") is empty or larger than " +
                               std::to_string(kMaxImagePixels) + " texels (corrupt header?)");
    }
    int width = 0, height = 0, channels = 0;
    if (!stbi_info_from_memory(data, size, &width, &height, &channels))
        failRead(path, std::string("bad Radiance header (") + stbi_failure_reason() + ")");
    if (!resolution || saturatingInteger(resolution->width) != width ||
        saturatingInteger(resolution->height) != height)
        failRead(path,
                 "unsupported Radiance header (its resolution line does not read as "
                 "\"-Y <height> +X <width>\")");
    checkImageSize(path, width, height);
    // A scanline takes 4 bytes per texel, or, run-length encoded (widths 8 to
    // 32767), at least 4 header bytes and 2 bytes per run of up to 127 values
    // of each of its 4 channels: a header claiming more texels than the file
    // can hold is refused before stb allocates them.
    const int64_t rowBytes =
        width < 8 || width > 32767 ? 4 * int64_t(width) : 4 + 8 * ((int64_t(width) + 126) / 127);
    // The texels follow the resolution line.
    const size_t dataStart = resolution->dataStart;
    const int64_t dataBytes = size - static_cast<int64_t>(dataStart);
    if (int64_t(height) * rowBytes > dataBytes)
        failRead(path, "truncated: " + std::to_string(width) + " x " + std::to_string(height) +
                           " texels need more than the file's " + std::to_string(dataBytes) +
                           " bytes of texel data");
    const std::string rleProblem = checkRleScanlines(bytes, dataStart, width, height);
    if (!rleProblem.empty()) failRead(path, rleProblem);

    HdrReader reader{&bytes};
    const stbi_io_callbacks callbacks{&HdrReader::read, &HdrReader::skip, &HdrReader::eof};
    float* pixels = stbi_loadf_from_callbacks(&callbacks, &reader, &width, &height, &channels, 3);
    if (!pixels) failRead(path, std::string("bad Radiance data (") + stbi_failure_reason() + ")");
    std::unique_ptr<float, void (*)(void*)> owner(pixels, &stbi_image_free);
    if (reader.pastEnd) failRead(path, "truncated: the file ends before its last scanline");
    Image image(width, height);
    std::copy(pixels, pixels + image.pixels.size(), image.pixels.begin());
    return image;
}

}  // namespace

Image readImage(const std::string& path) {
    const std::string ext = lowercaseExtension(path);
    if (ext != ".exr" && ext != ".hdr")
        failRead(path, "unsupported extension '" + ext + "' (expected .exr or .hdr)");
    return decodeImage(readFile(path), path);
}

Image decodeImage(const std::string& bytes, const std::string& path) {
    const std::string ext = lowercaseExtension(path);
    if (ext != ".exr" && ext != ".hdr")
        failRead(path, "unsupported extension '" + ext + "' (expected .exr or .hdr)");
    Image image = ext == ".exr" ? readExr(path, bytes) : readHdr(path, bytes);
    // One check where images enter: compare, montage, render merge and
    // envmaps all refuse NaN and infinite pixels, with the same message.
    checkFinitePixels(image, "cannot read image '" + path + "'");
    return image;
}

namespace {

[[noreturn]] void failPng(const std::string& path, const std::string& reason) {
    throw InputError("cannot read PNG image '" + path + "': " + reason);
}

uint32_t bigEndian32(const std::string& bytes, size_t at) {
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v = v << 8 | static_cast<unsigned char>(bytes[at + k]);
    return v;
}

// The CRC-32 of PNG chunks (ISO 3309, zlib's crc32), a byte at a time.
uint32_t pngCrc(std::string_view bytes) {
    static const std::array<uint32_t, 256> table = [] {
        std::array<uint32_t, 256> t{};
        for (uint32_t n = 0; n < 256; ++n) {
            uint32_t c = n;
            for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
            t[n] = c;
        }
        return t;
    }();
    uint32_t crc = 0xffffffffu;
    for (const char b : bytes)
        crc = table[(crc ^ static_cast<unsigned char>(b)) & 0xffu] ^ crc >> 8;
    return crc ^ 0xffffffffu;
}

// A chunk type for messages: its four letters, or its bytes in hex.
std::string chunkName(const std::string& type) {
    const bool letters = std::all_of(type.begin(), type.end(), [](char c) {
        return std::isalpha(static_cast<unsigned char>(c)) != 0;
    });
    if (letters) return type;
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%08x", bigEndian32(type, 0));
    return hex;
}

// What the image header (IHDR) says, and the bytes of filtered image data
// (one filter byte per row, Adam7's seven passes for an interlaced image)
// that the image data must inflate to.
struct PngHeader {
    uint32_t width = 0, height = 0;
    uint64_t imageDataBytes = 0;
};

PngHeader readPngHeader(const std::string& data, const std::string& path) {
    if (data.size() != 13)
        failPng(path, "IHDR chunk of " + std::to_string(data.size()) + " bytes (expected 13)");
    PngHeader h;
    h.width = bigEndian32(data, 0);
    h.height = bigEndian32(data, 4);
    const int depth = static_cast<unsigned char>(data[8]),
              colour = static_cast<unsigned char>(data[9]);
    const int interlace = static_cast<unsigned char>(data[12]);
    // Samples per texel of each colour type, and the bit depths it allows.
    int samples = 0;
    bool depthOk = false;
    switch (colour) {
        case 0:
            samples = 1,
            depthOk = depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16;
            break;
        case 3:
            samples = 1, depthOk = depth == 1 || depth == 2 || depth == 4 || depth == 8;
            break;
        case 2:
            samples = 3, depthOk = depth == 8 || depth == 16;
            break;
        case 4:
            samples = 2, depthOk = depth == 8 || depth == 16;
            break;
        case 6:
            samples = 4, depthOk = depth == 8 || depth == 16;
            break;
        default:
            break;
    }
    if (samples == 0 || !depthOk || data[10] != 0 || data[11] != 0 || interlace > 1)
        failPng(path, "IHDR: colour type " + std::to_string(colour) + ", bit depth " +
                          std::to_string(depth) + ", compression " +
                          std::to_string(static_cast<unsigned char>(data[10])) + ", filter " +
                          std::to_string(static_cast<unsigned char>(data[11])) + ", interlace " +
                          std::to_string(interlace) + " is not a valid PNG header");
    checkImageSize(path, h.width, h.height);
    const uint64_t bits = static_cast<uint64_t>(samples) * depth;
    const auto passBytes = [&](uint64_t w, uint64_t rows) {
        return w == 0 || rows == 0 ? 0 : rows * (1 + (w * bits + 7) / 8);
    };
    if (interlace == 0) {
        h.imageDataBytes = passBytes(h.width, h.height);
    } else {
        static const int x0[7] = {0, 4, 0, 2, 0, 1, 0}, y0[7] = {0, 0, 4, 0, 2, 0, 1};
        static const int dx[7] = {8, 8, 4, 4, 2, 2, 1}, dy[7] = {8, 8, 8, 4, 4, 2, 2};
        for (int p = 0; p < 7; ++p)
            h.imageDataBytes += passBytes((h.width + dx[p] - 1 - x0[p]) / dx[p],
                                          (h.height + dy[p] - 1 - y0[p]) / dy[p]);
    }
    return h;
}

// stb_image checks no CRC, reserves what a chunk's length field claims
// before reading it (up to 2 GB), reads nothing after IEND and inflates image
// data beyond what the image needs. So the chunks are walked first: the
// signature, every chunk within the file and matching its CRC, IHDR first and
// valid, IEND last, and the IDAT data (at most twice the image's filtered
// size, plus 4 KiB) inflating to exactly the bytes the image needs.
void checkPngChunks(const std::string& bytes, const std::string& path) {
    static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kSignature, 8) != 0)
        failPng(path, "not a PNG file (bad signature)");
    // The chunks' frames first (each within the file, IEND last), then their
    // CRCs and contents.
    std::vector<std::pair<size_t, uint32_t>> chunks;  // offset, data length
    for (size_t at = 8;;) {
        if (at >= bytes.size())
            failPng(path,
                    "no IEND chunk: the file ends at byte " + std::to_string(at) + " (truncated?)");
        if (bytes.size() - at < 12)
            failPng(path, "chunk at byte " + std::to_string(at) + " is cut short (truncated?)");
        const uint32_t length = bigEndian32(bytes, at);
        if (length > bytes.size() - at - 12)
            failPng(path, "chunk at byte " + std::to_string(at) + " claims " +
                              std::to_string(length) + " bytes, the file has " +
                              std::to_string(bytes.size() - at - 12) +
                              " left (truncated or corrupt)");
        chunks.emplace_back(at, length);
        at += 12 + static_cast<size_t>(length);
        if (bytes.compare(at - 8 - length, 4, "IEND") == 0) {
            if (at != bytes.size())
                failPng(path, std::to_string(bytes.size() - at) +
                                  " bytes after the IEND chunk (corrupt file)");
            break;
        }
    }
    std::optional<PngHeader> header;
    bool apple = false;  // a CgBI chunk first: raw deflate data (stb reads it)
    std::string imageData;
    for (const auto& [at, length] : chunks) {
        const std::string type = bytes.substr(at + 4, 4);
        const std::string name = chunkName(type);
        const uint32_t stored = bigEndian32(bytes, at + 8 + length);
        const uint32_t crc = pngCrc(std::string_view(bytes).substr(at + 4, 4 + length));
        if (stored != crc) {
            char text[96];
            std::snprintf(text, sizeof text, " at byte %zu: CRC 0x%08x, but its bytes give 0x%08x",
                          at, stored, crc);
            failPng(path, name + " chunk" + text + " (corrupt file)");
        }
        const std::string data = bytes.substr(at + 8, length);
        if (!header && type == "CgBI" && at == 8) {
            apple = true;
        } else if (!header) {
            if (type != "IHDR")
                failPng(path, "the first chunk is " + name + ", not IHDR (corrupt file)");
            header = readPngHeader(data, path);
        } else if (type == "IHDR") {
            failPng(path, "a second IHDR chunk at byte " + std::to_string(at));
        } else if (type == "IDAT") {
            if (imageData.size() + length > 2 * header->imageDataBytes + 4096)
                failPng(path,
                        "IDAT chunks hold more than " +
                            std::to_string(2 * header->imageDataBytes + 4096) +
                            " bytes, over twice the " + std::to_string(header->imageDataBytes) +
                            " bytes of image data a " + std::to_string(header->width) + " x " +
                            std::to_string(header->height) + " image needs (corrupt file)");
            imageData += data;
        }
    }
    if (!header) failPng(path, "no IHDR chunk");
    // Inflated into a buffer of exactly the image's size: a stream that
    // holds more stops at its end (stb reports "output buffer limit").
    const uint64_t needed = header->imageDataBytes;
    if (needed > static_cast<uint64_t>(INT_MAX) || imageData.size() > static_cast<size_t>(INT_MAX))
        failPng(path, "image data of " + std::to_string(needed) + " bytes: too large");
    std::string inflated(static_cast<size_t>(needed), '\0');
    const int n = (apple ? stbi_zlib_decode_noheader_buffer : stbi_zlib_decode_buffer)(
        inflated.data(), static_cast<int>(needed), imageData.data(),
        static_cast<int>(imageData.size()));
    const std::string image =
        std::to_string(header->width) + " x " + std::to_string(header->height) + " image needs";
    if (n < 0 && std::strcmp(stbi_failure_reason(), "output buffer limit") == 0)
        failPng(path, "its image data inflate to more than the " + std::to_string(needed) +
                          " bytes a " + image + " (surplus data; corrupt file)");
    if (n < 0) failPng(path, std::string("corrupt image data (") + stbi_failure_reason() + ")");
    if (static_cast<uint64_t>(n) < needed)
        failPng(path, "its image data inflate to " + std::to_string(n) + " bytes, fewer than the " +
                          std::to_string(needed) + " bytes a " + image + " (truncated?)");
}

}  // namespace

Image decodePng(const std::string& bytes, const std::string& path) {
    if (bytes.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
        throw InputError("cannot read PNG image '" + path + "': file too large");
    checkPngChunks(bytes, path);
    int w = 0, h = 0, channels = 0;
    // The header first: a 16384 x 16384 PNG is refused before it is decoded.
    if (!stbi_info_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                               static_cast<int>(bytes.size()), &w, &h, &channels))
        throw InputError("cannot read PNG image '" + path + "': " + stbi_failure_reason());
    checkImageSize(path, w, h);
    std::unique_ptr<stbi_uc, void (*)(void*)> data(
        stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                              static_cast<int>(bytes.size()), &w, &h, &channels, 3),
        stbi_image_free);
    if (!data) throw InputError("cannot read PNG image '" + path + "': " + stbi_failure_reason());
    Image image(w, h);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        image.pixels[i] = static_cast<float>(srgbToLinear(data.get()[i] / 255.0));
    return image;
}

Image readImageOrPng(const std::string& path) {
    const std::string ext = lowercaseExtension(path);
    if (ext != ".exr" && ext != ".hdr" && ext != ".png")
        failRead(path, "unsupported extension '" + ext + "' (expected .exr, .hdr or .png)");
    if (ext != ".png") return readImage(path);
    return decodePng(readFile(path), path);
}

std::string encodeExr(const Image& image, const std::string& path) {
    checkImage(image, "cannot write OpenEXR image '" + path + "'");
    std::string bytes;
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;  // lossless
        const char* names[3] = {"R", "G", "B"};
        for (const char* name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
        Imf::FrameBuffer frameBuffer;
        const size_t xStride = 3 * sizeof(float), yStride = xStride * image.width;
        for (int c = 0; c < 3; ++c)
            frameBuffer.insert(names[c], Imf::Slice::Make(Imf::FLOAT, &image.pixels[c],
                                                          header.dataWindow(), xStride, yStride));
        // Encoded in memory, then written through writeFileAtomic (temp file
        // + rename): a reader never sees a half-written file.
        Imf::StdOSStream stream;
        {
            Imf::OutputFile file(stream, header);
            file.setFrameBuffer(frameBuffer);
            file.writePixels(image.height);
        }  // the destructor completes the line offset table
        bytes = stream.str();
    } catch (const Iex::BaseExc& e) {
        throw InputError("cannot write OpenEXR image '" + path + "': " + e.what());
    }
    return bytes;
}

void writeExr(const std::string& path, const Image& image) {
    writeFileAtomic(path, encodeExr(image, path));
}

}  // namespace weft
