// .npy and .npz files built byte by byte from the published format
// (numpy/lib/format.py documentation; PKWARE APPNOTE for zip) parse to the
// values they hold, the writer produces exactly what numpy writes, and
// unsupported or damaged input is rejected with the file and key named.
#include "recon/bundle/npy.h"

#include <cstring>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/test_util.h"

namespace doasido::recon {
namespace {

using ::testing::HasSubstr;
using doasido::testing::ReadFile;
using doasido::testing::TempDir;
using doasido::testing::WriteFile;

void PutLe(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((v >> (8 * i)) & 0xff);
}

std::string DoubleLe(double d) {
  std::uint64_t bits;
  std::memcpy(&bits, &d, 8);
  std::string s;
  PutLe(s, bits, 8);
  return s;
}

// An .npy file as the format document describes it: magic, version, header
// length, the dict padded with spaces and '\n' to a multiple of `align`.
std::string NpyBytes(int major, const std::string& dict, const std::string& data,
                     size_t align = 64) {
  const size_t len_bytes = major == 1 ? 2 : 4;
  const size_t prefix = 8 + len_bytes;
  size_t total = prefix + dict.size() + 1;
  const size_t padded = (total + align - 1) / align * align;
  std::string header = dict + std::string(padded - total, ' ') + "\n";
  std::string out = std::string("\x93NUMPY", 6);
  out += static_cast<char>(major);
  out += '\0';
  PutLe(out, header.size(), static_cast<int>(len_bytes));
  return out + header + data;
}

TEST(NpyTest, ParsesVersion1Float64Matrix) {
  std::string data;
  for (int i = 1; i <= 6; ++i) data += DoubleLe(i * 0.5);
  const std::string bytes =
      NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }", data);
  ASSERT_EQ(bytes.size() % 64, 48u);  // 64-byte header + 48 data bytes
  const NpyArray a = ParseNpy(bytes, "x.npy");
  EXPECT_EQ(a.dtype, DType::kF8);
  EXPECT_EQ(a.shape, (std::vector<std::int64_t>{2, 3}));
  const Eigen::MatrixXd m = ToEigen(a);
  ASSERT_EQ(m.rows(), 2);
  ASSERT_EQ(m.cols(), 3);
  EXPECT_EQ(m(0, 0), 0.5);
  EXPECT_EQ(m(0, 2), 1.5);  // C order: row 0 holds the first three values
  EXPECT_EQ(m(1, 0), 2.0);
  EXPECT_EQ(m(1, 2), 3.0);
}

TEST(NpyTest, WriterMatchesNumpyBytes) {
  std::string data;
  for (int i = 1; i <= 6; ++i) data += DoubleLe(i * 0.5);
  const std::string expected =
      NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }", data);
  Eigen::Matrix<double, 2, 3> m;
  m << 0.5, 1.0, 1.5, 2.0, 2.5, 3.0;
  EXPECT_EQ(SerializeNpy(FromEigen(m)), expected);
  // A 1-D shape is written as a one-element tuple "(3,)".
  const std::string expected_1d = NpyBytes(
      1, "{'descr': '<i4', 'fortran_order': False, 'shape': (3,), }", std::string(12, '\0'));
  EXPECT_EQ(SerializeNpy(MakeArray<std::int32_t>({3}, {0, 0, 0})), expected_1d);
}

TEST(NpyTest, ParsesVersion2Int32AndOldStyleHeaders) {
  std::string data;
  for (std::int32_t v : {-1, 2, 70000}) PutLe(data, static_cast<std::uint32_t>(v), 4);
  // Version 2.0 has a 4-byte header length; old numpy aligned to 16 bytes.
  const NpyArray a = ParseNpy(
      NpyBytes(2, "{'descr': '<i4', 'fortran_order': False, 'shape': (3,), }", data, 16), "v2");
  EXPECT_EQ(a.dtype, DType::kI4);
  ASSERT_EQ(a.size(), 3);
  EXPECT_EQ(a.AsInt(0), -1);
  EXPECT_EQ(a.AsInt(1), 2);
  EXPECT_EQ(a.AsInt(2), 70000);
  // Python 2 numpy wrote long integers with an L suffix and keys in any order.
  std::string i8;
  PutLe(i8, static_cast<std::uint64_t>(-5), 8);
  PutLe(i8, 1ull << 40, 8);
  const NpyArray b = ParseNpy(
      NpyBytes(1, "{'shape': (2L,), 'fortran_order': False, \"descr\": '<i8'}", i8), "py2");
  EXPECT_EQ(b.AsInt(0), -5);
  EXPECT_EQ(b.AsInt(1), std::int64_t{1} << 40);
}

