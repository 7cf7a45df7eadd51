// A raw stereo recording as a job: the CLI uploads the two videos, the calibration and the masks,
// the worker prepares the clip and reconstructs it in the same job, `watch` shows the preparation,
// and the prepared clip comes back with the results.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "tests/integration/service_harness.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

// The synthetic recording's eyes as Motion-JPEG videos beside its calibration and masks.
void MakeRecording(const fs::path& dir) {
  scene::SynthOptions options;
  options.frames = 6;
  options.width = 128;
  options.height = 96;
  options.recording = true;
  scene::WriteSyntheticClip(options, dir / "synth");
  for (const char* eye : {"left", "right"}) {
    cv::VideoWriter video((dir / (std::string(eye) + ".avi")).string(), cv::CAP_OPENCV_MJPEG,
                          cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(128, 96));
    for (int i = 0; i < options.frames; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", i);
      video.write(cv::imread((dir / "synth/recording" / eye / name).string()));
    }
  }
}

TEST(PrepareJobTest, RecordingInPreparedClipAndResultsOut) {
  Cluster cluster;
  cluster.StartWorker("w1");
  MakeRecording(cluster.path("rec"));
  const fs::path rec = cluster.path("rec");
  const auto submitted =
      RunCli(cluster.address(),
             {"submit", "--left", (rec / "left.avi").string(), "--right", (rec / "right.avi").string(),
              "--calibration", (rec / "synth/recording/calibration.yaml").string(), "--masks",
              (rec / "synth/recording/masks").string(), "--frames", "0:6:1", "--iterations", "20", "--wait",
              "--previews", cluster.path("previews").string()});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err << submitted.out << cluster.ServerLog();
  EXPECT_NE(submitted.out.find("SUCCEEDED"), std::string::npos) << submitted.out;
  EXPECT_NE(submitted.err.find("uploaded 9 file(s)"), std::string::npos) << submitted.err;
  EXPECT_TRUE(fs::exists(cluster.path("previews/prepare-it0.png"))) << submitted.out;

  const auto listed = RunCli(cluster.address(), {"--json", "list"});
  const auto id = listed.out.substr(listed.out.find("\"id\":\"") + 6, 12);
  const v1::Job job = cluster.Job(id);
  ASSERT_TRUE(job.has_prepare());
  EXPECT_EQ(job.prepare().left(), "left.avi");
  EXPECT_EQ(job.prepare().calibration(0), "calibration.yaml");
  EXPECT_EQ(job.prepare().masks(), "masks");
  EXPECT_EQ(job.name(), "rec") << "the folder of both eyes, not the left eye's file";
  const auto status = RunCli(cluster.address(), {"status", id});
  EXPECT_NE(status.out.find("  recording 9 file(s)"), std::string::npos) << status.out;

  const auto fetched = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("results").string()});
  ASSERT_EQ(fetched.exit_code, 0) << fetched.err;
  for (const char* file : {"metrics.json", "clip/prepare.json", "clip/preview.png", "clip/poses_bounds.npy",
                           "clip/images/000005.png", "clip/depth/000005.npy", "clip/masks/000005.png"}) {
    EXPECT_TRUE(fs::exists(cluster.path("results") / file)) << file;
  }
  // The prepared clip says where it came from in the submitter's names, not the worker's scratch.
  const std::string report = ReadBytes(cluster.path("results/clip/prepare.json"));
  EXPECT_NE(report.find((rec / "left.avi").string()), std::string::npos) << report;
  EXPECT_NE(report.find((rec / "synth/recording/calibration.yaml").string()), std::string::npos) << report;
  EXPECT_NE(report.find("\"masks\": \"" + (rec / "synth/recording/masks").string()), std::string::npos)
      << report;

  // The same recording again: nothing is uploaded twice. The eyes' skips travel with the job.
  const auto again =
      RunCli(cluster.address(),
             {"submit", "--left", (rec / "left.avi").string(), "--right", (rec / "right.avi").string(),
              "--calibration", (rec / "synth/recording/calibration.yaml").string(), "--masks",
              (rec / "synth/recording/masks").string(), "--iterations", "20", "--skip-left", "2",
              "--skip-right", "1"});
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.err.find(": 0 B sent"), std::string::npos) << again.err;
  const v1::Job skipped = cluster.Job(again.out.substr(again.out.find("job ") + 4, 12));
  EXPECT_EQ(skipped.prepare().skip_left(), 2);
  EXPECT_EQ(skipped.prepare().skip_right(), 1);
}

