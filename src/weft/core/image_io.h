// weft/core/image_io.h — reading and writing the HDR image files.
//
// The one home of linear image files: envmaps (render/environment_light.h) and the
// images compared and laid out by eval/ are read here, and renders written
// here. PNG, an 8-bit display format, is written by writePng (image.h, which
// this header includes) and read by decodePng / readImageOrPng (figures and
// heatmaps, never as linear data); the linear formats are:
//   OpenEXR (.exr)    read: RGB or RGBA channels, any pixel type (alpha
//                     ignored; Y-only is grey; a missing one of R, G, B reads
//                     as 0; the data window is the image); luminance/chroma
//                     and subsampled files are refused. Written: 32-bit float
//                     R, G, B, ZIP compressed (lossless).
//   Radiance (.hdr)   read only (RGBE, flat or run-length encoded), through
//                     stb_image, with truncated and corrupt files detected
//                     first (see image_io.cpp); the size is read as written
//                     (stb_image wraps "-Y 4294967312" to 16).
// Every image read is checked here, once for every command that reads one
// (compare, montage, render merge, envmaps): its size against the limits and
// the memory budget, and its pixels finite (checkFinitePixels, image.h).
#pragma once

#include <cstdint>
#include <string>

#include "weft/core/image.h"

namespace weft {

// Images larger than this (2^28 texels, 3 GiB of floats) are refused as
// corrupt rather than allocated.
inline constexpr int64_t kMaxImagePixels = int64_t(1) << 28;

// Refuses (InputError naming `path`) an image header of width x height texels
// that is empty, over kMaxImagePixels, or whose decoding would exceed the
// memory budget (core/limits.h): checked before any texel is allocated.
void checkImageSize(const std::string& path, int64_t width, int64_t height);

// Reads a linear RGB image, OpenEXR (.exr) or Radiance RGBE (.hdr); the
// extension picks the reader (case-insensitive). Values are returned as
// stored. InputError naming the file for a missing, unreadable, truncated or
// corrupt file, an unknown extension, more than kMaxImagePixels texels, or a
// NaN or infinite value (naming the first such pixel and channel).
Image readImage(const std::string& path);
// The same on the file's bytes; `path` picks the reader by its extension and
// names the file in errors.
Image decodeImage(const std::string& bytes, const std::string& path);
// A PNG's bytes as linear RGB: 8-bit RGB or RGBA (alpha ignored) decoded from
// sRGB, so that writePng at exposure 0 gives back the same bytes. InputError
// naming `path` for a file that is not a PNG, truncated or corrupt, or too
// large. The chunks are checked before stb_image decodes them (it checks
// none of this): each within the file and matching its CRC-32, IHDR first
// and valid, IEND last with nothing after it, and the image data no larger
// than twice what the image needs plus 4 KiB, inflating to exactly that.
Image decodePng(const std::string& bytes, const std::string& path);
// readImage, except that a .png file is decoded with decodePng: for the
// display images that `weft montage` lays out and `weft compare` may score.
Image readImageOrPng(const std::string& path);
// Writes linear RGB as an OpenEXR file with 32-bit float R, G, B channels,
// atomically (temp file + rename). InputError naming the file for an image
// that fails checkImage or a file that cannot be written.
void writeExr(const std::string& path, const Image& image);
// The bytes writeExr writes (`path` only names the file in errors).
std::string encodeExr(const Image& image, const std::string& path);

}  // namespace weft