TEST(NpyTest, ParsesBoolUint8ScalarsFloat32AndStrings) {
  const NpyArray b = ParseNpy(
      NpyBytes(1, "{'descr': '|b1', 'fortran_order': False, 'shape': (2, 2), }",
               std::string("\x01\x00\x00\x01", 4)),
      "b");
  EXPECT_EQ(b.dtype, DType::kB1);
  EXPECT_EQ(b.AsDoubleVector(), (std::vector<double>{1, 0, 0, 1}));

  const NpyArray u = ParseNpy(
      NpyBytes(1, "{'descr': '|u1', 'fortran_order': False, 'shape': (), }", "\xff"), "u");
  EXPECT_EQ(u.ndim(), 0);
  EXPECT_EQ(u.size(), 1);
  EXPECT_EQ(u.AsInt(0), 255);

  float f = -2.25f;
  std::uint32_t fb;
  std::memcpy(&fb, &f, 4);
  std::string fd;
  PutLe(fd, fb, 4);
  const NpyArray a = ParseNpy(
      NpyBytes(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 1), }", fd), "f");
  EXPECT_EQ(a.dtype, DType::kF4);
  EXPECT_EQ(a.AsDouble(0), -2.25);

  const NpyArray empty = ParseNpy(
      NpyBytes(1, "{'descr': '<f4', 'fortran_order': False, 'shape': (0, 3), }", ""), "e");
  EXPECT_EQ(empty.size(), 0);

  // numpy.array("openpose21"): UTF-32LE, 10 characters.
  std::string text;
  for (char c : std::string("openpose21")) PutLe(text, static_cast<unsigned char>(c), 4);
  const NpyArray s = ParseNpy(
      NpyBytes(1, "{'descr': '<U10', 'fortran_order': False, 'shape': (), }", text), "s");
  EXPECT_EQ(s.ToString(), "openpose21");
  EXPECT_EQ(SerializeNpy(MakeStringArray("openpose21")), SerializeNpy(s));
}

void ExpectBadNpy(const std::string& bytes, const std::string& needle) {
  try {
    ParseNpy(bytes, "/data/hands.npz:left_joints");
    ADD_FAILURE() << "no error for " << needle;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "bad_npy");
    EXPECT_THAT(std::string(e.what()), HasSubstr(needle));
    EXPECT_EQ(e.site().file, "/data/hands.npz");
    EXPECT_EQ(e.site().field, "left_joints");
  }
}

TEST(NpyTest, RejectsFortranOrderBigEndianAndDamage) {
  const std::string data = DoubleLe(1) + DoubleLe(2);
  ExpectBadNpy(NpyBytes(1, "{'descr': '<f8', 'fortran_order': True, 'shape': (2, 1), }", data),
               "Fortran");
  ExpectBadNpy(NpyBytes(1, "{'descr': '>f8', 'fortran_order': False, 'shape': (2,), }", data),
               "big-endian");
  ExpectBadNpy(NpyBytes(1, "{'descr': '<c16', 'fortran_order': False, 'shape': (1,), }", data),
               "unsupported dtype '<c16'");
  ExpectBadNpy(NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }", data),
               "16 bytes but shape (3,) of f8 needs 24");
  ExpectBadNpy(NpyBytes(1, "{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (1,), }",
                        data),
               "structured");
  ExpectBadNpy("PK\x03\x04 not an npy", "magic");
  ExpectBadNpy(NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }", data)
                   .substr(0, 20),
               "truncated");
}

TEST(NpyTest, DamagedBytesThrowOrParseButNeverCrash) {
  std::string data;
  for (int i = 0; i < 6; ++i) data += DoubleLe(i);
  const std::string good =
      NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }", data);
  int parsed = 0, rejected = 0;
  auto attempt = [&](const std::string& bytes) {
    try {
      const NpyArray a = ParseNpy(bytes, "damaged.npy");
      // Whatever parses is self-consistent.
      EXPECT_EQ(a.data.size(), static_cast<size_t>(a.size() * a.item_size));
      ++parsed;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "bad_npy");
      ++rejected;
    }
  };
  for (size_t n = 0; n < good.size(); ++n) attempt(good.substr(0, n));  // every truncation
  std::mt19937 rng(12);
  for (int trial = 0; trial < 2000; ++trial) {
    std::string bytes = good;
    const int flips = 1 + static_cast<int>(rng() % 3);
    for (int f = 0; f < flips; ++f) {
      bytes[rng() % 80] = static_cast<char>(rng() & 0xff);  // damage magic and header
    }
    attempt(bytes);
  }
  EXPECT_EQ(rejected + parsed, static_cast<int>(good.size()) + 2000);
  EXPECT_GE(rejected, static_cast<int>(good.size()));  // no truncation parses
}

