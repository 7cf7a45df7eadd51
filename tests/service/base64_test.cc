#include "common/base64.h"

#include <gtest/gtest.h>

#include <string>

namespace endorecon {
namespace {

TEST(Base64Test, Rfc4648Vectors) {
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
}

TEST(Base64Test, BinaryBytesAndLongInputsHaveNoLineBreaks) {
  EXPECT_EQ(Base64(std::string("\0\xff\xfe", 3)), "AP/+");
  const std::string encoded = Base64(std::string(3000, 'x'));
  EXPECT_EQ(encoded.size(), 4000u);
  EXPECT_EQ(encoded.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace endorecon
