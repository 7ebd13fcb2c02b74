#include "recon/bundle/npy.h"

#include <zip.h>

#include <algorithm>
#include <cctype>
#include <ctime>
#include <fstream>

#include "core/file_text.h"

namespace doasido::recon {
namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr size_t kMagicLen = 6;
constexpr size_t kAlign = 64;

[[noreturn]] void Bad(const std::string& where, const std::string& what) {
  // `where` is "file" or "file:key"; split so ErrorSite names both.
  const size_t colon = where.rfind(':');
  ErrorSite site;
  if (colon == std::string::npos) {
    site.file = where;
  } else {
    site.file = where.substr(0, colon);
    site.field = where.substr(colon + 1);
  }
  throw Error("bad_npy", what, site);
}

// A tiny reader for the Python dict literal of a .npy header. It accepts
// exactly what numpy writes (and its historical variants: double quotes,
// "3L" integers, no trailing comma) and nothing more.
class HeaderParser {
 public:
  HeaderParser(const std::string& text, const std::string& where) : s_(text), where_(where) {}

  void Parse(std::string& descr, bool& fortran, std::vector<std::int64_t>& shape) {
    bool got_descr = false, got_fortran = false, got_shape = false;
    Expect('{');
    while (true) {
      SkipSpace();
      if (Peek() == '}') break;
      const std::string key = ParseString();
      Expect(':');
      SkipSpace();
      if (key == "descr") {
        if (Peek() == '[') Bad(where_, "structured dtypes are not supported");
        descr = ParseString();
        got_descr = true;
      } else if (key == "fortran_order") {
        fortran = ParseBool();
        got_fortran = true;
      } else if (key == "shape") {
        shape = ParseTuple();
        got_shape = true;
      } else {
        Bad(where_, "unexpected header key '" + key + "'");
      }
      SkipSpace();
      if (Peek() == ',') {
        ++pos_;
        continue;
      }
      SkipSpace();
      if (Peek() != '}') Bad(where_, "malformed header dict");
    }
    if (!got_descr || !got_fortran || !got_shape) {
      Bad(where_, "header lacks one of 'descr', 'fortran_order', 'shape'");
    }
  }

 private:
  char Peek() const { return pos_ < s_.size() ? s_[pos_] : '\0'; }
  void SkipSpace() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  void Expect(char c) {
    SkipSpace();
    if (Peek() != c) Bad(where_, std::string("malformed header: expected '") + c + "'");
    ++pos_;
  }
  std::string ParseString() {
    SkipSpace();
    const char quote = Peek();
    if (quote != '\'' && quote != '"') Bad(where_, "malformed header: expected a string");
    const size_t end = s_.find(quote, pos_ + 1);
    if (end == std::string::npos) Bad(where_, "malformed header: unterminated string");
    std::string out = s_.substr(pos_ + 1, end - pos_ - 1);
    pos_ = end + 1;
    return out;
  }
  bool ParseBool() {
    if (s_.compare(pos_, 4, "True") == 0) {
      pos_ += 4;
      return true;
    }
    if (s_.compare(pos_, 5, "False") == 0) {
      pos_ += 5;
      return false;
    }
    Bad(where_, "malformed header: 'fortran_order' is not True or False");
  }
  std::vector<std::int64_t> ParseTuple() {
    std::vector<std::int64_t> out;
    Expect('(');
    while (true) {
      SkipSpace();
      if (Peek() == ')') {
        ++pos_;
        return out;
      }
      if (!std::isdigit(static_cast<unsigned char>(Peek()))) {
        Bad(where_, "malformed header: shape holds a non-integer");
      }
      std::int64_t v = 0;
      while (std::isdigit(static_cast<unsigned char>(Peek()))) {
        v = v * 10 + (Peek() - '0');
        if (v > (std::int64_t{1} << 40)) Bad(where_, "shape extent is implausibly large");
        ++pos_;
      }
      if (Peek() == 'L') ++pos_;
      out.push_back(v);
      SkipSpace();
      if (Peek() == ',') ++pos_;
    }
  }