// A raw recording is staged under fixed names (left.avi); a job's error names the file as the user
// gave it (it said "left.avi: ...", a file the user never had; found 2026-12-05).
TEST(PrepareJobTest, AFailedRecordingNamesTheUsersFile) {
  Cluster cluster;
  cluster.StartWorker("w1");
  MakeRecording(cluster.path("rec"));
  const fs::path rec = cluster.path("rec");
  WriteBytes(rec / "mine.avi", "not a video at all");
  const auto submitted = RunCli(
      cluster.address(),
      {"submit", "--left", (rec / "mine.avi").string(), "--right", (rec / "right.avi").string(),
       "--calibration", (rec / "synth/recording/calibration.yaml").string(), "--iterations", "20", "--wait"});
  EXPECT_EQ(submitted.exit_code, 5) << submitted.err << submitted.out;
  const std::string said = submitted.out + submitted.err;
  EXPECT_NE(said.find((rec / "mine.avi").string()), std::string::npos) << said;
  EXPECT_EQ(said.find("left.avi"), std::string::npos) << said;
  // A folder is named as the user gave it too, where the worker names it without its slash (it was
  // "masks frame 4: ...", the upload's name; found 2026-12-07).
  fs::copy(rec / "synth/recording/masks", rec / "my masks", fs::copy_options::recursive);
  std::vector<fs::path> masks;
  for (const auto& entry : fs::directory_iterator(rec / "my masks")) masks.push_back(entry.path());
  std::sort(masks.begin(), masks.end());
  fs::remove(masks.back());
  const auto short_masks =
      RunCli(cluster.address(),
             {"submit", "--left", (rec / "left.avi").string(), "--right", (rec / "right.avi").string(),
              "--calibration", (rec / "synth/recording/calibration.yaml").string(), "--masks",
              (rec / "my masks").string(), "--iterations", "20", "--wait"});
  EXPECT_EQ(short_masks.exit_code, 5) << short_masks.err << short_masks.out;
  const std::string reason = short_masks.out + short_masks.err;
  EXPECT_NE(reason.find((rec / "my masks").string() + " frame 5: the masks end after 5 frames"),
            std::string::npos)
      << reason;
  EXPECT_EQ(reason.find(": masks frame"), std::string::npos) << reason;
}

