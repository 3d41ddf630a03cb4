// weft/core/npy.h — NumPy .npy arrays: reading, writing, conversion to double.
//
// Format: https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html
// Reads versions 1.0, 2.0 and 3.0; writes 1.0 (2.0 only if the header would not
// fit in 1.0's 16-bit length), byte for byte what numpy.save writes, including
// numpy's spare header space and 64-byte alignment. Only little-endian, C-order
// arrays of the dtypes below; anything else is an InputError naming the file.
//
//     descr          C type     notes
//     <f4  <f8       float, double
//     <i4  <i8       int32_t, int64_t
//     |u1  (<u1)     uint8_t    read as "|u1"
//     |b1            bool       one byte, 0 or 1 (read only)
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace weft {

struct NpyArray {
    std::string descr;                 // canonical numpy dtype string, e.g. "<f8", "|u1"
    std::vector<size_t> shape;         // empty for a 0-d (scalar) array
    std::vector<unsigned char> bytes;  // raw little-endian data, C order

    // Number of elements: the product of shape (1 for a 0-d array).
    size_t size() const;
    // Bytes per element for descr.
    size_t itemSize() const;
};

// Reads a .npy file. InputError naming the file on: bad magic, unsupported
// version, malformed header, fortran_order True, big-endian or unsupported
// dtype, data shorter than the shape says, or bytes after the data.
NpyArray readNpy(const std::string& path);
// The same on bytes already in memory; `pathForErrors` names them in messages.
NpyArray decodeNpy(std::string_view bytes, const std::string& pathForErrors);

// Every element converted to double (bool -> 0/1; 64-bit integers above 2^53
// round). `pathForErrors` names the array in the InputError for an
// unsupported dtype or a byte count that does not match the shape.
std::vector<double> npyToDoubles(const NpyArray& array, const std::string& pathForErrors);

// numpy's repr of a shape tuple: "()", "(3,)", "(2, 6)".
std::string npyShapeString(const std::vector<size_t>& shape);

// The complete .npy file for `data` (product(shape) elements, C order).
// T is one of float, double, int32_t, int64_t, uint8_t.
template <typename T>
std::string encodeNpy(const T* data, const std::vector<size_t>& shape);

// encodeNpy written through writeFileAtomic.
template <typename T>
void writeNpy(const std::string& path, const T* data, const std::vector<size_t>& shape);

// A row-major 2-D array of doubles.
struct NpyMatrix {
    size_t rows = 0, cols = 0;
    std::vector<double> values;  // rows * cols, row-major

    double operator()(size_t r, size_t c) const { return values[r * cols + c]; }
};

// Reads a 2-D float32 or float64 array with exactly `cols` columns (any number
// of rows, including 0). `what` says what the array holds, for the message:
// "PAIRS.npy: expected a float32 or float64 array of shape (n, 6) for fiber
// pairs, got <i8 (10, 6)". Empty `what` leaves out the " for ..." part.
NpyMatrix readNpyMatrix(const std::string& path, size_t cols, const std::string& what);

}  // namespace weft