  const std::string& s_;
  const std::string& where_;
  size_t pos_ = 0;
};

void ParseDescr(const std::string& descr, const std::string& where, DType& dtype,
                int& item_size) {
  if (descr.size() < 3) Bad(where, "unsupported dtype '" + descr + "'");
  const char order = descr[0];
  const char kind = descr[1];
  int size = 0;
  for (size_t i = 2; i < descr.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(descr[i]))) {
      Bad(where, "unsupported dtype '" + descr + "'");
    }
    size = size * 10 + (descr[i] - '0');
    if (size > (1 << 20)) Bad(where, "unsupported dtype '" + descr + "'");
  }
  if (order != '<' && order != '>' && order != '|' && order != '=') {
    Bad(where, "unsupported dtype '" + descr + "'");
  }
  const int bytes = kind == 'U' ? 4 : size;
  if (order == '>' && bytes > 1) {
    Bad(where, "big-endian dtype '" + descr + "' is not supported (save little-endian)");
  }
  if (kind == 'f' && size == 8) {
    dtype = DType::kF8;
  } else if (kind == 'f' && size == 4) {
    dtype = DType::kF4;
  } else if (kind == 'u' && size == 1) {
    dtype = DType::kU1;
  } else if (kind == 'b' && size == 1) {
    dtype = DType::kB1;
  } else if (kind == 'i' && size == 4) {
    dtype = DType::kI4;
  } else if (kind == 'i' && size == 8) {
    dtype = DType::kI8;
  } else if (kind == 'U' && size >= 1) {
    dtype = DType::kUnicode;
    item_size = 4 * size;
    return;
  } else {
    Bad(where, "unsupported dtype '" + descr + "' (expected f8 f4 u1 b1 i4 i8 or U)");
  }
  item_size = size;
}

std::string ShapeTuple(const std::vector<std::int64_t>& shape) {
  std::string s = "(";
  for (size_t i = 0; i < shape.size(); ++i) {
    if (i > 0) s += ", ";
    s += std::to_string(shape[i]);
  }
  if (shape.size() == 1) s += ",";
  return s + ")";
}

std::uint32_t ReadLe(const std::string& b, size_t at, int bytes) {
  std::uint32_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[at + i]);
  return v;
}

std::string ZipMessage(int code) {
  zip_error_t err;
  zip_error_init_with_code(&err, code);
  std::string msg = zip_error_strerror(&err);
  zip_error_fini(&err);
  return msg;
}

void WriteAll(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw Error("io", "cannot create file", {.file = path.string()});
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw Error("io", "write failed (disk full?)", {.file = path.string()});
}

}  // namespace

std::string DescrOf(DType dtype, int item_size) {
  switch (dtype) {
    case DType::kF8: return "<f8";
    case DType::kF4: return "<f4";
    case DType::kU1: return "|u1";
    case DType::kB1: return "|b1";
    case DType::kI4: return "<i4";
    case DType::kI8: return "<i8";
    case DType::kUnicode: return "<U" + std::to_string(item_size / 4);
  }
  return "?";
}

std::string DTypeName(DType dtype, int item_size) { return DescrOf(dtype, item_size).substr(1); }

std::int64_t NpyArray::size() const {
  for (std::int64_t e : shape) {
    if (e == 0) return 0;
  }
  std::int64_t n = 1;
  for (std::int64_t e : shape) n *= e;
  return n;
}

std::string NpyArray::ShapeString() const { return ShapeTuple(shape); }

