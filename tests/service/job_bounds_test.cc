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
  EXPECT_NE(testing::ErrorFrom([] { ValidateJobName("   "); }).find("name is only spaces"),
            std::string::npos);
  EXPECT_NO_THROW(ValidateJobName(""));  // none: the clip's
  EXPECT_NO_THROW(ValidateWorkerId("node7-gpu0"));
  EXPECT_NE(testing::ErrorFrom([] { ValidateWorkerId(""); }).find("worker id is empty"), std::string::npos);
  EXPECT_NE(testing::ErrorFrom([] { ValidateWorkerId("w\x1b[2J"); }).find("worker id holds a control character"),
            std::string::npos);
  // Unicode's direction controls turn a terminal's line around ("x\u202eevil" shows as "xlive"), and
  // C1 controls are escapes to some terminals (found 2026-12-06); other text past ASCII is a name.
  for (const char* turning : {"x\xe2\x80\xae"
                              "evil",
                              "a\xe2\x81\xa6"
                              "b",
                              "a\xe2\x80\x8f"
                              "b",
                              "a\xc2\x9b"
                              "2J",
                              "a\xd8\x9c"
                              "b",
                              "a\xe2\x80\xa8"
                              "b",
                              "a\xef\xbb\xbf"
                              "b"}) {
    EXPECT_NE(
        testing::ErrorFrom([&] { ValidateJobName(turning); }).find("name holds a Unicode control character"),
        std::string::npos)
        << turning;
  }
  EXPECT_NO_THROW(
      ValidateJobName("\xe2\x80\x94 caf\xc3\xa9 \xe2\x80\x9c"
                      "quoted\xe2\x80\x9d \xc2\xa9"));
}

// What the server passes on from a worker (a failure's reason): shown as it is, less what a terminal
// would act on (a worker's reason "boom\x1b]0;PWNED\x07\nFAKE: job SUCCEEDED" was printed as it came).
TEST(JobBoundsTest, AWorkersTextIsMadePrintable) {
  EXPECT_EQ(PrintableText("boom\x1b]0;PWNED\x07\nFAKE", 100), "boom?]0;PWNED??FAKE");
  EXPECT_EQ(PrintableText("x\xe2\x80\xae"
                          "evil \xe2\x80\x94 ok",
                          100),
            "x?evil \xe2\x80\x94 ok");
  EXPECT_EQ(PrintableText("abc\xc3\xa9", 4), "abc");
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

// What a command prints of an error keeps its line breaks and nothing else a terminal would act on.
TEST(JobBoundsTest, PrintableLinesKeepTheLineBreaksAlone) {
  EXPECT_EQ(PrintableLines("no job 'a\x1b[2Jb'\nendorecon: try again"),
            "no job 'a?[2Jb'\nendorecon: try again");
  EXPECT_EQ(PrintableLines("ends with a break\n"), "ends with a break\n");
  EXPECT_EQ(PrintableLines("tab\there \xc3\xa9"), "tab?here \xc3\xa9");
  EXPECT_EQ(PrintableLines(""), "");
}

}  // namespace
}  // namespace endorecon
