// A real PACS at both ends (Orthanc on loopback): an endoscopic H.264 recording made here is
// stored in it, a job is submitted by its Study UID (the server retrieves it by C-GET; the job
// scales its frames), runs, and its DICOM results go back into the same patient and study. Then:
// the PACS down during a send (the send fails, the job stays SUCCEEDED, a resend after it is back
// succeeds), an association refused by AE title, an unknown study, a PACS down during a retrieval
// (waited for), and a retrieval by C-MOVE to the server's storage SCP.
#include <dcmtk/dcmdata/dctk.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/dicom/dataset_access.h"
#include "common/dicom/result_instances.h"
#include "common/dicom/store_scu.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "tests/integration/audit_reader.h"
#include "tests/integration/orthanc_harness.h"
#include "tests/unit/dciodvfy.h"

namespace endorecon::testing {
namespace {
namespace fs = std::filesystem;

constexpr const char* kPatient = "PAT-15";

// The synthetic clip's frames as an H.264 Video Endoscopic recording (endorecon-worker to-dicom:
// OpenCV's FFmpeg encodes, DCMTK wraps) of a new study; returns its Study Instance UID.
std::string MakeRecording(const fs::path& dir, const fs::path& out) {
  MakeClip(dir / "clip");
  const std::string study = dicom::NewUid("");
  Process writer({BuiltBinary("worker/runtime/endorecon-worker"), "to-dicom",
                  (dir / "clip" / "images").string(), "-o", out.string(), "--fps", "10", "--patient-id",
                  kPatient, "--patient-name", "Test^Patient", "--study-uid", study},
                 dir / "to-dicom.log");
  EXPECT_EQ(writer.Wait(), 0) << writer.Log();
  return study;
}

// A CT image of the same patient in `study` (a series of its own): an object of a class endorecon does
// not take, as real studies hold beside a recording.
fs::path MakeCtImage(const fs::path& out, const std::string& study) {
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  dicom::Put(data, DCM_SOPClassUID, UID_CTImageStorage);
  dicom::Put(data, DCM_SOPInstanceUID, dicom::NewUid(""));
  dicom::Put(data, DCM_StudyInstanceUID, study);
  dicom::Put(data, DCM_SeriesInstanceUID, dicom::NewUid(""));
  dicom::Put(data, DCM_PatientID, kPatient);
  dicom::Put(data, DCM_PatientName, "Test^Patient");
  dicom::Put(data, DCM_Modality, "CT");
  dicom::Put(data, DCM_SeriesNumber, "7");
  dicom::Put(data, DCM_InstanceNumber, "1");
  dicom::Put(data, DCM_PhotometricInterpretation, "MONOCHROME2");
  data.putAndInsertUint16(DCM_SamplesPerPixel, 1);
  data.putAndInsertUint16(DCM_Rows, 4);
  data.putAndInsertUint16(DCM_Columns, 4);
  data.putAndInsertUint16(DCM_BitsAllocated, 16);
  data.putAndInsertUint16(DCM_BitsStored, 12);
  data.putAndInsertUint16(DCM_HighBit, 11);
  data.putAndInsertUint16(DCM_PixelRepresentation, 0);
  const Uint16 pixels[16] = {};
  data.putAndInsertUint16Array(DCM_PixelData, pixels, 16);
  EXPECT_TRUE(file.saveFile(out.c_str(), EXS_LittleEndianExplicit).good());
  return out;
}

std::string JobIdIn(const std::string& out) {
  const auto at = out.find("job ");
  return at == std::string::npos ? "" : out.substr(at + 4, 12);
}

// A string field of a JSON answer, "" when absent or not a string (Orthanc writes null for some).
std::string Text(const nlohmann::json& json, const std::string& key) {
  return json.is_object() && json.contains(key) && json[key].is_string() ? json[key].get<std::string>() : "";
}

// Submits the study without a worker and returns the job once its retrieval ended (the job then
// waits in the queue).
v1::Job SubmitAndAwaitRetrieval(Cluster& cluster, const std::string& study) {
  const auto submitted = RunCli(cluster.address(), {"submit", "--pacs", "orthanc", "--study", study});
  EXPECT_EQ(submitted.exit_code, 0) << submitted.err;
  const std::string id = JobIdIn(submitted.out);
  EXPECT_TRUE(WaitUntil([&] { return cluster.Job(id).retrieval().state() != v1::Retrieval::RETRIEVING; },
                        std::chrono::seconds(60)));
  return cluster.Job(id);
}

const v1::DicomSend* SendTo(const v1::Job& job, const std::string& destination) {
  for (const auto& send : job.sends()) {
    if (send.destination() == destination) return &send;
  }
  return nullptr;
}

class PacsRoundTripTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scp_port_ = FreePort();
    mover_port_ = FreePort();
    orthanc_ = std::make_unique<Orthanc>(
        dir_ / "orthanc",
        std::vector<OrthancModality>{{"ENDORECON", scp_port_, true}, {"MOVER", mover_port_, false}});
    const std::string why = orthanc_->Start();
    if (!why.empty()) GTEST_SKIP() << "Orthanc cannot start, PACS tests skipped: " << why;
  }