namespace {

// The value of type T stored at `p` (host byte order; unaligned is fine).
template <typename T>
T Load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace

double NpyArray::AsDouble(std::int64_t i) const {
  const std::uint8_t* p = data.data() + i * item_size;
  switch (dtype) {
    case DType::kF8: return Load<double>(p);
    case DType::kF4: return Load<float>(p);
    case DType::kU1: return *p;
    case DType::kB1: return *p != 0 ? 1.0 : 0.0;
    case DType::kI4: return Load<std::int32_t>(p);
    case DType::kI8: return static_cast<double>(Load<std::int64_t>(p));
    case DType::kUnicode: break;
  }
  throw Error("bad_array", "a string array has no numeric value");
}

std::int64_t NpyArray::AsInt(std::int64_t i) const {
  const std::uint8_t* p = data.data() + i * item_size;
  switch (dtype) {
    case DType::kU1: return *p;
    case DType::kB1: return *p != 0 ? 1 : 0;
    case DType::kI4: return Load<std::int32_t>(p);
    case DType::kI8: return Load<std::int64_t>(p);
    default: break;
  }
  throw Error("bad_array", "dtype " + DTypeName(dtype, item_size) + " is not an integer type");
}

std::vector<double> NpyArray::AsDoubleVector() const {
  std::vector<double> out(static_cast<size_t>(size()));
  for (std::int64_t i = 0; i < size(); ++i) out[static_cast<size_t>(i)] = AsDouble(i);
  return out;
}

std::string NpyArray::ToString() const {
  if (dtype != DType::kUnicode) throw Error("bad_array", "not a string array");
  std::string out;
  for (int c = 0; c + 4 <= item_size && static_cast<size_t>(c + 4) <= data.size(); c += 4) {
    const std::uint32_t cp = data[c] | (data[c + 1] << 8) | (data[c + 2] << 16) |
                             (static_cast<std::uint32_t>(data[c + 3]) << 24);
    if (cp == 0) break;
    out += cp < 128 ? static_cast<char>(cp) : '?';
  }
  return out;
}

NpyArray MakeBoolArray(std::vector<std::int64_t> shape, const std::vector<bool>& values) {
  NpyArray a;
  a.dtype = DType::kB1;
  a.item_size = 1;
  a.shape = std::move(shape);
  a.data.resize(values.size());
  for (size_t i = 0; i < values.size(); ++i) a.data[i] = values[i] ? 1 : 0;
  return a;
}

NpyArray MakeStringArray(const std::string& text) {
  NpyArray a;
  a.dtype = DType::kUnicode;
  const size_t chars = std::max<size_t>(1, text.size());
  a.item_size = static_cast<int>(4 * chars);
  a.data.assign(4 * chars, 0);
  for (size_t i = 0; i < text.size(); ++i) a.data[4 * i] = static_cast<std::uint8_t>(text[i]);
  return a;
}

Eigen::MatrixXd ToEigen(const NpyArray& a) {
  if (a.dtype == DType::kUnicode) throw Error("bad_array", "string array is not numeric");
  Eigen::Index rows = 1, cols = 1;
  if (a.ndim() == 1) {
    rows = a.shape[0];
  } else if (a.ndim() == 2) {
    rows = a.shape[0];
    cols = a.shape[1];
  } else if (a.ndim() > 2) {
    throw Error("bad_array", "array of shape " + a.ShapeString() + " is not 2-D");
  }
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) m(r, c) = a.AsDouble(r * cols + c);
  }
  return m;
}

NpyArray ParseNpy(const std::string& bytes, const std::string& where) {
  if (bytes.size() < kMagicLen + 4 || bytes.compare(0, kMagicLen, kMagic, kMagicLen) != 0) {
    Bad(where, "not a .npy array (magic \\x93NUMPY missing)");
  }
  const int major = static_cast<unsigned char>(bytes[6]);
  size_t len_bytes = 0;
  if (major == 1) {
    len_bytes = 2;
  } else if (major == 2 || major == 3) {
    len_bytes = 4;
  } else {
    Bad(where, "unsupported .npy format version " + std::to_string(major));
  }
  if (bytes.size() < 8 + len_bytes) Bad(where, "truncated .npy header");
  const size_t header_len = ReadLe(bytes, 8, static_cast<int>(len_bytes));
  const size_t data_start = 8 + len_bytes + header_len;
  if (bytes.size() < data_start) Bad(where, "truncated .npy header");
  const std::string header = bytes.substr(8 + len_bytes, header_len);

  std::string descr;
  bool fortran = false;
  NpyArray a;
  HeaderParser(header, where).Parse(descr, fortran, a.shape);
  if (fortran) {
    Bad(where, "Fortran-order array is not supported (save with np.ascontiguousarray)");
  }
  ParseDescr(descr, where, a.dtype, a.item_size);
  // Bound the element count by the bytes present before multiplying, so a
  // damaged shape cannot overflow.
  bool empty = false;
  for (std::int64_t e : a.shape) empty = empty || e == 0;
  if (!empty) {
    const std::uint64_t limit = bytes.size() / static_cast<std::uint64_t>(a.item_size);
    std::uint64_t count = 1;
    for (std::int64_t e : a.shape) {
      if (static_cast<std::uint64_t>(e) > limit / count) {
        Bad(where, "shape " + a.ShapeString() + " of " + DTypeName(a.dtype, a.item_size) +
                       " needs more bytes than the " + std::to_string(bytes.size()) +
                       " in the file");
      }
      count *= static_cast<std::uint64_t>(e);
    }
  }
  const size_t expected = static_cast<size_t>(a.size()) * static_cast<size_t>(a.item_size);
  const size_t got = bytes.size() - data_start;
  if (got != expected) {
    Bad(where, "data holds " + std::to_string(got) + " bytes but shape " + a.ShapeString() +
                   " of " + DTypeName(a.dtype, a.item_size) + " needs " +
                   std::to_string(expected));
  }
  a.data.assign(bytes.begin() + static_cast<std::ptrdiff_t>(data_start), bytes.end());
  return a;
}

