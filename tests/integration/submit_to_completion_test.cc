// A clip goes in through the CLI, a worker reconstructs it, the results come back verified.
#include <fcntl.h>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common/json_file.h"
#include "common/sha256.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(SubmitToCompletionTest, ClipInResultsOut) {
  Cluster cluster;
  cluster.StartWorker("w1");
  MakeClip(cluster.path("clip"));
  const auto submitted =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "30", "--wait",
                                 "--previews", cluster.path("previews").string()});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err << submitted.out << cluster.ServerLog();
  EXPECT_NE(submitted.out.find("SUCCEEDED"), std::string::npos) << submitted.out;
  // Previews were saved, or the watch says none arrived (it left nothing and said nothing).
  const bool saved = std::filesystem::exists(cluster.path("previews")) &&
                     !std::filesystem::is_empty(cluster.path("previews"));
  EXPECT_NE(saved, submitted.err.find("no preview arrived while watching") != std::string::npos)
      << submitted.err;
  // Renders of the patient's frames are the user's alone, as fetched results are (they followed the
  // umask; found 2026-12-07).
  if (saved) {
    EXPECT_EQ(std::filesystem::status(cluster.path("previews")).permissions() & std::filesystem::perms::all,
              std::filesystem::perms::owner_all);
    for (const auto& file : std::filesystem::directory_iterator(cluster.path("previews")))
      EXPECT_EQ(file.status().permissions() & std::filesystem::perms::all,
                std::filesystem::perms::owner_read | std::filesystem::perms::owner_write)
          << file.path();
  }
  // An id of another shape is answered with what an id looks like.
  const auto short_id = RunCli(cluster.address(), {"status", "F15961"});
  EXPECT_EQ(short_id.exit_code, 3) << short_id.err;
  EXPECT_NE(short_id.err.find("a job id is 12 lower-case hexadecimal digits"), std::string::npos)
      << short_id.err;

  const auto listed = RunCli(cluster.address(), {"--json", "list"});
  ASSERT_EQ(listed.exit_code, 0);
  const auto id = listed.out.substr(listed.out.find("\"id\":\"") + 6, 12);
  const auto job = cluster.Job(id);
  EXPECT_EQ(job.state(), v1::SUCCEEDED);
  EXPECT_EQ(job.worker_id(), "w1");
  EXPECT_EQ(job.options().iterations(), 30);
  ASSERT_GT(job.result().files_size(), 0);
  // A finished job's row shows the iterations it trained (30), not its evaluation's last frame
  // ("eval 8/8" read as iterations; found 2026-12-05).
  const auto table = RunCli(cluster.address(), {"list"});
  EXPECT_NE(table.out.find(fmt::format("{:>12} ", 30)), std::string::npos) << table.out;
  EXPECT_EQ(table.out.find("eval "), std::string::npos) << table.out;

  const auto fetched = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("results").string()});
  ASSERT_EQ(fetched.exit_code, 0) << fetched.err;
  EXPECT_NE(fetched.out.find("report: " + (cluster.path("results") / "report.html").string()),
            std::string::npos)
      << fetched.out;
  // The report is titled by the job's name (its clip folder on the worker is "clip" whatever it was).
  EXPECT_EQ(ReadJsonFile(cluster.path("results") / "config.json").value("title", ""), job.name());
  bool has_metrics = false;
  for (const auto& file : job.result().files()) {
    const auto local = cluster.path("results") / file.path();
    ASSERT_TRUE(std::filesystem::exists(local)) << file.path();
    EXPECT_EQ(Sha256File(local), file.sha256()) << file.path();
    // The user's alone, whatever the umask: results hold patient data (they were 0644; found
    // 2026-12-06).
    const auto group_or_others = std::filesystem::perms::group_all | std::filesystem::perms::others_all;
    EXPECT_EQ(std::filesystem::status(local).permissions() & group_or_others, std::filesystem::perms::none)
        << file.path();
    EXPECT_EQ(std::filesystem::status(local.parent_path()).permissions() & group_or_others,
              std::filesystem::perms::none)
        << file.path();
    has_metrics = has_metrics || file.path() == "metrics.json";
  }
  EXPECT_TRUE(has_metrics);
  // Its size is the results' as `status` says it, though identical files came once (it said the
  // bytes received, fewer).
  const std::string described = RunCli(cluster.address(), {"status", id}).out;
  const std::string results = fmt::format("  results   {} file(s), ", job.result().files_size());
  ASSERT_NE(described.find(results), std::string::npos) << described;
  const std::size_t from = described.find(results) + results.size();
  const std::string size = described.substr(from, described.find(" (", from) - from);
  EXPECT_NE(fetched.out.find(fmt::format("fetched {0} of {0} file(s) ({1}", job.result().files_size(), size)),
            std::string::npos)
      << fetched.out << " / " << described;

  // A second fetch finds everything in place and sends nothing.
  const auto again = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("results").string()});
  EXPECT_EQ(again.exit_code, 0);
  EXPECT_NE(again.out.find(fmt::format("all {} file(s) are in {} already; every file verified",
                                       job.result().files_size(), cluster.path("results").string())),
            std::string::npos)
      << again.out;
  // With --json, what the text says (it printed the manifest alone).
  const auto json =
      RunCli(cluster.address(), {"--json", "fetch", id, "-o", cluster.path("results").string()});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const auto fetch = nlohmann::json::parse(json.out);
  EXPECT_EQ(fetch["job"], id);
  EXPECT_EQ(fetch["report"], (cluster.path("results") / "report.html").string());
  EXPECT_EQ(fetch["fetched_files"], 0);
  EXPECT_EQ(fetch["files"], job.result().files_size());
  EXPECT_EQ(fetch["result"]["files"].size(), static_cast<std::size_t>(job.result().files_size()));
  // A folder of someone's files is refused, nothing written into it (found 2026-12-05); one holding
  // a download in progress (a .part) is a resume.
  std::filesystem::create_directories(cluster.path("documents"));
  std::filesystem::create_directories(cluster.path("resumed"));
  WriteBytes(cluster.path("documents") / "letter.txt", "dear");
  const auto mixed = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("documents").string()});
  EXPECT_EQ(mixed.exit_code, 2) << mixed.err;
  // The one other file named alone: ", ..." followed it however many there were (found 2026-12-07).
  EXPECT_NE(mixed.err.find("holds other files (letter.txt) than this job's results"), std::string::npos)
      << mixed.err;
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(cluster.path("documents")),
                          std::filesystem::directory_iterator()),
            1);
  WriteBytes(cluster.path("resumed") / "metrics.json.part", "{");
  EXPECT_EQ(RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("resumed").string()}).exit_code, 0);
  EXPECT_EQ(ReadBytes(cluster.path("resumed") / ".endorecon-job"), id + "\n") << "the folder names its job";
  // Another job's results are refused: by the job its folder names, and, in a folder without that
  // name, by a file this job's results do not have (a longer clip's frame), however deep.
  std::filesystem::copy(cluster.path("resumed"), cluster.path("other"),
                        std::filesystem::copy_options::recursive);
  WriteBytes(cluster.path("other") / ".endorecon-job", "0123456789ab\n");
  const auto other = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("other").string()});
  EXPECT_EQ(other.exit_code, 2) << other.err;
  EXPECT_NE(other.err.find("holds the results of job 0123456789ab"), std::string::npos) << other.err;
  std::filesystem::remove(cluster.path("other") / ".endorecon-job");
  WriteBytes(cluster.path("other") / "rgb" / "000999.png", "a longer clip's frame");
  const auto longer = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("other").string()});
  EXPECT_EQ(longer.exit_code, 2) << longer.err;
  EXPECT_NE(longer.err.find("holds other files (rgb/000999.png)"), std::string::npos) << longer.err;
  WriteBytes(cluster.path("other") / "rgb" / "001000.png", "and another");
  EXPECT_NE(RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("other").string()}).err.find(", ...)"),
            std::string::npos);
  // A second fetch into a folder one is writing into is refused (four at once failed as checksum
  // mismatches).
  {
    const int held = ::open((cluster.path("resumed") / ".endorecon-job").c_str(), O_RDWR);
    ASSERT_GE(held, 0);
    ASSERT_EQ(::flock(held, LOCK_EX), 0);
    const auto busy = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("resumed").string()});
    EXPECT_EQ(busy.exit_code, 7) << busy.err;
    EXPECT_NE(busy.err.find("another endorecon fetch is writing into"), std::string::npos) << busy.err;
    ::close(held);
  }

  // A result file gone from the server's store (deleted under it) is named with its job, not by a
  // bare digest.
  const auto& lost = job.result().files(0).sha256();
  std::filesystem::remove(cluster.data_dir() / "blobs" / lost.substr(0, 2) / lost);
  const auto missing = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("elsewhere").string()});
  EXPECT_EQ(missing.exit_code, 3) << missing.err;
  EXPECT_NE(missing.err.find("job " + id + ": a result file is missing from the server's store"),
            std::string::npos)
      << missing.err;

  // The same clip again: nothing is uploaded twice.
  const auto resubmitted =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "30"});
  EXPECT_EQ(resubmitted.exit_code, 0);
  EXPECT_NE(resubmitted.err.find(": 0 B sent"), std::string::npos) << resubmitted.err;

  const auto status = RunCli(cluster.address(), {"status", id});
  EXPECT_EQ(status.exit_code, 0);
  EXPECT_NE(status.out.find("SUCCEEDED"), std::string::npos);
  EXPECT_EQ(RunCli(cluster.address(), {"status", "doesnotexist"}).exit_code, 3);
}

