#include "common/npy.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>

#include "common/error.h"
#include "common/json_file.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;

// Builds .npy bytes by hand: magic, version, little-endian header length, header, data.
std::string NpyBytes(int major, const std::string& header, const std::string& data) {
  std::string bytes = "\x93NUMPY";
  bytes += static_cast<char>(major);
  bytes += '\0';
  const std::size_t length_bytes = major == 1 ? 2 : 4;
  for (std::size_t i = 0; i < length_bytes; ++i)
    bytes += static_cast<char>((header.size() >> (8 * i)) & 0xff);
  return bytes + header + data;
}

template <typename T>
std::string Raw(std::initializer_list<T> values) {
  std::string out(values.size() * sizeof(T), '\0');
  std::memcpy(out.data(), values.begin(), out.size());
  return out;
}

std::string ErrorOf(const std::filesystem::path& path) {
  try {
    ReadNpy(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  ADD_FAILURE() << "no error for " << path;
  return "";
}

TEST(NpyTest, RoundTripFloat32) {
  TempDir dir("npy");
  const std::vector<float> values = {0.f, 1.5f, -2.25f, 1e-20f, 3e30f, 7.f};
  WriteNpyFloat32(dir / "a.npy", values.data(), {2, 3});
  const std::string bytes = ReadBytes(dir / "a.npy");
  EXPECT_EQ((bytes.size() - values.size() * 4) % 64, 0u);
  EXPECT_EQ(bytes[6], 1);
  EXPECT_EQ(bytes[bytes.size() - values.size() * 4 - 1], '\n');

  const NpyArray array = ReadNpy(dir / "a.npy");
  EXPECT_EQ(array.shape, (std::vector<std::size_t>{2, 3}));
  EXPECT_EQ(array.dtype, "<f4");
  ASSERT_EQ(array.size(), values.size());
  for (std::size_t i = 0; i < values.size(); ++i) EXPECT_EQ(array.data[i], values[i]);
}

TEST(NpyTest, RoundTripOneAndZeroDimensions) {
  TempDir dir("npy");
  const float values[] = {4.f, 5.f, 6.f};
  WriteNpyFloat32(dir / "v.npy", values, {3});
  EXPECT_EQ(ReadNpy(dir / "v.npy").shape, (std::vector<std::size_t>{3}));
  WriteNpyFloat32(dir / "s.npy", values, {});
  const NpyArray scalar = ReadNpy(dir / "s.npy");
  EXPECT_TRUE(scalar.shape.empty());
  ASSERT_EQ(scalar.size(), 1u);
  EXPECT_EQ(scalar.data[0], 4.0);
  WriteNpyFloat32(dir / "e.npy", values, {0, 5});
  EXPECT_EQ(ReadNpy(dir / "e.npy").size(), 0u);
}

TEST(NpyTest, ReadsVersions2And3AndUint8) {
  TempDir dir("npy");
  WriteBytes(dir / "v2.npy", NpyBytes(2, "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }\n",
                                      Raw<double>({1.25, -3.5})));
  const NpyArray v2 = ReadNpy(dir / "v2.npy");
  EXPECT_EQ(v2.data, (std::vector<double>{1.25, -3.5}));
  WriteBytes(dir / "v3.npy",
             NpyBytes(3, "{\"descr\": \"|u1\", \"fortran_order\": False, \"shape\": (1, 3)}\n",
                      std::string("\x00\x11\xff", 3)));
  const NpyArray v3 = ReadNpy(dir / "v3.npy");
  EXPECT_EQ(v3.shape, (std::vector<std::size_t>{1, 3}));
  EXPECT_EQ(v3.data, (std::vector<double>{0, 17, 255}));
}

// A pipe named like a pose file is refused, not read for ever (found 2026-12-05); so is it as a
// JSON side file.
TEST(NpyTest, APipeIsRefusedNotWaitedOn) {
  testing::TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "poses_bounds.npy").c_str(), 0600), 0);
  try {
    ReadNpy(dir / "poses_bounds.npy");
    ADD_FAILURE() << "a pipe was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("poses_bounds.npy: a named pipe (FIFO), not a file"),
              std::string::npos)
        << e.what();
  }
  ASSERT_EQ(::mkfifo((dir / "transforms.json").c_str(), 0600), 0);
  EXPECT_THROW(ReadJsonFile(dir / "transforms.json"), Error);
}