std::string SerializeNpy(const NpyArray& a) {
  const size_t expected = static_cast<size_t>(a.size()) * static_cast<size_t>(a.item_size);
  if (a.data.size() != expected) {
    throw Error("bad_array", "array data holds " + std::to_string(a.data.size()) +
                                 " bytes but shape " + a.ShapeString() + " needs " +
                                 std::to_string(expected));
  }
  std::string dict = "{'descr': '" + DescrOf(a.dtype, a.item_size) +
                     "', 'fortran_order': False, 'shape': " + ShapeTuple(a.shape) + ", }";
  // Format 1.0 unless the header length does not fit its 16-bit field.
  int major = 1;
  size_t prefix = kMagicLen + 2 + 2;
  size_t total = prefix + dict.size() + 1;
  if (((total + kAlign - 1) / kAlign) * kAlign - prefix > 65535) {
    major = 2;
    prefix += 2;
    total += 2;
  }
  const size_t padded = ((total + kAlign - 1) / kAlign) * kAlign;
  dict.append(padded - total, ' ');
  dict += '\n';
  const size_t header_len = dict.size();

  std::string out(kMagic, kMagicLen);
  out += static_cast<char>(major);
  out += '\0';
  for (size_t i = 0; i < (major == 1 ? 2u : 4u); ++i) {
    out += static_cast<char>((header_len >> (8 * i)) & 0xff);
  }
  out += dict;
  out.append(reinterpret_cast<const char*>(a.data.data()), a.data.size());
  return out;
}

NpyArray ReadNpy(const std::filesystem::path& path) {
  return ParseNpy(ReadFileOrThrow(path, "io", "cannot open file"), path.string());
}

void WriteNpy(const std::filesystem::path& path, const NpyArray& a) {
  WriteAll(path, SerializeNpy(a));
}

NpzArchive ReadNpz(const std::filesystem::path& path) {
  const std::string file = path.string();
  if (!std::filesystem::exists(path)) throw Error("io", "file does not exist", {.file = file});
  int code = 0;
  zip_t* zip = zip_open(file.c_str(), ZIP_RDONLY, &code);
  if (zip == nullptr) {
    throw Error("bad_npy", "not a readable .npz (zip) archive: " + ZipMessage(code),
                {.file = file});
  }
  NpzArchive out;
  const zip_int64_t n = zip_get_num_entries(zip, 0);
  for (zip_int64_t i = 0; i < n; ++i) {
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(zip, static_cast<zip_uint64_t>(i), 0, &st) != 0 ||
        (st.valid & ZIP_STAT_NAME) == 0 || (st.valid & ZIP_STAT_SIZE) == 0) {
      zip_discard(zip);
      throw Error("bad_npy", "cannot stat archive member " + std::to_string(i), {.file = file});
    }
    std::string name = st.name;
    if (name.size() < 4 || name.compare(name.size() - 4, 4, ".npy") != 0) continue;
    const std::string key = name.substr(0, name.size() - 4);
    zip_file_t* member = zip_fopen_index(zip, static_cast<zip_uint64_t>(i), 0);
    if (member == nullptr) {
      const std::string msg = zip_strerror(zip);
      zip_discard(zip);
      throw Error("bad_npy", "cannot open member: " + msg, {.file = file, .field = key});
    }
    // Read as the data arrives rather than allocating the size the archive
    // claims: a damaged header may claim gigabytes for a few bytes.
    std::string bytes;
    char chunk[1 << 16];
    zip_uint64_t remaining = st.size;
    while (remaining > 0) {
      const zip_int64_t got = zip_fread(member, chunk, std::min<zip_uint64_t>(remaining, sizeof chunk));
      if (got <= 0) break;
      bytes.append(chunk, static_cast<size_t>(got));
      remaining -= static_cast<zip_uint64_t>(got);
    }
    zip_fclose(member);
    if (remaining != 0) {
      zip_discard(zip);
      throw Error("bad_npy", "member is truncated or corrupt", {.file = file, .field = key});
    }
    try {
      out[key] = ParseNpy(bytes, file + ":" + key);
    } catch (...) {
      zip_discard(zip);
      throw;
    }
  }
  zip_discard(zip);
  return out;
}