TEST(NpyTest, BigEndianSingleBytesAreFine) {
  // Byte order does not apply to one-byte types; numpy may label them '>'.
  const NpyArray a = ParseNpy(
      NpyBytes(1, "{'descr': '>u1', 'fortran_order': False, 'shape': (1,), }", "\x07"), "u1");
  EXPECT_EQ(a.AsInt(0), 7);
}

// CRC-32 (IEEE 802.3, reflected 0xEDB88320), as zip requires.
std::uint32_t Crc32(const std::string& s) {
  std::uint32_t crc = 0xffffffffu;
  for (unsigned char c : s) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

// A zip archive of stored members, laid out as in PKWARE's APPNOTE: local
// headers with data, then the central directory, then its end record. With
// `zip64_local`, each local header is written the way numpy.savez's
// zipfile.open(..., force_zip64=True) leaves it: version 4.5, 0xFFFFFFFF in
// the 32-bit size fields and the real sizes in a ZIP64 extra field.
std::string StoredZip(const std::vector<std::pair<std::string, std::string>>& members,
                      bool zip64_local = false) {
  std::string body, central;
  const int version = zip64_local ? 45 : 20;
  for (const auto& [name, data] : members) {
    const std::uint32_t offset = static_cast<std::uint32_t>(body.size());
    const std::uint32_t crc = Crc32(data);
    std::string extra;
    if (zip64_local) {
      PutLe(extra, 0x0001, 2);  // ZIP64 extended information
      PutLe(extra, 16, 2);
      PutLe(extra, data.size(), 8);  // uncompressed
      PutLe(extra, data.size(), 8);  // compressed
    }
    body += "PK\x03\x04";
    PutLe(body, version, 2);  // version needed
    PutLe(body, 0, 2);   // flags
    PutLe(body, 0, 2);   // method: stored
    PutLe(body, 0, 2);   // time
    PutLe(body, 0x21, 2);  // date 1980-01-01
    PutLe(body, crc, 4);
    PutLe(body, zip64_local ? 0xffffffffu : data.size(), 4);
    PutLe(body, zip64_local ? 0xffffffffu : data.size(), 4);
    PutLe(body, name.size(), 2);
    PutLe(body, extra.size(), 2);
    body += name + extra + data;
    central += "PK\x01\x02";
    PutLe(central, version, 2);  // made by
    PutLe(central, version, 2);  // needed
    PutLe(central, 0, 2);
    PutLe(central, 0, 2);
    PutLe(central, 0, 2);
    PutLe(central, 0x21, 2);
    PutLe(central, crc, 4);
    PutLe(central, data.size(), 4);
    PutLe(central, data.size(), 4);
    PutLe(central, name.size(), 2);
    PutLe(central, 0, 2);  // extra
    PutLe(central, 0, 2);  // comment
    PutLe(central, 0, 2);  // disk
    PutLe(central, 0, 2);  // internal attributes
    PutLe(central, 0, 4);  // external attributes
    PutLe(central, offset, 4);
    central += name;
  }
  std::string end = "PK\x05\x06";
  PutLe(end, 0, 2);
  PutLe(end, 0, 2);
  PutLe(end, members.size(), 2);
  PutLe(end, members.size(), 2);
  PutLe(end, central.size(), 4);
  PutLe(end, body.size(), 4);
  PutLe(end, 0, 2);
  return body + central + end;
}

TEST(NpzTest, ReadsHandMadeStoredArchive) {
  TempDir dir;
  std::string k;
  for (double v : {500.0, 0.0, 319.5, 0.0, 500.0, 239.5, 0.0, 0.0, 1.0}) k += DoubleLe(v);
  const std::string k_npy =
      NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (3, 3), }", k);
  const std::string v_npy = NpyBytes(
      1, "{'descr': '|u1', 'fortran_order': False, 'shape': (4,), }", std::string("\1\0\1\1", 4));
  WriteFile(dir / "a.npz", StoredZip({{"K.npy", k_npy}, {"valid.npy", v_npy}, {"README", "x"}}));
  const NpzArchive npz = ReadNpz(dir / "a.npz");
  ASSERT_EQ(npz.size(), 2u);  // the non-.npy member is ignored
  const Eigen::MatrixXd K = ToEigen(npz.at("K"));
  EXPECT_EQ(K(0, 2), 319.5);
  EXPECT_EQ(K(1, 2), 239.5);
  EXPECT_EQ(K(2, 2), 1.0);
  EXPECT_EQ(npz.at("valid").AsDoubleVector(), (std::vector<double>{1, 0, 1, 1}));
}