// A folder named as an eye sends only its frames: `--left ../../etc` uploaded every file of /etc
// (found 2026-12-05). A folder without frames, or a folder as --calibration, is refused before any
// upload, naming the path as the user gave it.
TEST(PrepareJobTest, AnEyesFolderSendsOnlyItsFramesAndAFolderIsNoCalibration) {
  Cluster cluster;
  MakeRecording(cluster.path("rec"));
  const fs::path rec = cluster.path("rec");
  fs::create_directories(rec / "notes");
  WriteBytes(rec / "notes" / "secret.txt", "not a frame");
  const auto calibration = (rec / "synth/recording/calibration.yaml").string();
  auto result = RunCli(cluster.address(), {"submit", "--left", (rec / "notes").string(), "--right",
                                           (rec / "right.avi").string(), "--calibration", calibration});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find((rec / "notes").string() + ": the folder holds no image"), std::string::npos)
      << result.err;
  result =
      RunCli(cluster.address(), {"submit", "--left", (rec / "left.avi").string(), "--right",
                                 (rec / "right.avi").string(), "--calibration", (rec / "synth").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("synth: a folder, and --calibration takes a file"), std::string::npos)
      << result.err;
  // An eye a frame short, or a frame cut short, is refused before the upload too, naming the user's
  // folder and frame (both were uploaded, queued and failed on a worker; found 2026-12-06).
  fs::copy(rec / "synth/recording/right", rec / "short", fs::copy_options::recursive);
  fs::copy(rec / "synth/recording/left", rec / "cut", fs::copy_options::recursive);
  std::vector<fs::path> frames;
  for (const auto& entry : fs::directory_iterator(rec / "short")) frames.push_back(entry.path());
  std::sort(frames.begin(), frames.end());
  fs::remove(frames.back());
  result = RunCli(cluster.address(), {"submit", "--left", (rec / "synth/recording/left").string(), "--right",
                                      (rec / "short").string(), "--calibration", calibration});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find((rec / "short").string() + "/: " + std::to_string(frames.size() - 1) +
                            " frames while " + (rec / "synth/recording/left").string() + "/ has " +
                            std::to_string(frames.size())),
            std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("(found before the upload: nothing was sent)"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("pass --skip-left or --skip-right"), std::string::npos) << result.err;
  // A skip that leaves an eye's folder no frame (it was uploaded, and the job failed on a worker;
  // found 2026-12-07).
  result = RunCli(cluster.address(), {"submit", "--left", (rec / "synth/recording/left").string(), "--right",
                                      (rec / "short").string(), "--calibration", calibration, "--skip-left",
                                      std::to_string(frames.size())});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("/: it holds " + std::to_string(frames.size()) +
                            " frame(s): none is left after the " + std::to_string(frames.size()) +
                            " skipped (--skip-left " + std::to_string(frames.size()) + ")"),
            std::string::npos)
      << result.err;
  const fs::path cut = rec / "cut" / frames.front().filename();
  WriteBytes(cut, ReadBytes(cut).substr(0, 200));
  result =
      RunCli(cluster.address(), {"submit", "--left", (rec / "cut").string(), "--right",
                                 (rec / "synth/recording/right").string(), "--calibration", calibration});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find(cut.string() + ": a truncated PNG"), std::string::npos) << result.err;
  int uploaded = 0;
  for (const char* folder : {"blobs", "partial"}) {
    if (!fs::exists(cluster.data_dir() / folder)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(cluster.data_dir() / folder))
      uploaded += entry.is_regular_file() ? 1 : 0;
  }
  EXPECT_EQ(uploaded, 0);

  // The eyes' frames as folders, a stray file among them: the frames go, the stray file does not.
  WriteBytes(rec / "synth/recording/left/notes.txt", "not a frame");
  result =
      RunCli(cluster.address(), {"submit", "--left", (rec / "synth/recording/left").string(), "--right",
                                 (rec / "synth/recording/right").string(), "--calibration", calibration});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("uploaded 13 file(s)"), std::string::npos) << result.err;
}

TEST(PrepareJobTest, BadRecordingOptionsAreRefusedBeforeAnyUpload) {
  Cluster cluster;
  const auto result = RunCli(cluster.address(), {"submit", "--left", "L.mp4", "--right", "R.mp4",
                                                 "--calibration", "c.yaml", "--frames", "1:x"});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("'1:x': expected START:END:STEP"), std::string::npos) << result.err;
  const auto both = RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--side-by-side",
                                               "s.mp4", "--rectified", "--focal", "500", "--baseline", "4"});
  EXPECT_EQ(both.exit_code, 2) << both.err;

  // The server checks that the options name uploaded files.
  v1::SubmitRequest request;
  auto* file = request.mutable_clip()->add_files();
  file->set_path("left.mp4");
  file->set_size(1);
  file->set_sha256(std::string(64, 'a'));
  request.mutable_prepare()->set_left("left.mp4");
  request.mutable_prepare()->set_right("right.mp4");
  request.mutable_prepare()->add_calibration("calibration.yaml");
  grpc::ClientContext context;
  v1::Job job;
  const grpc::Status status = cluster.stub().Submit(&context, request, &job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("'right.mp4' is not a file (or folder) of the uploaded recording"),
            std::string::npos)
      << status.error_message();
}

}  // namespace
}  // namespace endorecon::testing