// A content the clip holds under several names goes up once: the server keeps one blob a content,
// and 3,000 hard links of one frame went up as 7.1 GB (found 2026-12-06). The worker downloads it
// once too and copies it to the other names (the run needs every frame).
TEST(SubmitToCompletionTest, AContentUnderSeveralNamesIsSentOnce) {
  Cluster cluster;
  cluster.StartWorker("w1");
  const auto clip = cluster.path("clip");
  MakeClip(clip);
  std::string payload(8 << 20, '\0');
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<char>((i * 2654435761u) >> 13);
  AddPngPayload(clip / "images" / "000000.png", payload);
  for (const char* copy : {"000001.png", "000002.png", "000003.png"}) {
    std::filesystem::copy_file(clip / "images" / "000000.png", clip / "images" / copy,
                               std::filesystem::copy_options::overwrite_existing);
  }
  const auto submitted = RunCli(cluster.address(), {"submit", clip.string(), "--iterations", "5", "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err << submitted.out << cluster.ServerLog();
  // One 8.4 MB frame and the clip's few kB, not four of them.
  EXPECT_NE(submitted.err.find("file(s): 8.4 MB sent"), std::string::npos) << submitted.err;
  EXPECT_NE(submitted.out.find("SUCCEEDED"), std::string::npos) << submitted.out;
}

// --frames picks a clip folder's frames through the service, as `reconstruct --frames` does (a
// long clip was cut by hand, slicing poses_bounds.npy; found 2026-12-06): the picked frames go up
// alone, as a clip cut to them, and the job, its status and its config.json say which. Picking none is
// refused before the upload. A cut's temporary folder a killed CLI left is removed by the next.
TEST(SubmitToCompletionTest, FramesPicksAClipFoldersFrames) {
  Cluster cluster;
  const auto clip = cluster.path("clip");
  MakeClip(clip);  // 8 frames
  const auto none =
      RunCli(cluster.address(), {"submit", clip.string(), "--frames", "8:", "--iterations", "5"});
  EXPECT_EQ(none.exit_code, 2) << none.err;
  EXPECT_NE(none.err.find("--frames 8::1 picks none of " + clip.string() + "'s 8 frames"), std::string::npos)
      << none.err;
  EXPECT_NE(none.err.find("nothing was sent"), std::string::npos) << none.err;
  // A damaged picked frame is named where the user has it (not by its link in the cut clip); a damaged
  // frame not picked is not sent, nor checked.
  const std::string frame = ReadBytes(clip / "images" / "000005.png");
  WriteBytes(clip / "images" / "000005.png", "not a png");
  const auto damaged = RunCli(cluster.address(), {"submit", clip.string(), "--frames", "2:8:3"});
  EXPECT_EQ(damaged.exit_code, 2) << damaged.err;
  EXPECT_NE(damaged.err.find((clip / "images" / "000005.png").string()), std::string::npos) << damaged.err;
  EXPECT_EQ(damaged.err.find("endorecon-clip-"), std::string::npos) << damaged.err;
  WriteBytes(clip / "images" / "000005.png", frame);
  WriteBytes(clip / "images" / "000004.png", "not a png");

  // A cut folder a killed CLI left (its process is gone): removed by the next cut.
  Process gone({"/bin/true"}, cluster.path("true.log"));
  gone.Wait();
  const auto left =
      std::filesystem::temp_directory_path() / ("endorecon-clip-" + std::to_string(gone.pid()) + "-1");
  std::filesystem::create_directories(left / "images");

  cluster.StartWorker("w1");
  const auto submitted = RunCli(cluster.address(), {"--json", "submit", clip.string(), "--frames", "2:8:3",
                                                    "--iterations", "5", "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err << submitted.out << cluster.ServerLog();
  EXPECT_NE(submitted.err.find("uploading frames 2:8:3 of " + clip.string() + ": 2 of its 8 frames"),
            std::string::npos)
      << submitted.err;
  // What stays here is named as without --frames (it went unsaid with them).
  EXPECT_NE(submitted.err.find("left out 1 file(s) under " + clip.string() +
                               " that the clip's layout does not name (docs/formats.md), not uploaded: "
                               "synth.json"),
            std::string::npos)
      << submitted.err;
  const auto id = submitted.out.substr(submitted.out.find("\"id\":\"") + 6, 12);
  EXPECT_FALSE(std::filesystem::exists(left));
  const v1::Job job = cluster.Job(id);
  EXPECT_EQ(job.name(), "clip");
  EXPECT_EQ(job.recording().frames(), "2:8:3");
  EXPECT_NE(RunCli(cluster.address(), {"status", id}).out.find("(frames 2:8:3)"), std::string::npos);
  // Frames 2 and 5: their image, depth map, mask and gt/ image and depth, and the cut poses_bounds.npy.
  EXPECT_EQ(job.clip().files_size(), 11);
  const auto fetched = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("results").string()});
  ASSERT_EQ(fetched.exit_code, 0) << fetched.err;
  EXPECT_EQ(ReadJsonFile(cluster.path("results") / "config.json").value("frames", ""), "2:8:3");
  int frames = 0;
  for (const auto& entry : std::filesystem::directory_iterator(cluster.path("results") / "rgb")) {
    frames += entry.path().extension() == ".png";
  }
  EXPECT_EQ(frames, 2) << "frames 2 and 5";
}

TEST(SubmitToCompletionTest, UnreachableServerExitsWithFour) {
  const auto result = RunCli("127.0.0.1:" + std::to_string(FreePort()), {"--timeout", "1", "list"});
  EXPECT_EQ(result.exit_code, 4) << result.err;
}

// A server address with no port, or one past 65535, is refused as the usage error it is, by the CLI
// and by a worker: gRPC took 127.0.0.1:99999 as port 34463 and "localhost" as port 443, and the
// worker retried there for good (found 2026-12-05).
TEST(SubmitToCompletionTest, AServerAddressWithoutAPortOrPastTheLastIsRefused) {
  for (const std::string address : {"127.0.0.1:99999", "localhost", "127.0.0.1:049531"}) {
    const auto result = RunCli(address, {"list"});
    EXPECT_EQ(result.exit_code, 2) << result.err;
    EXPECT_NE(result.err.find(address), std::string::npos) << result.err;
  }
  // 049531 is in the range: the digits' count is what is wrong, and is said.
  EXPECT_NE(RunCli("127.0.0.1:049531", {"list"}).err.find("in at most five digits"), std::string::npos);
  TempDir dir("address");
  Process worker({BuiltBinary("worker/runtime/endorecon-worker"), "serve", "--server", "127.0.0.1:99999",
                  "--metrics-port", "-1"},
                 dir / "worker.log");
  EXPECT_EQ(worker.Wait(), 2) << worker.Log();
  EXPECT_NE(worker.Log().find("the port must be a number from 1 to 65535"), std::string::npos)
      << worker.Log();
}

// A worker's numbers and id are checked at start: --lease-wait -1 busy-polled an idle queue,
// --threads -3 was taken, and an id with a newline was listed raw (found 2026-12-05).
TEST(SubmitToCompletionTest, AWorkersBadNumbersAndIdAreRefusedAtStart) {
  TempDir dir("worker-flags");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--lease-wait", "-1"}, "--lease-wait: -1 is not above 0"},
      {{"--threads", "-3"}, "--threads"},
      {{"--timeout", "0"}, "--timeout: 0 is not above 0"},
      {{"--exit-when-idle", "-5"}, "--exit-when-idle: -5 is negative; expected a number >= 0"},
      {{"--exit-when-idle", "nan"}, "--exit-when-idle: nan is not a finite number"},
      {{"--id", "a\nb"}, "--id: worker id holds a control character (byte 10)"},
  };
  for (const auto& [flags, expected] : cases) {
    std::vector<std::string> argv = {
        BuiltBinary("worker/runtime/endorecon-worker"), "serve",          "--server",
        "127.0.0.1:" + std::to_string(FreePort()),      "--metrics-port", "-1"};
    argv.insert(argv.end(), flags.begin(), flags.end());
    Process worker(argv, dir / "worker.log");
    EXPECT_EQ(worker.Wait(), 2) << flags[0] << ": " << worker.Log();
    EXPECT_NE(worker.Log().find(expected), std::string::npos) << worker.Log();
  }
}

}  // namespace
}  // namespace endorecon::testing
