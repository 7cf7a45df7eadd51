// The CLI's global options (--server, --json, --timeout, and any added later) work after the
// subcommand too, as git, docker and kubectl users type them: `endorecon submit clip --json`.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <csignal>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(CliGlobalOptionsTest, ServerAndTimeoutAfterTheSubcommand) {
  // An address nobody listens on: the call fails as unreachable (4), not as bad usage (2).
  const auto result =
      RunCliAsTyped({"list", "--server", "127.0.0.1:" + std::to_string(FreePort()), "--timeout", "1"});
  EXPECT_EQ(result.exit_code, 4) << result.err;
}

TEST(CliGlobalOptionsTest, JsonAfterTheSubcommand) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  const auto submitted =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "5", "--json"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  const auto job = nlohmann::json::parse(submitted.out);
  ASSERT_TRUE(job.contains("id")) << submitted.out;
  const auto status = RunCli(cluster.address(), {"status", job["id"].get<std::string>(), "--json"});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_EQ(nlohmann::json::parse(status.out)["id"], job["id"]);
  // Every field, zeros too: a script read job["priority"] and met a missing key when it was 0.
  const auto fields = nlohmann::json::parse(status.out);
  EXPECT_EQ(fields.value("priority", -1), 0) << status.out;
  EXPECT_EQ(fields.value("attempts", -1), 0) << status.out;
  // More jobs than --limit: said on stderr, and the JSON has the next page's token.
  ASSERT_EQ(
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "5"}).exit_code, 0);
  const auto one = RunCli(cluster.address(), {"--json", "list", "--limit", "1"});
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_NE(one.err.find("1 job(s) are listed and there are more: --limit N lists more, --page-token "),
            std::string::npos)
      << one.err;
  // The token is the listed job's id, not its place in the server's one sequence of jobs, which told
  // a tenant how many jobs every tenant had submitted (found 2026-12-06).
  const auto first_page = nlohmann::json::parse(one.out);
  ASSERT_EQ(first_page["jobs"].size(), 1u) << one.out;
  EXPECT_EQ(first_page.value("next_page_token", ""), first_page["jobs"][0].value("id", "")) << one.out;
  // A script goes on from there with --page-token (the token was offered and could not be used).
  const auto rest =
      RunCli(cluster.address(), {"--json", "list", "--page-token", first_page["next_page_token"]});
  ASSERT_EQ(rest.exit_code, 0) << rest.err;
  const auto second_page = nlohmann::json::parse(rest.out);
  ASSERT_EQ(second_page["jobs"].size(), 1u) << rest.out;
  EXPECT_NE(second_page["jobs"][0]["id"], first_page["jobs"][0]["id"]);
  EXPECT_EQ(second_page.value("next_page_token", ""), "");
  EXPECT_EQ(RunCli(cluster.address(), {"list", "--limit", "2"}).err.find("there are more"),
            std::string::npos);
}

// What a script needs of the CLI's ends: output that did not arrive is an error (`list --json >
// jobs.json` on a full disk exited 0 with the file cut short), and SIGTERM, which job runners send,
// ends a watch as Ctrl-C does, saying the job goes on (it killed the CLI without a word; found
// 2026-12-06).
TEST(CliGlobalOptionsTest, AnOutputNotWrittenIsAnErrorAndSigtermEndsAWatchSayingSo) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  const std::string id = cluster.Submit(cluster.path("clip"), {"--iterations", "100000"});
  const std::string err = cluster.path("err.txt").string();
  const int status = std::system((BuiltBinary("client/endorecon") + " --server " + cluster.address() +
                                  " --json list > /dev/full 2> " + err)
                                     .c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 8);
  EXPECT_NE(ReadBytes(err).find("cannot write the output to stdout (No space left on device)"),
            std::string::npos)
      << ReadBytes(err);

  Process watch({BuiltBinary("client/endorecon"), "--server", cluster.address(), "watch", id},
                cluster.path("watch.log"));
  ASSERT_TRUE(WaitUntil([&] { return watch.Log().find("QUEUED") != std::string::npos; })) << watch.Log();
  watch.Signal(SIGTERM);
  EXPECT_EQ(watch.Wait(), 143);
  EXPECT_NE(watch.Log().find("stopped watching; job " + id), std::string::npos) << watch.Log();
  EXPECT_EQ(cluster.Job(id).state(), v1::QUEUED) << "the job goes on";
}

TEST(CliGlobalOptionsTest, UnknownOptionsAreStillRefused) {
  const auto result = RunCliAsTyped({"list", "--no-such-option"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--no-such-option"), std::string::npos) << result.err;
  const auto extra = RunCliAsTyped({"status", "abc", "def"});
  EXPECT_EQ(extra.exit_code, 2) << "a second job id is not taken";
  // A mistyped command is named (it was "A subcommand is required").
  const auto typo = RunCliAsTyped({"--timeout", "3", "statuss", "abc"});
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("unknown command 'statuss' (did you mean 'status'?); the commands of endorecon: "
                          "submit, status, watch, list"),
            std::string::npos)
      << typo.err;
  // A mistyped option too, after the command, its value not taken for the clip.
  const auto option = RunCliAsTyped({"submit", "clip", "--time-budjet", "15"});
  EXPECT_EQ(option.exit_code, 2);
  EXPECT_NE(option.err.find("endorecon: unknown option --time-budjet of 'submit' (did you mean "
                            "--time-budget?); endorecon submit --help lists them"),
            std::string::npos)
      << option.err;
  // The three binaries of one build print one version: the project's, with the source's commit
  // when built from a git checkout (as the tests are), which `endorecon workers` shows too.
  const auto version = RunCliAsTyped({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.out.rfind("0.1.0", 0), 0u) << version.out;
  EXPECT_EQ(Capture(BuiltBinary("server/endorecon-server") + " --version"), version.out);
  EXPECT_EQ(Capture(BuiltBinary("worker/runtime/endorecon-worker") + " --version"), version.out);
}

}  // namespace
}  // namespace endorecon::testing
