#include "server/refusal_pacer.h"

#include <gtest/gtest.h>

namespace endorecon::server {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

AuditEntry Refusal(const std::string& peer, const std::string& method = "List") {
  return {"-", "-", "", method, "", "UNAUTHENTICATED", peer, "", ""};
}

// A wrong token in a loop wrote a line per call: 308 kB in 1.5 s (found 2026-12-07). Past a burst,
// refusals alike are held back for the window, and the lines with their held_back count every one.
TEST(RefusalPacerTest, AFloodIsHeldBackAndEveryRefusalCounted) {
  RefusalPacer pacer(seconds(10), 5);
  const auto start = RefusalPacer::Clock::now();
  long long lines = 0, counted = 0;
  // 2,000 refusals in 15 s, each from a connection of its own (the port differs).
  for (int i = 0; i < 2000; ++i) {
    AuditEntry entry = Refusal("ipv4:10.1.2.3:" + std::to_string(40000 + i));
    if (pacer.Pass(entry, start + milliseconds(i * 15 / 2))) {
      ++lines;
      counted += 1 + entry.held_back;
    }
  }
  EXPECT_EQ(lines, 10) << "5 a window";
  EXPECT_TRUE(pacer.TakeDue(start + seconds(16)).empty()) << "the second window is not over";
  const auto due = pacer.TakeDue(start + seconds(21));
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].method, "List");
  counted += 1 + due[0].held_back;
  EXPECT_EQ(counted, 2000);
  EXPECT_TRUE(pacer.TakeDue(start + seconds(40)).empty()) << "nothing held back";
  // Forgotten after a quiet window: the next refusals have their lines at once.
  AuditEntry later = Refusal("ipv4:10.1.2.3:1");
  EXPECT_TRUE(pacer.Pass(later, start + seconds(50)));
  EXPECT_EQ(later.held_back, 0);
}

TEST(RefusalPacerTest, AFewRefusalsEachHaveALine) {
  RefusalPacer pacer(seconds(10), 5);
  const auto now = RefusalPacer::Clock::now();
  for (int i = 0; i < 5; ++i) {
    AuditEntry entry = Refusal("ipv4:127.0.0.1:" + std::to_string(i));
    EXPECT_TRUE(pacer.Pass(entry, now + milliseconds(i)));
  }
  EXPECT_TRUE(pacer.TakeDue(now + seconds(11)).empty());
}

TEST(RefusalPacerTest, OtherAddressesMethodsAndPrincipalsAreKindsOfTheirOwn) {
  RefusalPacer pacer(seconds(10), 1);
  const auto now = RefusalPacer::Clock::now();
  AuditEntry first = Refusal("ipv4:10.1.2.3:1");
  AuditEntry other_address = Refusal("ipv4:10.1.2.4:1");
  AuditEntry other_method = Refusal("ipv4:10.1.2.3:2", "Submit");
  AuditEntry known = Refusal("ipv4:10.1.2.3:3");
  known.principal = "alice";
  AuditEntry again = Refusal("ipv4:10.1.2.3:4");
  EXPECT_TRUE(pacer.Pass(first, now));
  EXPECT_TRUE(pacer.Pass(other_address, now));
  EXPECT_TRUE(pacer.Pass(other_method, now));
  EXPECT_TRUE(pacer.Pass(known, now));
  EXPECT_FALSE(pacer.Pass(again, now + milliseconds(10)));
  // At shutdown everything held back is written, whatever its age.
  const auto due = pacer.TakeDue(now + std::chrono::hours(1));
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0].peer, "ipv4:10.1.2.3:4");
  EXPECT_EQ(due[0].held_back, 0);
}

}  // namespace
}  // namespace endorecon::server