void WriteNpz(const std::filesystem::path& path, const NpzArchive& arrays, bool compress) {
  const std::string file = path.string();
  if (arrays.empty()) {
    // libzip deletes an archive with no members instead of writing one; an
    // empty zip is just its end-of-central-directory record.
    WriteAll(path, std::string("PK\x05\x06", 4) + std::string(18, '\0'));
    return;
  }
  std::vector<std::string> buffers;  // must outlive zip_close, which reads them
  buffers.reserve(arrays.size());
  for (const auto& [key, array] : arrays) buffers.push_back(SerializeNpy(array));

  int code = 0;
  zip_t* zip = zip_open(file.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
  if (zip == nullptr) {
    throw Error("io", "cannot create archive: " + ZipMessage(code), {.file = file});
  }
  // A fixed timestamp keeps archives byte-identical across runs (numpy also
  // writes a constant date).
  const std::time_t kStamp = 315964800;  // 1980-01-06
  size_t i = 0;
  for (const auto& [key, array] : arrays) {
    const std::string& bytes = buffers[i++];
    zip_source_t* src = zip_source_buffer(zip, bytes.data(), bytes.size(), 0);
    zip_int64_t index = src == nullptr ? -1
                                       : zip_file_add(zip, (key + ".npy").c_str(), src,
                                                      ZIP_FL_OVERWRITE | ZIP_FL_ENC_UTF_8);
    if (index < 0) {
      if (src != nullptr) zip_source_free(src);
      const std::string msg = zip_strerror(zip);
      zip_discard(zip);
      throw Error("io", "cannot add member: " + msg, {.file = file, .field = key});
    }
    const auto u = static_cast<zip_uint64_t>(index);
    if (zip_set_file_compression(zip, u, compress ? ZIP_CM_DEFLATE : ZIP_CM_STORE, 0) != 0 ||
        zip_file_set_mtime(zip, u, kStamp, 0) != 0) {
      const std::string msg = zip_strerror(zip);
      zip_discard(zip);
      throw Error("io", "cannot set member options: " + msg, {.file = file, .field = key});
    }
  }
  if (zip_close(zip) != 0) {
    const std::string msg = zip_strerror(zip);
    zip_discard(zip);
    throw Error("io", "cannot write archive: " + msg, {.file = file});
  }
}

const NpyArray& RequireKey(const NpzArchive& npz, const std::string& key,
                           const std::string& file) {
  auto it = npz.find(key);
  if (it == npz.end()) {
    throw Error("bad_bundle", "array '" + key + "' is missing", {.file = file, .field = key});
  }
  return it->second;
}

void CheckShape(const NpyArray& a, const std::vector<std::int64_t>& expected,
                const std::string& file, const std::string& key) {
  bool ok = a.shape.size() == expected.size();
  for (size_t i = 0; ok && i < expected.size(); ++i) {
    ok = expected[i] < 0 || expected[i] == a.shape[i];
  }
  if (!ok) {
    std::string want = "(";
    for (size_t i = 0; i < expected.size(); ++i) {
      if (i > 0) want += ", ";
      want += expected[i] < 0 ? std::string("*") : std::to_string(expected[i]);
    }
    if (expected.size() == 1) want += ",";
    want += ")";
    throw Error("bad_bundle", "shape " + a.ShapeString() + ", expected " + want,
                {.file = file, .field = key});
  }
}

void CheckFloat(const NpyArray& a, const std::string& file, const std::string& key) {
  if (!a.is_float()) {
    throw Error("bad_bundle", "dtype " + DTypeName(a.dtype, a.item_size) + ", expected f4 or f8",
                {.file = file, .field = key});
  }
}

void CheckInteger(const NpyArray& a, const std::string& file, const std::string& key) {
  if (!a.is_integer()) {
    throw Error("bad_bundle",
                "dtype " + DTypeName(a.dtype, a.item_size) + ", expected an integer type",
                {.file = file, .field = key});
  }
}

}  // namespace doasido::recon