  TempDir dir_{"pacs"};
  int scp_port_ = 0, mover_port_ = 0;
  std::unique_ptr<Orthanc> orthanc_;
};

TEST_F(PacsRoundTripTest, RecordingFromThePacsResultsBackIntoItsStudy) {
  const std::string study = MakeRecording(dir_.path(), dir_ / "recording.dcm");
  const auto stored = orthanc_->Store(dir_ / "recording.dcm");
  ASSERT_EQ(Text(stored, "Status"), "Success") << stored.dump();
  const std::string orthanc_study = Text(stored, "ParentStudy");

  Cluster cluster({"--ae-title", "ENDORECON", "--pacs", "orthanc=" + orthanc_->Address(), "--pacs",
                   "wrongae=WRONGAE@127.0.0.1:" + std::to_string(orthanc_->dicom_port()), "--dicom-listen",
                   "127.0.0.1:" + std::to_string(scp_port_), "--send-attempts", "2", "--send-backoff-ms",
                   "200", "--dicom-timeout", "5"});
  cluster.StartWorker("w1");
  const auto submitted =
      RunCli(cluster.address(), {"submit", "--pacs", "orthanc", "--study", study, "--send-to", "orthanc",
                                 "--iterations", "30", "--size", "64x48", "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err << cluster.ServerLog();
  EXPECT_NE(submitted.out.find("retrieval from PACS orthanc by C-GET"), std::string::npos) << submitted.out;
  EXPECT_NE(submitted.out.find("send to orthanc: sent 5 of 5"), std::string::npos) << submitted.out;
  // Each line once: the retrieval's was printed again with every update of the send (found
  // 2026-12-05).
  const auto count = [&](const std::string& what) {
    int n = 0;
    for (auto at = submitted.out.find(what); at != std::string::npos; at = submitted.out.find(what, at + 1))
      ++n;
    return n;
  };
  EXPECT_EQ(count(", done\n"), 1) << submitted.out;
  EXPECT_EQ(count("send to orthanc: sent 5 of 5\n"), 1) << submitted.out;
  const std::string id = JobIdIn(submitted.out);
  v1::Job job = cluster.Job(id);
  EXPECT_EQ(job.state(), v1::SUCCEEDED);
  EXPECT_EQ(job.retrieval().state(), v1::Retrieval::RETRIEVED);
  EXPECT_EQ(job.retrieval().instances(), 1);
  ASSERT_EQ(job.clip().files_size(), 1);
  // Named by its place, not by its SOP Instance UID, which stood in errors and logs.
  EXPECT_EQ(job.clip().files(0).path(), "instance-0001.dcm");
  EXPECT_EQ(job.retrieval().bytes(), job.clip().files(0).size());
  EXPECT_GT(job.retrieval().bytes(), 1000);

  // In the PACS: the recording's study now holds four more series, of the same patient.
  const auto series = orthanc_->Post(
      "/tools/find",
      nlohmann::json{{"Level", "Series"}, {"Query", {{"StudyInstanceUID", study}}}, {"Expand", true}}.dump());
  ASSERT_TRUE(series.is_array()) << series.dump();
  EXPECT_EQ(series.size(), 6u) << series.dump();
  std::map<std::string, nlohmann::json> by_class;
  for (const auto& one : series) {
    EXPECT_EQ(Text(one, "ParentStudy"), orthanc_study);
    ASSERT_TRUE(one.contains("Instances") && !one["Instances"].empty()) << one.dump();
    const std::string instance = one["Instances"][0].get<std::string>();
    auto tags = orthanc_->Get("/instances/" + instance + "/simplified-tags");
    ASSERT_TRUE(tags.is_object()) << instance;
    EXPECT_EQ(Text(tags, "PatientID"), kPatient);
    tags["ID"] = instance;
    by_class[Text(tags, "SOPClassUID")] = tags;
  }
  const auto rendered = by_class["1.2.840.10008.5.1.4.1.1.7.4"];
  EXPECT_EQ(Text(rendered, "NumberOfFrames"), "8") << rendered.dump();
  // Orthanc's JSON leaves out long values: read this one as it is.
  EXPECT_NE(orthanc_->GetText("/instances/" + Text(rendered, "ID") + "/content/0008-2111").find("endorecon"),
            std::string::npos);
  EXPECT_EQ(Text(by_class["1.2.840.10008.5.1.4.1.1.7.3"], "NumberOfFrames"), "8");
  EXPECT_EQ(by_class.count("1.2.840.10008.5.1.4.1.1.104.3"), 1u);
  EXPECT_EQ(by_class.count("1.2.840.10008.5.1.4.1.1.77.1.1.1"), 1u);
  const auto patients = orthanc_->Get("/patients");
  ASSERT_TRUE(patients.is_array() && patients.size() == 1u) << patients.dump();
  EXPECT_EQ(Text(orthanc_->Get("/studies/" + orthanc_study), "ParentPatient"),
            patients[0].get<std::string>());

  // The study, now holding the results too, is run again: the retrieval takes the results the PACS
  // sends with the recording and keeps the recording alone (the PACS refused the whole C-GET, as the
  // server offered no context for the results' classes; found 2026-12-05).
  const auto again = RunCli(cluster.address(), {"submit", "--pacs", "orthanc", "--study", study,
                                                "--iterations", "5", "--size", "64x48", "--wait"});
  EXPECT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_EQ(cluster.Job(JobIdIn(again.out)).retrieval().instances(), 1);

  // What the worker wrote conforms, and the mesh is there in the open formats too.
  ASSERT_EQ(RunCli(cluster.address(), {"fetch", id, "-o", (dir_ / "results").string()}).exit_code, 0);
  for (const char* name : {"rendered.dcm", "depth.dcm", "uncertainty.dcm", "model_map.dcm", "mesh.dcm"}) {
    EXPECT_EQ(DciodvfyErrors(dir_ / "results" / "dicom" / name), "") << name;
  }
  EXPECT_TRUE(fs::exists(dir_ / "results" / "mesh.ply"));
  EXPECT_TRUE(fs::exists(dir_ / "results" / "mesh.obj"));
  // The recording's 32 x 24 frames were scaled to the size the job asked for, as its record says.
  EXPECT_EQ(cv::imread((dir_ / "results" / "rgb" / "000000.png").string()).size(), cv::Size(64, 48));
  std::ifstream record_file(dir_ / "results" / "recording.json");
  const auto record = nlohmann::json::parse(record_file, nullptr, false);
  EXPECT_EQ(record.value("size", nlohmann::json()), nlohmann::json({64, 48})) << record.dump();
  EXPECT_EQ(record.value("recorded_size", nlohmann::json()), nlohmann::json({32, 24}));
  EXPECT_EQ(record.value("endoscope", ""), "moving");

  const auto metrics =
      Capture("curl -s http://127.0.0.1:" + std::to_string(cluster.metrics_port()) + "/metrics");
  EXPECT_NE(metrics.find("endorecon_dicom_instances_sent_total{destination=\"orthanc\"} 5"),
            std::string::npos)
      << metrics;
  EXPECT_EQ(metrics.find("endorecon_dicom_retrieval_bytes_total 0\n"), std::string::npos);

  // An association the PACS refuses by AE title: the send fails with the PACS's reason.
  const auto refused = RunCli(cluster.address(), {"send", id, "--to", "wrongae", "--wait"});
  EXPECT_EQ(refused.exit_code, 5) << refused.out << refused.err;
  job = cluster.Job(id);
  ASSERT_NE(SendTo(job, "wrongae"), nullptr);
  EXPECT_EQ(SendTo(job, "wrongae")->state(), v1::DicomSend::SEND_FAILED);
  EXPECT_NE(SendTo(job, "wrongae")->error().find("rejected"), std::string::npos)
      << SendTo(job, "wrongae")->error();
  EXPECT_EQ(SendTo(job, "wrongae")->attempts(), 1) << "a permanent rejection is not retried";

  // A job submitted with a send that fails: `submit --wait` says so in its exit code, as `send --wait`
  // does (it exited 0; found 2026-12-05).
  MakeClip(dir_ / "clip");
  const auto sent_badly = RunCli(cluster.address(), {"submit", (dir_ / "clip").string(), "--dicom",
                                                     "--send-to", "wrongae", "--iterations", "5", "--wait"});
  EXPECT_EQ(sent_badly.exit_code, 5) << sent_badly.out << sent_badly.err;
  // The listing shows it: a SUCCEEDED job whose results did not reach the PACS.
  const auto listed = RunCli(cluster.address(), {"list"});
  EXPECT_NE(listed.out.find("[send to wrongae failed]"), std::string::npos) << listed.out;

  // The PACS down: the send fails and the job keeps its results; back up, a resend goes through.
  orthanc_->Stop();
  const auto down = RunCli(cluster.address(), {"send", id, "--to", "orthanc", "--wait"});
  EXPECT_EQ(down.exit_code, 5) << down.out << down.err;
  job = cluster.Job(id);
  EXPECT_EQ(job.state(), v1::SUCCEEDED);
  EXPECT_EQ(SendTo(job, "orthanc")->state(), v1::DicomSend::SEND_FAILED);
  EXPECT_EQ(SendTo(job, "orthanc")->attempts(), 2);
  EXPECT_NE(metrics.size(), 0u);
  ASSERT_EQ(orthanc_->Start(), "");
  const auto resent = RunCli(cluster.address(), {"send", id, "--to", "orthanc", "--wait"});
  EXPECT_EQ(resent.exit_code, 0) << resent.out << resent.err;
  EXPECT_EQ(SendTo(cluster.Job(id), "orthanc")->state(), v1::DicomSend::SENT);
  EXPECT_EQ(SendTo(cluster.Job(id), "orthanc")->sent(), 5);

  // A study the PACS does not hold: the job fails with the reason, before any worker sees it.
  const auto missing =
      RunCli(cluster.address(), {"submit", "--pacs", "orthanc", "--study", "1.2.3.4.5", "--wait"});
  EXPECT_EQ(missing.exit_code, 5) << missing.out << missing.err;
  EXPECT_NE(missing.out.find("FAILED: retrieval from PACS orthanc failed"), std::string::npos) << missing.out;
  // ... said as what it is, not as a PACS that would not send (C-GET and C-MOVE were tried after
  // C-FIND found nothing), and without the UID, as every log line.
  const std::string missing_job = cluster.Job(JobIdIn(missing.out)).error();
  EXPECT_NE(missing_job.find("NOT_FOUND: PACS ORTHANC holds no such study"), std::string::npos)
      << missing_job;
  EXPECT_EQ(missing_job.find("1.2.3.4.5"), std::string::npos) << missing_job;
  EXPECT_EQ(missing_job.find("C-GET"), std::string::npos) << missing_job;

  // A window past the retrieved recording's end fails the job from its header before the queue,
  // naming the file as the job's clip does (a worker found it, after the wait, until 2026-12-07).
  const auto past = RunCli(cluster.address(),
                           {"submit", "--pacs", "orthanc", "--study", study, "--frames", "20:", "--wait"});
  EXPECT_EQ(past.exit_code, 5) << past.out << past.err;
  const v1::Job past_job = cluster.Job(JobIdIn(past.out));
  EXPECT_NE(
      past_job.error().find("the recording retrieved from PACS orthanc: instance-0001.dcm: zero frames: "
                            "the window 20::1 holds none of the recording's 8 frames"),
      std::string::npos)
      << past_job.error();
  EXPECT_EQ(past_job.started_unix_ms(), 0) << "no worker ran it";
}

// A PACS that does not answer (down for maintenance, restarting) is waited for: the job stays QUEUED
// and its retrieval is tried again, its last reason and next attempt shown; it failed at once until
// 2026-12-06. A PACS that refuses this server is not: that stays so until someone changes a
// configuration.
TEST_F(PacsRoundTripTest, ARetrievalWaitsForAPacsThatIsDownNotForOneThatRefuses) {
  const std::string study = MakeRecording(dir_.path(), dir_ / "recording.dcm");
  ASSERT_EQ(Text(orthanc_->Store(dir_ / "recording.dcm"), "Status"), "Success");
  orthanc_->Stop();
  Cluster cluster({"--ae-title", "ENDORECON", "--pacs", "orthanc=" + orthanc_->Address(), "--pacs",
                   "wrongae=WRONGAE@127.0.0.1:" + std::to_string(orthanc_->dicom_port()),
                   "--retrieve-attempts", "12", "--retrieve-backoff-ms", "300", "--dicom-timeout", "5"});
  const auto submitted = RunCli(cluster.address(), {"submit", "--pacs", "orthanc", "--study", study});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  const std::string id = JobIdIn(submitted.out);
  ASSERT_TRUE(
      WaitUntil([&] { return cluster.Job(id).retrieval().attempts() >= 2; }, std::chrono::seconds(30)))
      << cluster.ServerLog();
  v1::Job waiting = cluster.Job(id);
  EXPECT_EQ(waiting.state(), v1::QUEUED);
  EXPECT_EQ(waiting.retrieval().state(), v1::Retrieval::RETRIEVING);
  EXPECT_EQ(waiting.retrieval().error().rfind("UNAVAILABLE: ", 0), 0u) << waiting.retrieval().error();
  const auto status = RunCli(cluster.address(), {"status", id});
  EXPECT_NE(status.out.find("waiting for the PACS (attempt "), std::string::npos) << status.out;

  ASSERT_EQ(orthanc_->Start(), "");
  ASSERT_TRUE(WaitUntil([&] { return cluster.Job(id).retrieval().state() != v1::Retrieval::RETRIEVING; },
                        std::chrono::seconds(90)));
  const v1::Job retrieved = cluster.Job(id);
  EXPECT_EQ(retrieved.retrieval().state(), v1::Retrieval::RETRIEVED) << retrieved.retrieval().error();
  EXPECT_EQ(retrieved.state(), v1::QUEUED);
  EXPECT_EQ(retrieved.retrieval().instances(), 1);
  EXPECT_GE(retrieved.retrieval().attempts(), 3);

  // Refused by AE title: one attempt, FAILED_PRECONDITION.
  const auto refused = RunCli(cluster.address(), {"submit", "--pacs", "wrongae", "--study", study, "--wait"});
  EXPECT_EQ(refused.exit_code, 5) << refused.out << refused.err;
  const v1::Job failed = cluster.Job(JobIdIn(refused.out));
  EXPECT_EQ(failed.retrieval().attempts(), 1);
  EXPECT_EQ(failed.retrieval().error().rfind("FAILED_PRECONDITION: ", 0), 0u) << failed.retrieval().error();
}

TEST_F(PacsRoundTripTest, CMoveToTheServersStorageScpWhenCGetIsRefused) {
  const std::string study = MakeRecording(dir_.path(), dir_ / "recording.dcm");
  ASSERT_EQ(Text(orthanc_->Store(dir_ / "recording.dcm"), "Status"), "Success");
  // A CT beside it: the recording's series is moved alone (the whole study failed for the CT).
  ASSERT_EQ(Text(orthanc_->Store(MakeCtImage(dir_ / "ct.dcm", study)), "Status"), "Success");
  // Orthanc lets the AE MOVER move but not get; without a worker the job waits in the queue.
  Cluster cluster({"--ae-title", "MOVER", "--pacs", "orthanc=" + orthanc_->Address(), "--dicom-listen",
                   "127.0.0.1:" + std::to_string(mover_port_), "--dicom-timeout", "5"});
  const v1::Job job = SubmitAndAwaitRetrieval(cluster, study);
  EXPECT_EQ(job.retrieval().state(), v1::Retrieval::RETRIEVED)
      << job.retrieval().error() << cluster.ServerLog();
  EXPECT_EQ(job.retrieval().method(), "C-MOVE");
  EXPECT_EQ(job.retrieval().instances(), 1);
  // Orthanc aborts the association of a C-GET this AE may not make: said with what to check (no hint
  // until 2026-12-07).
  EXPECT_NE(cluster.ServerLog().find("then aborted it: does it allow MOVER to C-GET"), std::string::npos)
      << cluster.ServerLog();
  EXPECT_EQ(job.state(), v1::QUEUED);
  ASSERT_EQ(job.clip().files_size(), 1);
  EXPECT_EQ(job.clip().files(0).size(), job.retrieval().bytes());

  // With no retrieval in progress, the storage SCP takes nothing, even from the PACS's AE title
  // (an unasked-for instance was kept under dicom-incoming/ for good), and answers only its own
  // called AE title (any was answered; found 2026-12-05).
  const dicom::Peer scp{"MOVER", "127.0.0.1", mover_port_};
  dicom::StoreSettings as_pacs;
  as_pacs.calling_ae_title = "ORTHANC";
  const dicom::StoreResult unasked = dicom::StoreFiles(scp, {dir_ / "recording.dcm"}, as_pacs);
  ASSERT_EQ(unasked.stored.size(), 1u);
  EXPECT_FALSE(unasked.stored[0]);
  EXPECT_NE(unasked.first_error.find("0x0124"), std::string::npos) << unasked.first_error;
  // An endorecon result (taken, not kept, while a retrieval of its study runs) is refused too: it was
  // answered Success, asked or not (found 2026-12-07).
  dicom::SeriesHeader header;
  header.study = dicom::NewStudyContext("P-1", "", "", "");
  dicom::WriteColorFrames(dir_ / "rendered.dcm", header, {cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3))});
  const dicom::StoreResult result_unasked = dicom::StoreFiles(scp, {dir_ / "rendered.dcm"}, as_pacs);
  ASSERT_EQ(result_unasked.stored.size(), 1u);
  EXPECT_FALSE(result_unasked.stored[0]);
  EXPECT_NE(result_unasked.first_error.find("0x0124"), std::string::npos) << result_unasked.first_error;
  int kept = 0;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(cluster.data_dir() / "dicom-incoming"))
    kept += entry.is_regular_file() ? 1 : 0;
  EXPECT_EQ(kept, 0);
  const dicom::Peer wrong_called{"NOTMOVER", "127.0.0.1", mover_port_};
  EXPECT_THROW(dicom::StoreFiles(wrong_called, {dir_ / "recording.dcm"}, as_pacs), Error);
}

