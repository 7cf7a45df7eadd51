// common/job_bounds: what a client may name in a submit and a worker in its registration.
#include "common/job_bounds.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"
#include "common/safe_path.h"
#include "tests/unit/clip_fixture.h"

namespace endorecon {
namespace {

TEST(JobBoundsTest, NamesAndWorkerIdsArePrintableAndBounded) {
  EXPECT_NO_THROW(ValidateJobName("liver, 2026-12-05"));
  EXPECT_NE(testing::ErrorFrom([] { ValidateJobName("a\nb"); }).find("name holds a control character (byte 10)"),
            std::string::npos);
  EXPECT_NE(testing::ErrorFrom([] { ValidateJobName(std::string(300, 'n')); }).find("name has 300 bytes; at most 256"),
            std::string::npos);
  EXPECT_NO_THROW(ValidateWorkerId("node7-gpu0"));
  EXPECT_NE(testing::ErrorFrom([] { ValidateWorkerId(""); }).find("worker id is empty"), std::string::npos);
  EXPECT_NE(testing::ErrorFrom([] { ValidateWorkerId("w\x1b[2J"); }).find("worker id holds a control character"),
            std::string::npos);
}

// A clip folder's name becomes the job's when none is given: made valid, not refused after the upload
// (a newline in a folder's name was; found 2026-12-05).
TEST(JobBoundsTest, AFoldersNameIsMadeAValidJobName) {
  EXPECT_EQ(ValidJobName("clip\nday 2"), "clip?day 2");
  EXPECT_EQ(ValidJobName("caf\xc3\xa9"), "caf\xc3\xa9");
  EXPECT_EQ(ValidJobName("bad\xff\xc3\xa9"), "bad???") << "no UTF-8 text: every byte past ASCII";
  const std::string long_name = std::string(255, 'a') + "\xc3\xa9" + "b";  // the 256th byte starts a character
  const std::string made = ValidJobName(long_name);
  EXPECT_EQ(made, std::string(255, 'a'));
  EXPECT_TRUE(IsUtf8(made));
  EXPECT_NO_THROW(ValidateJobName(ValidJobName(std::string(1000, '\t'))));
}

}  // namespace
}  // namespace endorecon
