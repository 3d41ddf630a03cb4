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
#include <climits>
#include <cstring>
#include <memory>
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

Image readExr(const std::string& path, const std::string& bytes) {
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

Image readHdr(const std::string& path, const std::string& bytes) {
    if (bytes.size() > static_cast<size_t>(INT_MAX)) failRead(path, "file larger than 2 GiB");
    const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
    const int size = static_cast<int>(bytes.size());
    if (!stbi_is_hdr_from_memory(data, size))
        failRead(path, "not a Radiance RGBE file (no #?RADIANCE or #?RGBE header)");
    int width = 0, height = 0, channels = 0;
    if (!stbi_info_from_memory(data, size, &width, &height, &channels))
        failRead(path, std::string("bad Radiance header (") + stbi_failure_reason() + ")");
    checkImageSize(path, width, height);
    // A scanline takes 4 bytes per texel, or, run-length encoded (widths 8 to
    // 32767), at least 4 header bytes and 2 bytes per run of up to 127 values
    // of each of its 4 channels: a header claiming more texels than the file
    // can hold is refused before stb allocates them.
    const int64_t rowBytes =
        width < 8 || width > 32767 ? 4 * int64_t(width) : 4 + 8 * ((int64_t(width) + 126) / 127);
    // The texels follow the resolution line, the line after the blank line
    // that ends the header.
    const size_t blank = bytes.find("\n\n");
    const size_t dataStart = blank == std::string::npos ? 0 : bytes.find('\n', blank + 2) + 1;
    const int64_t dataBytes = size - static_cast<int64_t>(std::min(dataStart, bytes.size()));
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
    return ext == ".exr" ? readExr(path, bytes) : readHdr(path, bytes);
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