// A study holding a CT beside the recording: the PACS failed the whole-study C-GET (no context for
// the CT's class) and the job failed until 2026-12-05. The server lists the study's instances
// (C-FIND) and retrieves the recording's series alone; a study holding no recording fails naming
// what it holds instead.
TEST_F(PacsRoundTripTest, AStudyHoldingOtherObjectsGivesItsRecordingSeries) {
  const std::string study = MakeRecording(dir_.path(), dir_ / "recording.dcm");
  ASSERT_EQ(Text(orthanc_->Store(dir_ / "recording.dcm"), "Status"), "Success");
  ASSERT_EQ(Text(orthanc_->Store(MakeCtImage(dir_ / "ct.dcm", study)), "Status"), "Success");
  const std::string ct_only = dicom::NewUid("");
  ASSERT_EQ(Text(orthanc_->Store(MakeCtImage(dir_ / "ct2.dcm", ct_only)), "Status"), "Success");
  Cluster cluster({"--ae-title", "ENDORECON", "--pacs", "orthanc=" + orthanc_->Address(), "--dicom-listen",
                   "127.0.0.1:" + std::to_string(scp_port_), "--dicom-timeout", "5"});
  const v1::Job job = SubmitAndAwaitRetrieval(cluster, study);
  EXPECT_EQ(job.retrieval().state(), v1::Retrieval::RETRIEVED)
      << job.retrieval().error() << cluster.ServerLog();
  EXPECT_EQ(job.retrieval().method(), "C-GET");
  EXPECT_EQ(job.retrieval().instances(), 1);
  EXPECT_EQ(job.clip().files_size(), 1);
  EXPECT_NE(cluster.ServerLog().find("the study holds 1 series of other objects (CTImageStorage x 1)"),
            std::string::npos)
      << cluster.ServerLog();

  const auto none = RunCli(cluster.address(), {"submit", "--pacs", "orthanc", "--study", ct_only, "--wait"});
  EXPECT_EQ(none.exit_code, 5) << none.out << none.err;
  EXPECT_NE(none.out.find("the study holds no recording, only objects of classes endorecon does not take "
                          "(CTImageStorage x 1)"),
            std::string::npos)
      << none.out;
}