TEST(NpyTest, RejectsBadForms) {
  TempDir dir("npy");
  const std::string f8_2 = Raw<double>({1.0, 2.0});
  struct Case {
    std::string name, bytes, expected;
  };
  const std::vector<Case> cases = {
      {"magic.npy", "\x93NUMPZ\x01\x00" + std::string(8, ' '), "not a .npy file"},
      {"empty.npy", "", "not a .npy file"},
      {"version.npy", NpyBytes(4, "{}", ""), "version 4.0 is not supported"},
      {"fortran.npy", NpyBytes(1, "{'descr': '<f8', 'fortran_order': True, 'shape': (2,), }", f8_2),
       "fortran_order is True"},
      {"big.npy", NpyBytes(1, "{'descr': '>f8', 'fortran_order': False, 'shape': (2,), }", f8_2),
       "'>f8' is not supported (big-endian"},
      {"int.npy", NpyBytes(1, "{'descr': '<i4', 'fortran_order': False, 'shape': (2,), }", f8_2),
       "dtype '<i4' is not supported"},
      {"short.npy", NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }", f8_2),
       "needs 24 data bytes, the file has 16 (truncated)"},
      {"long.npy", NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (1,), }", f8_2),
       "(trailing bytes)"},
      {"header.npy", NpyBytes(1, "{'descr': '<f8', 'fortran_order': Maybe, 'shape': (2,), }", f8_2),
       "expected True or False"},
      {"key.npy", NpyBytes(1, "{'descr': '<f8', 'colour': 'red', 'shape': (2,), }", f8_2),
       "unexpected key 'colour'"},
      {"missing.npy", NpyBytes(1, "{'descr': '<f8', 'shape': (2,), }", f8_2), "missing"},
      {"cut.npy", NpyBytes(1, "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }", "").substr(0, 30),
       "truncated .npy header"},
  };
  for (const Case& c : cases) {
    WriteBytes(dir / c.name, c.bytes);
    const std::string message = ErrorOf(dir / c.name);
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.name << ": " << message;
    EXPECT_NE(message.find(c.name), std::string::npos) << message;
  }
  EXPECT_NE(ErrorOf(dir / "absent.npy").find("cannot open"), std::string::npos);
}

struct PoseFixture {
  const char* scene;
  std::size_t rows;
};

class NpyFixtureTest : public ::testing::TestWithParam<PoseFixture> {};

TEST_P(NpyFixtureTest, ReadsEndoNerfPoseFile) {
  const std::filesystem::path path = std::filesystem::path(ENDORECON_SHARED_DIR) / "data/endonerf_poses" /
                                     GetParam().scene / "poses_bounds.npy";
  const NpyArray array = ReadNpy(path);
  EXPECT_EQ(array.dtype, "<f8");
  ASSERT_EQ(array.shape, (std::vector<std::size_t>{GetParam().rows, 17}));
  for (std::size_t row = 0; row < GetParam().rows; ++row) {
    const double* r = &array.data[row * 17];
    EXPECT_EQ(r[4], 512.0);             // H
    EXPECT_EQ(r[9], 640.0);             // W
    EXPECT_NEAR(r[14], 569.468, 1e-3);  // f
    EXPECT_EQ(r[0], 1.0);
    EXPECT_EQ(r[6], 1.0);
    EXPECT_EQ(r[12], 1.0);
    EXPECT_LT(r[15], r[16]);  // near < far
  }
}

INSTANTIATE_TEST_SUITE_P(EndoNerf, NpyFixtureTest,
                         ::testing::Values(PoseFixture{"pulling_soft_tissues", 63},
                                           PoseFixture{"cutting_tissues_twice", 156}));

}  // namespace
}  // namespace endorecon