TEST(NpzTest, ReadsNumpyStyleZip64LocalHeaders) {
  TempDir dir;
  std::string joints;
  for (int i = 0; i < 2 * 21 * 3; ++i) joints += DoubleLe(0.001 * i);
  const std::string npy =
      NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 21, 3), }", joints);
  WriteFile(dir / "hands.npz", StoredZip({{"right_joints.npy", npy}}, true));
  const NpzArchive npz = ReadNpz(dir / "hands.npz");
  ASSERT_EQ(npz.count("right_joints"), 1u);
  const NpyArray& a = npz.at("right_joints");
  EXPECT_EQ(a.shape, (std::vector<std::int64_t>{2, 21, 3}));
  EXPECT_EQ(a.AsDouble(1 * 63 + 20 * 3 + 2), 0.001 * 125);  // [1, 20, 2]
}

TEST(NpzTest, WritesStoredAndDeflatedMembersThatReadBack) {
  TempDir dir;
  std::vector<double> values(3000);
  for (size_t i = 0; i < values.size(); ++i) values[i] = static_cast<double>(i % 17) * 0.25;
  const NpzArchive in = {{"a", MakeArray<double>({1000, 3}, values)},
                         {"flag", MakeBoolArray({3}, {true, false, true})}};
  for (bool compress : {false, true}) {
    const auto path = dir / (compress ? "c.npz" : "s.npz");
    WriteNpz(path, in, compress);
    const std::string raw = ReadFile(path);
    // Compression method of the first local header (offset 8): 0 stored, 8 deflate.
    ASSERT_GT(raw.size(), 10u);
    EXPECT_EQ(static_cast<int>(raw[8]), compress ? 8 : 0);
    const NpzArchive out = ReadNpz(path);
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out.at("a").data, in.at("a").data);
    EXPECT_EQ(out.at("a").shape, in.at("a").shape);
    EXPECT_EQ(out.at("flag").dtype, DType::kB1);
    EXPECT_EQ(out.at("flag").data, in.at("flag").data);
  }
  EXPECT_LT(std::filesystem::file_size(dir / "c.npz"), std::filesystem::file_size(dir / "s.npz"));
}

TEST(NpzTest, ErrorsNameFileAndKey) {
  TempDir dir;
  const std::string bad =
      NpyBytes(1, "{'descr': '<f8', 'fortran_order': True, 'shape': (1, 1), }", DoubleLe(1));
  WriteFile(dir / "bad.npz", StoredZip({{"joints.npy", bad}}));
  try {
    ReadNpz(dir / "bad.npz");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.site().file, (dir / "bad.npz").string());
    EXPECT_EQ(e.site().field, "joints");
    EXPECT_THAT(std::string(e.what()), HasSubstr("Fortran"));
  }
  WriteFile(dir / "junk.npz", "this is not a zip archive at all");
  EXPECT_THROW(ReadNpz(dir / "junk.npz"), Error);
  EXPECT_THROW(ReadNpz(dir / "absent.npz"), Error);
}

TEST(NpzTest, EmptyArchiveRoundTrips) {
  TempDir dir;
  WriteNpz(dir / "e.npz", {});
  EXPECT_TRUE(ReadNpz(dir / "e.npz").empty());
}

TEST(NpyTest, CheckHelpersNameFieldAndShape) {
  const NpyArray a = MakeArray<double>({2, 21, 3}, std::vector<double>(126, 0));
  EXPECT_NO_THROW(CheckShape(a, {-1, 21, 3}, "hands.npz", "left_joints"));
  try {
    CheckShape(a, {2, 16, 3}, "hands.npz", "left_joints");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.site().field, "left_joints");
    EXPECT_THAT(std::string(e.what()), HasSubstr("(2, 21, 3), expected (2, 16, 3)"));
  }
  EXPECT_THROW(CheckInteger(a, "f", "k"), Error);
  EXPECT_NO_THROW(CheckFloat(a, "f", "k"));
}

}  // namespace
}  // namespace doasido::recon