// With tokens: a recording retrieved for a job is the submitting tenant's, and its bytes count
// against that tenant's byte quota; a tenant whose quota it would pass gets a FAILED job, and not
// a byte of the recording enters the blob store.
TEST_F(PacsRoundTripTest, ARetrievedRecordingCountsAgainstTheSubmittersByteQuota) {
  const std::string study = MakeRecording(dir_.path(), dir_ / "recording.dcm");
  ASSERT_EQ(Text(orthanc_->Store(dir_ / "recording.dcm"), "Status"), "Success");
  const auto recording_bytes = fs::file_size(dir_ / "recording.dcm");
  WriteBytes(dir_ / "quotas.json", nlohmann::json{{"radiology", {{"max_bytes", recording_bytes + 100}}},
                                                  {"research", {{"max_bytes", 1000}}}}
                                       .dump());
  Cluster cluster({"--pacs", "orthanc=" + orthanc_->Address(), "--dicom-timeout", "5", "--quotas",
                   (dir_ / "quotas.json").string()},
                  false);
  const auto alice = MakeCredentials(cluster, "", "client", "radiology", "alice");
  const auto carol = MakeCredentials(cluster, "", "client", "research", "carol");
  cluster.UseCredentials(alice);
  cluster.StartServer();
  const auto as = [&](const ClientCredentials& who, std::vector<std::string> args) {
    auto argv = who.CliFlags();
    argv.insert(argv.end(), args.begin(), args.end());
    return RunCli(cluster.address(), argv);
  };

  const auto refused = as(carol, {"submit", "--pacs", "orthanc", "--study", study, "--wait"});
  EXPECT_EQ(refused.exit_code, 5) << refused.out << refused.err;
  EXPECT_NE(refused.out.find("max_bytes of 1000 bytes"), std::string::npos) << refused.out;
  EXPECT_TRUE(fs::is_empty(cluster.data_dir() / "blobs"));

  const auto kept = as(alice, {"submit", "--pacs", "orthanc", "--study", study});
  ASSERT_EQ(kept.exit_code, 0) << kept.err;
  const std::string id = JobIdIn(kept.out);
  ASSERT_TRUE(WaitUntil([&] { return cluster.Job(id).retrieval().state() != v1::Retrieval::RETRIEVING; },
                        std::chrono::seconds(60)));
  const v1::Job job = cluster.Job(id);
  EXPECT_EQ(job.retrieval().state(), v1::Retrieval::RETRIEVED) << job.retrieval().error();
  EXPECT_EQ(job.tenant(), "radiology");
  EXPECT_EQ(job.submitted_by(), "alice");
  // The recording now fills radiology's quota: another clip does not fit.
  MakeClip(cluster.path("clip"));
  const auto over = as(alice, {"submit", cluster.path("clip").string()});
  EXPECT_EQ(over.exit_code, 8) << over.err;
  EXPECT_NE(over.err.find("keeps " + std::to_string(recording_bytes) + " bytes"), std::string::npos)
      << over.err;

  const auto audit = AuditLines(cluster.data_dir() / "audit.jsonl");
  EXPECT_EQ(AuditFind(audit, "PacsRetrieve", "RESOURCE_EXHAUSTED", "server").size(), 1u);
  EXPECT_EQ(AuditFind(audit, "PacsRetrieve", "OK", "server", id).size(), 1u);
}

}  // namespace
}  // namespace endorecon::testing
