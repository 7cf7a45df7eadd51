// Bad DICOM input is refused with what and where at submit: by the CLI before the upload (a file
// that is not a recording, an unknown PACS name, a malformed Study UID, an endoscope that is neither
// moving nor fixed, a frame size that is not WxH, even), or by the server from the uploaded files'
// headers before the queue (a file named *.dcm that is not DICOM, a --frames window past the
// recording's end, a --size of another shape); nothing else is lost.
#include <gtest/gtest.h>

#include <filesystem>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(BadDicomInputTest, RefusedAtSubmitOrAtPreparation) {
  Cluster cluster;
  cluster.StartWorker("w1");
  WriteBytes(cluster.path("recording.dcm"), std::string(1000, 'x'));
  const auto bad = RunCli(cluster.address(), {"submit", cluster.path("recording.dcm").string(), "--wait"});
  EXPECT_EQ(bad.exit_code, 2) << bad.out << bad.err;
  // Named as in the clip, not by its path in the server's folder of links (it failed on the worker,
  // after the queue, until 2026-12-07).
  EXPECT_NE(bad.err.find("recording.dcm: not a DICOM file (no \"DICM\" at byte 128)"), std::string::npos)
      << bad.err;
  EXPECT_EQ(bad.err.find("endorecon-recording-"), std::string::npos) << bad.err;
  // Before its upload, by the CLI (a 200 MB folder went up to be refused; found 2026-12-07).
  EXPECT_NE(bad.err.find("found before the upload: nothing was sent"), std::string::npos) << bad.err;

  // A recording's --frames past its end and a --size of another shape: refused from its header at
  // submit (they were the worker's to find, after the queue).
  MakeClip(cluster.path("frames"));
  Process to_dicom(
      {BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom", cluster.path("frames/images").string(),
       "-o", cluster.path("rec.dcm").string(), "--format", "vl"},
      cluster.path("to-dicom.log"));
  ASSERT_EQ(to_dicom.Wait(), 0);
  for (const auto& [args, said] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--frames", "20:"},
            "rec.dcm: zero frames: the window 20::1 holds none of the recording's 8 frames"},
           {{"--size", "64x64"},
            "size 64x64 changes the recording's 32x24 aspect ratio; give a size of the same "
            "shape, e.g. 64x48"},
           {{"--stereo", "series"}, "rec.dcm: holds 1 series; stereo as two series needs exactly two"}}) {
    std::vector<std::string> command = {"submit", cluster.path("rec.dcm").string()};
    command.insert(command.end(), args.begin(), args.end());
    const auto refused = RunCli(cluster.address(), command);
    EXPECT_EQ(refused.exit_code, 2) << args[0] << ": " << refused.out << refused.err;
    EXPECT_NE(refused.err.find(said), std::string::npos) << args[0] << ": " << refused.err;
  }
  EXPECT_EQ(RunCli(cluster.address(), {"list"}).out.find(".dcm"), std::string::npos) << "nothing was queued";

  // A file that is not a recording at all (a video) is refused by the CLI before anything is uploaded.
  WriteBytes(cluster.path("endo.mp4"), std::string(1000, 'x'));
  const auto video = RunCli(cluster.address(), {"submit", cluster.path("endo.mp4").string()});
  EXPECT_EQ(video.exit_code, 2) << video.err;
  EXPECT_NE(video.err.find("endo.mp4: a file that is not a DICOM recording"), std::string::npos) << video.err;
  EXPECT_NE(video.err.find("endorecon-worker to-dicom VIDEO"), std::string::npos) << video.err;
  EXPECT_EQ(video.err.find("uploaded"), std::string::npos) << video.err;
  // So is a folder that is no clip (it was uploaded and queued, then failed on the worker).
  std::filesystem::create_directories(cluster.path("notaclip"));
  WriteBytes(cluster.path("notaclip") / "notes.txt", "not a frame");
  const auto folder = RunCli(cluster.address(), {"submit", cluster.path("notaclip").string()});
  EXPECT_EQ(folder.exit_code, 2) << folder.err;
  EXPECT_NE(folder.err.find("notaclip: not a clip: found neither transforms.json"), std::string::npos)
      << folder.err;
  EXPECT_EQ(folder.err.find("uploaded"), std::string::npos) << folder.err;

  // Options that do not apply to the input are refused before the upload, naming them: they were
  // ignored without a word (found 2026-12-05).
  const std::vector<std::pair<std::vector<std::string>, std::string>> misplaced = {
      {{"--calibration", "c.yaml"}, "prepare a raw recording"},
      {{"--exclude", "0,0,10,10"}, "prepare a raw recording"},
      {{"--patient-id", "P1"}, "a DICOM recording's results keep its own patient and study"},
      {{"--study", "1.2.3"}, "--study and --series name a recording in a PACS"},
      {{"--frames", "1:x"}, "'1:x'"}};
  for (const auto& [args, said] : misplaced) {
    std::vector<std::string> command = {"submit", cluster.path("recording.dcm").string()};
    command.insert(command.end(), args.begin(), args.end());
    const auto refused = RunCli(cluster.address(), command);
    EXPECT_EQ(refused.exit_code, 2) << args[0] << ": " << refused.err;
    EXPECT_NE(refused.err.find(said), std::string::npos) << args[0] << ": " << refused.err;
    EXPECT_EQ(refused.err.find("uploaded"), std::string::npos) << args[0] << ": " << refused.err;
  }

  const auto unknown = RunCli(cluster.address(), {"submit", "--pacs", "nowhere", "--study", "1.2.3"});
  EXPECT_EQ(unknown.exit_code, 3) << unknown.err;
  EXPECT_NE(unknown.err.find("no PACS named 'nowhere' is configured on the server"), std::string::npos)
      << unknown.err;

  const auto wobbly =
      RunCli(cluster.address(), {"submit", cluster.path("recording.dcm").string(), "--endoscope", "wobbly"});
  EXPECT_EQ(wobbly.exit_code, 2) << wobbly.err;
  EXPECT_NE(wobbly.err.find("--endoscope"), std::string::npos) << wobbly.err;
  const auto odd =
      RunCli(cluster.address(), {"submit", cluster.path("recording.dcm").string(), "--size", "321x180"});
  EXPECT_EQ(odd.exit_code, 2) << odd.err;
  EXPECT_NE(odd.err.find("'321x180'"), std::string::npos) << odd.err;
  // A client that skips the CLI's check meets the server's.
  v1::SubmitRequest request;
  auto* file = request.mutable_clip()->add_files();
  file->set_path("recording.dcm");
  file->set_size(1000);
  file->set_sha256(std::string(64, 'a'));
  request.mutable_recording()->set_endoscope("wobbly");
  request.mutable_recording()->set_size("320x180");
  grpc::ClientContext context;
  v1::Job job;
  const grpc::Status status = cluster.stub().Submit(&context, request, &job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("endoscope 'wobbly': expected moving or fixed"), std::string::npos)
      << status.error_message();

  // The worker is still there for the next job.
  MakeClip(cluster.path("clip"));
  const auto good =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "10", "--wait"});
  EXPECT_EQ(good.exit_code, 0) << good.out << good.err;
}

}  // namespace
}  // namespace endorecon::testing
