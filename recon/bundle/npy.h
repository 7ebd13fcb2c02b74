// NumPy .npy arrays and .npz archives, the format Python model adapters write.
//
// .npy (format 1.0, 2.0 and 3.0): the 6-byte magic "\x93NUMPY", a major and
// minor version byte, a little-endian header length (uint16 in 1.0, uint32
// in 2.0/3.0), then a Python dict literal
//   {'descr': '<f8', 'fortran_order': False, 'shape': (3, 3), }
// padded with spaces and a final '\n' so the data starts on a 64-byte
// boundary, then the raw element bytes. Supported element types are the
// little-endian (or byte-order-free) f8 f4 u1 b1 i4 i8 and unicode strings
// U<n>; only C (row-major) order. Fortran order and big-endian data are
// rejected rather than silently transposed or byte-swapped, because model
// adapters never produce them and a wrong guess would corrupt geometry.
//
// .npz: a zip archive holding one "<key>.npy" member per array (numpy.savez
// stores them, numpy.savez_compressed deflates them); both are read through
// libzip.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "core/error.h"

namespace doasido::recon {

enum class DType { kF8, kF4, kU1, kB1, kI4, kI8, kUnicode };

// The numpy descr string ("<f8", "|u1", "<U10", ...) for a dtype; `item_size`
// matters only for kUnicode (4 bytes per character).
std::string DescrOf(DType dtype, int item_size);
// Short name ("f8", "U10") for messages.
std::string DTypeName(DType dtype, int item_size);

// An n-dimensional array as stored on disk: C order, little-endian.
struct NpyArray {
  DType dtype = DType::kF8;
  int item_size = 8;                   // bytes per element
  std::vector<std::int64_t> shape;     // () for a scalar
  std::vector<std::uint8_t> data;      // size() * item_size bytes

  std::int64_t size() const;           // number of elements (1 for a scalar)
  int ndim() const { return static_cast<int>(shape.size()); }
  bool is_float() const { return dtype == DType::kF8 || dtype == DType::kF4; }
  bool is_integer() const {
    return dtype == DType::kU1 || dtype == DType::kI4 || dtype == DType::kI8 ||
           dtype == DType::kB1;
  }
  // "(2, 21, 3)" for messages.
  std::string ShapeString() const;

  // Element i (flat C-order index) converted to double; numeric dtypes only.
  double AsDouble(std::int64_t i) const;
  // Element i as int64; integer and bool dtypes only.
  std::int64_t AsInt(std::int64_t i) const;
  // Every element converted to double (numeric dtypes), in C order.
  std::vector<double> AsDoubleVector() const;
  // The string of a kUnicode scalar or one-element array (trailing NULs
  // dropped; characters outside ASCII become '?').
  std::string ToString() const;
};

template <typename T>
constexpr DType DTypeOf() {
  if constexpr (std::is_same_v<T, double>) return DType::kF8;
  else if constexpr (std::is_same_v<T, float>) return DType::kF4;
  else if constexpr (std::is_same_v<T, std::uint8_t>) return DType::kU1;
  else if constexpr (std::is_same_v<T, bool>) return DType::kB1;
  else if constexpr (std::is_same_v<T, std::int32_t>) return DType::kI4;
  else if constexpr (std::is_same_v<T, std::int64_t>) return DType::kI8;
  else static_assert(sizeof(T) == 0, "unsupported npy element type");
}

// An array of `shape` holding `values` (C order). `values.size()` must be the
// product of `shape`. T is one of double, float, uint8_t, int32_t, int64_t
// (bool is written as uint8_t 0/1 with dtype b1 through MakeBoolArray).
template <typename T>
NpyArray MakeArray(std::vector<std::int64_t> shape, const std::vector<T>& values) {
  static_assert(!std::is_same_v<T, bool>, "use MakeBoolArray");
  NpyArray a;
  a.dtype = DTypeOf<T>();
  a.item_size = sizeof(T);
  a.shape = std::move(shape);
  a.data.resize(values.size() * sizeof(T));
  if (!values.empty()) std::memcpy(a.data.data(), values.data(), a.data.size());
  return a;
}
NpyArray MakeBoolArray(std::vector<std::int64_t> shape, const std::vector<bool>& values);
// A 0-d unicode array (numpy.array("text")).
NpyArray MakeStringArray(const std::string& text);

// A 2-D array (rows, cols) from any Eigen matrix, in C order.
template <typename Derived>
NpyArray FromEigen(const Eigen::MatrixBase<Derived>& m) {
  using T = typename Derived::Scalar;
  std::vector<T> values(static_cast<size_t>(m.rows() * m.cols()));
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      values[static_cast<size_t>(r * m.cols() + c)] = m(r, c);
    }
  }
  return MakeArray<T>({m.rows(), m.cols()}, values);
}

// The array as a (rows, cols) double matrix: a 2-D array maps directly, a
// 1-D array becomes one column, a 0-d array a 1x1 matrix. Throws
// Error("bad_array") for higher rank or a non-numeric dtype.
Eigen::MatrixXd ToEigen(const NpyArray& a);

// Parses .npy bytes. `where` names the source ("K.npz:K") in errors.
// Throws Error("bad_npy") naming `where` and what is wrong.
NpyArray ParseNpy(const std::string& bytes, const std::string& where);
// Serialises to .npy bytes (format 1.0, or 2.0 when the header needs it).
std::string SerializeNpy(const NpyArray& a);

// File forms. Errors carry the path in ErrorSite::file.
NpyArray ReadNpy(const std::filesystem::path& path);
void WriteNpy(const std::filesystem::path& path, const NpyArray& a);

using NpzArchive = std::map<std::string, NpyArray>;

// Reads every "<key>.npy" member; members not ending in .npy are ignored.
// Throws Error("bad_npy") naming the file and key, or Error("io").
NpzArchive ReadNpz(const std::filesystem::path& path);
// Writes one member per key, stored (like numpy.savez) or deflated (like
// numpy.savez_compressed). Replaces an existing file. Throws Error("io").
void WriteNpz(const std::filesystem::path& path, const NpzArchive& arrays, bool compress = false);

// Validation helpers for readers of npz parts. Each throws
// Error("bad_bundle", ..., {.file = file, .field = key}).
//
// The array `key` of `npz`; throws if it is absent.
const NpyArray& RequireKey(const NpzArchive& npz, const std::string& key,
                           const std::string& file);
// Checks that the shape matches `expected`, where -1 matches any extent.
void CheckShape(const NpyArray& a, const std::vector<std::int64_t>& expected,
                const std::string& file, const std::string& key);
// Checks the dtype kind: floating (f4/f8) or integer (u1/i4/i8/b1).
void CheckFloat(const NpyArray& a, const std::string& file, const std::string& key);
void CheckInteger(const NpyArray& a, const std::string& file, const std::string& key);

}  // namespace doasido::recon
