// The server is killed (-9) mid-upload and mid-job. After a restart nothing accepted is lost:
// committed upload bytes, queued and running jobs, finished results; the upload resumes and the
// running job completes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <random>
#include <regex>
#include <string>
#include <thread>

#include "common/sha256.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

// Whether the server lists worker `id` with its devices (it registered with this server process).
bool ListedWithDevices(Cluster& cluster, const std::string& id) {
  grpc::ClientContext context;
  v1::ListWorkersResponse workers;
  if (!cluster.stub().ListWorkers(&context, {}, &workers).ok()) return false;
  for (const auto& one : workers.workers()) {
    if (one.id() == id && one.device_info_size() > 0) return true;
  }
  return false;
}

TEST(ServerRestartTest, KillDuringUploadThenTheUploadResumes) {
  Cluster cluster;
  const auto clip = cluster.path("bigclip");
  MakeClip(clip);  // a clip, which the CLI checks before its upload (and whose named files it uploads)
  // Its first frame made 24 MiB larger (random bytes in a chunk decoders skip).
  std::string data(24 << 20, '\0');
  std::mt19937_64 random(7);
  for (auto& byte : data) byte = static_cast<char>(random());
  const std::string bytes = AddPngPayload(clip / "images" / "000000.png", data);
  v1::FileEntry entry;
  entry.set_path("images/000000.png");
  entry.set_size(static_cast<std::int64_t>(bytes.size()));
  entry.set_sha256(Sha256Hex(bytes));

  // Stream the first 12 MiB and keep the stream open while the server dies.
  grpc::ClientContext context;
  v1::UploadStatus ignored;
  auto writer = cluster.stub().Upload(&context, &ignored);
  v1::UploadRequest manifest;
  *manifest.mutable_manifest()->add_files() = entry;
  ASSERT_TRUE(writer->Write(manifest));
  const int chunk = 3 << 20;
  for (int offset = 0; offset < (12 << 20); offset += chunk) {
    v1::UploadRequest request;
    request.mutable_chunk()->set_path("images/000000.png");
    request.mutable_chunk()->set_offset(offset);
    request.mutable_chunk()->set_data(bytes.substr(static_cast<std::size_t>(offset), chunk));
    ASSERT_TRUE(writer->Write(request));
  }
  v1::Manifest query_manifest;
  *query_manifest.add_files() = entry;
  std::int64_t committed_before = 0;
  WaitUntil([&] {
    grpc::ClientContext query;
    v1::UploadStatus status;
    cluster.stub().QueryUpload(&query, query_manifest, &status);
    committed_before = status.committed_bytes();
    return committed_before == (12 << 20);
  });
  ASSERT_EQ(committed_before, 12 << 20);
  cluster.KillServer(SIGKILL);
  EXPECT_FALSE(writer->Finish().ok());

  cluster.StartServer();
  grpc::ClientContext query;
  v1::UploadStatus after;
  ASSERT_TRUE(cluster.stub().QueryUpload(&query, query_manifest, &after).ok());
  EXPECT_EQ(after.committed_bytes(), committed_before);
  EXPECT_FALSE(after.complete());

  const auto resumed = RunCli(cluster.address(), {"submit", clip.string(), "--iterations", "30"});
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  // The rest of the large file and the clip's own few kB went; its first half did not.
  EXPECT_NE(resumed.err.find(" MB sent, 12.6 MB already on the server"), std::string::npos) << resumed.err;
  EXPECT_NE(resumed.err.find("uploaded 41 file(s): 12.6 MB sent"), std::string::npos) << resumed.err;
  const auto blob = cluster.data_dir() / "blobs" / entry.sha256().substr(0, 2) / entry.sha256();
  ASSERT_TRUE(std::filesystem::exists(blob));
  EXPECT_EQ(Sha256File(blob), entry.sha256());
}

// Makes a clip under `clip` with a 256 MB frame (random bytes from `seed`), starts `submit` of it
// with `more`, and sends it SIGINT once the server holds part of the upload; the submit's output.
std::string InterruptedUpload(Cluster& cluster, const std::filesystem::path& clip, std::uint64_t seed,
                              const std::vector<std::string>& more = {}) {
  MakeClip(clip);
  std::string data(256 << 20, '\0');
  std::mt19937_64 random(seed);
  for (std::size_t i = 0; i < data.size(); i += 8) data[i] = static_cast<char>(random());
  AddPngPayload(clip / "images" / "000000.png", data);
  std::vector<std::string> argv{BuiltBinary("client/endorecon"), "--server", cluster.address(), "submit",
                                clip.string()};
  argv.insert(argv.end(), more.begin(), more.end());
  Process submit(argv, cluster.path("submit.log"));
  EXPECT_TRUE(WaitUntil(
      [&] {
        std::error_code error;
        return !std::filesystem::is_empty(cluster.data_dir() / "partial", error) && !error;
      },
      std::chrono::seconds(120)));
  submit.Signal(SIGINT);
  EXPECT_EQ(submit.Wait(), 130) << submit.Log();
  return submit.Log();
}

// Ctrl-C during an upload says that what arrived is kept and the same submit resumes it (it said
// nothing), and exits 130; the same submit then resumes.
TEST(ServerRestartTest, CtrlCDuringAnUploadSaysHowToResume) {
  Cluster cluster;
  const auto clip = cluster.path("bigclip");
  const auto log = InterruptedUpload(cluster, clip, 11, {"--iterations", "30"});
  EXPECT_NE(log.find("upload interrupted; what arrived is kept on the server"), std::string::npos) << log;
  const auto resumed = RunCli(cluster.address(), {"submit", clip.string(), "--iterations", "30"});
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("already on the server"), std::string::npos) << resumed.err;
}

// An upload given up counted against its tenant's bytes until --orphan-hours, and nothing listed it
// or let it go sooner (found 2026-12-06): `endorecon uploads` lists it, after a server restart too,
// and `--drop` deletes it.
TEST(ServerRestartTest, AnInterruptedUploadIsListedAndCanBeDropped) {
  Cluster cluster;
  InterruptedUpload(cluster, cluster.path("bigclip"), 12);
  const auto partial = cluster.data_dir() / "partial";
  cluster.KillServer(SIGKILL);  // the ledger is kept in the data folder (a restart forgot it)
  cluster.StartServer();
  const auto listed = RunCli(cluster.address(), {"uploads"});
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  EXPECT_NE(listed.out.find("uploads waiting to be submitted (they count against the tenant's byte quota"),
            std::string::npos)
      << listed.out;
  EXPECT_NE(listed.out.find("  no tenant ('-'): "), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find(" distinct file(s), 268.5 MB"), std::string::npos) << listed.out;
  // What arrived before the Ctrl-C: some kB or MB of the 268.5 MB, whenever the signal came.
  EXPECT_TRUE(std::regex_search(
      listed.out, std::regex(" 268\\.5 MB \\([0-9.]+ [kM]?B of it arrived\\), the last upload begun ")))
      << listed.out;
  // The metrics say how many bytes wait, every tenant's (the dashboard shows them).
  const auto pending_bytes = [&] {
    const auto text = Capture(
        "curl -s --max-time 5 http://127.0.0.1:" + std::to_string(cluster.metrics_port()) + "/metrics");
    std::smatch match;
    static const std::regex kLine("\nendorecon_uploads_pending_bytes ([0-9.e+]+)");
    return std::regex_search(text, match, kLine) ? std::stod(match[1]) : -1.0;
  };
  EXPECT_TRUE(WaitUntil([&] { return pending_bytes() > 256e6; }, std::chrono::seconds(20)))
      << pending_bytes();
  // A server without tokens has one tenant: its drop needs no --tenant (an admin's does: see
  // JobCoordinatorTest).
  const auto dropped = RunCli(cluster.address(), {"uploads", "--drop"});
  ASSERT_EQ(dropped.exit_code, 0) << dropped.err;
  EXPECT_NE(dropped.out.find("dropped the uploads waiting to be submitted (no tenant ('-')): "),
            std::string::npos)
      << dropped.out;
  EXPECT_NE(dropped.out.find("; deleted "), std::string::npos) << dropped.out;
  EXPECT_TRUE(std::filesystem::is_empty(partial)) << "the interrupted file's partial went";
  EXPECT_TRUE(WaitUntil([&] { return pending_bytes() == 0; }, std::chrono::seconds(20))) << pending_bytes();
  EXPECT_NE(RunCli(cluster.address(), {"uploads"}).out.find("no uploads waiting to be submitted"),
            std::string::npos);
  // An admin's tenant is a tenant's name: a typo, or text meant for the server's log, is refused.
  const auto typo = RunCli(cluster.address(), {"uploads", "--drop", "--tenant", "Radiology\n[info] forged"});
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.err.find("tenant 'Radiology?[info] forged': expected 1-63 characters"), std::string::npos)
      << typo.err;
  EXPECT_NE(RunCli(cluster.address(), {"uploads", "--drop", "--tenant", "radiology"})
                .out.find("no uploads of tenant 'radiology' waiting to be submitted: nothing dropped"),
            std::string::npos);
  const auto again = RunCli(cluster.address(), {"--json", "uploads"});
  EXPECT_EQ(again.out, "{\"tenants\":[]}\n") << again.out << ": a listing deletes nothing";
}

TEST(ServerRestartTest, KillDuringAJobLosesNothing) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  auto& worker = cluster.StartWorker("w1", {"--checkpoint-interval", "0.5"});
  const auto finished = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  ASSERT_EQ(cluster.WaitForState(finished, v1::SUCCEEDED).state(), v1::SUCCEEDED) << cluster.ServerLog();
  const auto running = cluster.Submit(cluster.path("clip"), {"--iterations", "150"});
  const auto queued = cluster.Submit(cluster.path("clip"), {"--iterations", "30", "--priority", "-1"});
  ASSERT_TRUE(WaitUntil([&] { return cluster.Job(running).progress().iteration() > 0; }))
      << cluster.ServerLog();

  cluster.KillServer(SIGKILL);
  cluster.StartServer();
  EXPECT_EQ(cluster.Job(finished).state(), v1::SUCCEEDED);
  EXPECT_EQ(cluster.Job(queued).state(), v1::QUEUED);
  // The worker kept training and reports to the restarted server under the same lease.
  const auto done = cluster.WaitForState(running, v1::SUCCEEDED, std::chrono::seconds(120));
  ASSERT_EQ(done.state(), v1::SUCCEEDED) << cluster.ServerLog() << worker.Log();
  EXPECT_EQ(cluster.WaitForState(queued, v1::SUCCEEDED, std::chrono::seconds(120)).state(), v1::SUCCEEDED);
  const auto fetched = RunCli(cluster.address(), {"fetch", finished, "-o", cluster.path("out").string()});
  EXPECT_EQ(fetched.exit_code, 0) << fetched.err;
  EXPECT_TRUE(std::filesystem::exists(cluster.path("out") / "metrics.json"));
  // The restarted server knows the worker's devices again: the worker registered anew when its
  // next lease said so (`workers` listed it without devices; found 2026-12-05).
  EXPECT_TRUE(WaitUntil([&] { return ListedWithDevices(cluster, "w1"); }))
      << cluster.ServerLog() << worker.Log();
}

// A server down longer than half a minute while a job's finished results wait to go up (an upgrade,
// a slow restart): the worker waits for it, and the restarted server takes them under the lease it
// kept. The worker gave up after 30 s: the finished results were thrown away, and the job lost an
// attempt and trained again (found 2026-12-07).
TEST(ServerRestartTest, FinishedResultsWaitForAServerDownLongerThanHalfAMinute) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  auto& worker = cluster.StartWorker("w1");
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "20"});
  // Training's last checkpoint is up: the evaluation runs, then the results' upload.
  ASSERT_TRUE(
      WaitUntil([&] { return !cluster.Job(id).checkpoint().sha256().empty(); }, std::chrono::seconds(120)))
      << cluster.ServerLog() << worker.Log();
  cluster.KillServer(SIGKILL);
  std::this_thread::sleep_for(std::chrono::seconds(35));
  cluster.StartServer();
  const auto done = cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(120));
  ASSERT_EQ(done.state(), v1::SUCCEEDED) << cluster.ServerLog() << worker.Log();
  EXPECT_EQ(done.attempts(), 0) << done.error() << "\n" << worker.Log();
  EXPECT_NE(worker.Log().find("while the server holds the lease"), std::string::npos)
      << "the results did not wait for the server: the test tested nothing\n"
      << worker.Log();
  EXPECT_EQ(worker.Log().find("resumed from"), std::string::npos) << "trained again\n" << worker.Log();
}

// An idle worker, long-polling as deployed (10 s), is back on a restarted server within seconds:
// it took 17-20 s (retries 5 s apart, then a whole long poll before the server said "register
// again"; found 2026-12-05).
TEST(ServerRestartTest, AnIdleWorkerIsListedAgainSoonAfterARestart) {
  Cluster cluster;
  auto& worker = cluster.StartWorker("w1", {"--lease-wait", "10"});
  const auto listed = [&] { return ListedWithDevices(cluster, "w1"); };
  ASSERT_TRUE(WaitUntil(listed)) << worker.Log();
  std::this_thread::sleep_for(std::chrono::seconds(1));  // the worker's long poll is under way
  cluster.KillServer(SIGKILL);
  std::this_thread::sleep_for(std::chrono::seconds(3));  // its retries meet a closed port
  cluster.StartServer();
  // Retries 2 s apart at most, and an answer at once to a worker the server does not know.
  EXPECT_TRUE(WaitUntil(listed, std::chrono::seconds(8))) << cluster.ServerLog() << worker.Log();
  // Logged when its next lease call is answered, which may come just after it is listed again.
  EXPECT_TRUE(WaitUntil([&] { return worker.Log().find("the server answers again") != std::string::npos; },
                        std::chrono::seconds(5)))
      << worker.Log();
}

// An idle worker whose long poll is longer than the server's alive window (its --lease-wait 10 beside
// the harness's lease TTL of 3 s) stays listed alive: the server holds a poll half the window at most
// (it was listed gone, and out of endorecon_workers_connected, while it waited; found 2026-12-07).
TEST(ServerRestartTest, AnIdleWorkerInALongPollStaysAlive) {
  Cluster cluster;
  auto& worker = cluster.StartWorker("w1", {"--lease-wait", "10"});
  ASSERT_TRUE(WaitUntil([&] { return ListedWithDevices(cluster, "w1"); })) << worker.Log();
  for (int i = 0; i < 16; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    grpc::ClientContext context;
    v1::ListWorkersResponse workers;
    ASSERT_TRUE(cluster.stub().ListWorkers(&context, {}, &workers).ok());
    ASSERT_EQ(workers.workers_size(), 1);
    EXPECT_TRUE(workers.workers(0).alive()) << "after " << (i + 1) * 0.5 << " s";
  }
}

// A worker stopped by SIGTERM tells the server, and is listed as not alive at once: it was listed
// alive, and counted in endorecon_workers_connected, until its heartbeats had been missed for the
// alive window (found 2026-12-05).
TEST(ServerRestartTest, AWorkerThatStopsIsListedAsGoneAtOnce) {
  Cluster cluster;
  auto& worker = cluster.StartWorker("w1");
  ASSERT_TRUE(WaitUntil([&] { return ListedWithDevices(cluster, "w1"); })) << worker.Log();
  worker.Signal(SIGTERM);
  EXPECT_EQ(worker.Wait(), 0) << worker.Log();
  grpc::ClientContext context;
  v1::ListWorkersResponse workers;
  ASSERT_TRUE(cluster.stub().ListWorkers(&context, {}, &workers).ok());
  ASSERT_EQ(workers.workers_size(), 1);
  EXPECT_FALSE(workers.workers(0).alive()) << worker.Log();
}

// A worker busy with a long job when the server restarts is listed with its devices again while the
// job runs: its progress stream's answer says "register again" (only a lease did, after the job).
TEST(ServerRestartTest, ABusyWorkerIsListedAgainWhileItsJobRuns) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  auto& worker = cluster.StartWorker("w1");
  const auto id = cluster.Submit(cluster.path("clip"), {"--time-budget", "25"});
  ASSERT_TRUE(WaitUntil([&] { return cluster.Job(id).progress().iteration() > 0; })) << worker.Log();
  cluster.KillServer(SIGKILL);
  cluster.StartServer();
  EXPECT_TRUE(WaitUntil([&] { return ListedWithDevices(cluster, "w1"); }, std::chrono::seconds(10)))
      << cluster.ServerLog() << worker.Log();
  EXPECT_EQ(cluster.Job(id).state(), v1::RUNNING);
  EXPECT_TRUE(cluster.Job(id).lease_id().empty()) << "a client is not shown the worker's lease id";
  EXPECT_EQ(cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(120)).state(), v1::SUCCEEDED)
      << worker.Log();
}

// A second server started on a port in use (a typo, a double start) is refused. gRPC's default
// SO_REUSEPORT let it listen beside the first, and the kernel split new connections, submits
// included, between the two (found 2026-12-05).
TEST(ServerStartTest, ASecondServerOnATakenPortIsRefused) {
  Cluster cluster;
  TempDir other("second");
  Process second({BuiltBinary("server/endorecon-server"), "--listen", cluster.address(), "--data-dir",
                  (other / "data").string(), "--metrics-port", "-1"},
                 other / "server.log");
  EXPECT_NE(second.Wait(), 0);
  EXPECT_NE(second.Log().find("the port is taken"), std::string::npos) << second.Log();
  EXPECT_EQ(RunCli(cluster.address(), {"list"}).exit_code, 0);
}

// A start refused for a flag's file, a PACS or the metrics port makes no data folder: it used to leave
// an empty job store, audit log and blob folders behind (found 2026-12-07).
TEST(ServerStartTest, AStartRefusedForAFlagMakesNoDataFolder) {
  Cluster cluster;  // holds a metrics port
  TempDir dir("refused");
  const std::string port = std::to_string(FreePort());
  for (const auto& [flags, said] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--quotas", (dir / "missing.json").string()}, "--quotas"},
           {{"--pacs", "nowhere"}, "--pacs 'nowhere'"},
           {{"--metrics-port", std::to_string(cluster.metrics_port())},
            std::to_string(cluster.metrics_port())}}) {
    std::vector<std::string> command{BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:" + port,
                                     "--data-dir", (dir / "data").string()};
    if (flags.front() != "--metrics-port") command.insert(command.end(), {"--metrics-port", "-1"});
    command.insert(command.end(), flags.begin(), flags.end());
    Process server(command, dir / "server.log");
    EXPECT_NE(server.Wait(), 0) << flags.front();
    EXPECT_NE(server.Log().find(said), std::string::npos) << server.Log();
    EXPECT_FALSE(std::filesystem::exists(dir / "data")) << flags.front() << " made the data folder";
  }
}

// A restore that brought blobs/ back without jobs.sqlite (or with an empty one) started a new store,
// and its first retention sweep deleted every blob as no job's (found 2026-12-05): refused at start.
TEST(ServerStartTest, BlobsWithoutTheirJobStoreAreRefused) {
  TempDir dir("blobs-alone");
  std::filesystem::create_directories(dir / "data" / "blobs" / "ab");
  WriteBytes(dir / "data" / "blobs" / "ab" / "abcdef", "a blob");
  // No store; an empty file; a store of no table whose log was not copied beside it (a copy of a
  // running server's jobs.sqlite without jobs.sqlite-wal: every job was still in the log).
  for (const int store : {0, 1, 2}) {
    if (store == 1) WriteBytes(dir / "data" / "jobs.sqlite", "");
    if (store == 2) {
      std::filesystem::remove(dir / "data" / "jobs.sqlite");
      sqlite3* db = nullptr;
      ASSERT_EQ(sqlite3_open((dir / "data" / "jobs.sqlite").c_str(), &db), SQLITE_OK);
      ASSERT_EQ(
          sqlite3_exec(db, "PRAGMA journal_mode=WAL; PRAGMA user_version=1;", nullptr, nullptr, nullptr),
          SQLITE_OK);
      sqlite3_close(db);
      ASSERT_GT(std::filesystem::file_size(dir / "data" / "jobs.sqlite"), 0u);
    }
    Process server({BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0", "--data-dir",
                    (dir / "data").string(), "--metrics-port", "-1"},
                   dir / "server.log");
    EXPECT_NE(server.Wait(), 0);
    EXPECT_NE(server.Log().find("blobs/ holds files (abcdef, ...) but there is no job store"),
              std::string::npos)
        << server.Log();
    EXPECT_TRUE(std::filesystem::exists(dir / "data" / "blobs" / "ab" / "abcdef"));
    // The dry run the docs advise before a restored folder's first start refuses alike (with no store
    // at all too: it said only "no job store"), and leaves the store as it was (it made the missing
    // table, and the server then started on it).
    if (store != 1) {
      const auto size = store == 2 ? std::filesystem::file_size(dir / "data" / "jobs.sqlite") : 0;
      Process dry_run({BuiltBinary("server/endorecon-server"), "retention", "--data-dir",
                       (dir / "data").string(), "--retention-days", "1", "--dry-run"},
                      dir / "dry-run.log");
      EXPECT_NE(dry_run.Wait(), 0);
      EXPECT_NE(dry_run.Log().find("but there is no job store"), std::string::npos) << dry_run.Log();
      if (store == 2) {
        EXPECT_EQ(std::filesystem::file_size(dir / "data" / "jobs.sqlite"), size);
      }
    }
  }
}

// A restore chowned without -R leaves the server's folders and stores another user's. Each is refused
// at start, named, with the chown to do; the server runs as `nobody` here, as the suite runs as root
// and root passes every permission check (this was tried by hand only, 2026-12-07).
TEST(ServerStartTest, FilesTheServersUserCannotUseAreRefusedNamingThem) {
  if (::geteuid() != 0 || !std::filesystem::exists("/usr/bin/setpriv"))
    GTEST_SKIP() << "needs root and setpriv, to run the server as another user";
  constexpr int kNobody = 65534;
  TempDir dir("owners");
  std::filesystem::permissions(dir.path(), std::filesystem::perms(0755));
  const auto data = dir / "data";
  std::filesystem::create_directories(data / "blobs");
  std::filesystem::permissions(data, std::filesystem::perms::owner_all);
  std::filesystem::permissions(data / "blobs", std::filesystem::perms::owner_all);
  const auto own = [&](const std::filesystem::path& path, int user) {
    ASSERT_EQ(::chown(path.c_str(), user, user), 0);
  };
  own(data, kNobody);
  const auto start = [&] {
    return std::make_unique<Process>(
        std::vector<std::string>{"/usr/bin/setpriv", "--reuid=65534", "--regid=65534", "--clear-groups",
                                 BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0",
                                 "--data-dir", data.string(), "--metrics-port", "-1"},
        dir / "server.log");
  };
  const auto refused = [&](const std::string& named) {
    auto server = start();
    EXPECT_NE(server->Wait(), 0);
    const auto log = server->Log();
    EXPECT_NE(log.find("FAILED_PRECONDITION"), std::string::npos) << log;
    EXPECT_NE(log.find(named), std::string::npos) << log;
    EXPECT_NE(log.find("chown it"), std::string::npos) << log;
  };
  // Another's blobs/ holding a file, and no store: it passed as empty, and the refusal of the blob
  // store after made an empty job store, which took every blob for no job's once blobs/ was chowned.
  WriteBytes(data / "blobs" / "abcdef", "a blob");
  refused((data / "blobs").string() + ": this user cannot list it");
  std::filesystem::remove(data / "blobs" / "abcdef");
  refused((data / "blobs").string() + ": this user cannot");
  EXPECT_FALSE(std::filesystem::exists(data / "jobs.sqlite")) << "a refused start made a store";
  own(data / "blobs", kNobody);

  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((data / "jobs.sqlite").c_str(), &db), SQLITE_OK);  // root's, 0644
  ASSERT_EQ(sqlite3_exec(db, "PRAGMA journal_mode=WAL", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
  refused((data / "jobs.sqlite").string() + " cannot be read and written by this user");
  own(data / "jobs.sqlite", kNobody);

  // Its shared-memory file another's (0644): SQLite opened the store read-only without a word, and
  // the first write stopped the server (found 2026-12-07).
  WriteBytes(data / "jobs.sqlite-shm", "");
  refused((data / "jobs.sqlite-shm").string() + " cannot be read and written by this user");
  std::filesystem::remove(data / "jobs.sqlite-shm");

  WriteBytes(data / "audit.jsonl", "");
  refused("cannot open audit log " + (data / "audit.jsonl").string());
  own(data / "audit.jsonl", kNobody);

  std::filesystem::create_directory(data / "damaged");  // root's: a damaged file was deleted, not set aside
  refused((data / "damaged").string() + ": this user cannot use it");
  own(data / "damaged", kNobody);

  std::filesystem::remove(data / "server.lock");  // an earlier start's, the server's user's
  WriteBytes(data / "server.lock", "");
  refused("cannot open " + (data / "server.lock").string());
  own(data / "server.lock", kNobody);

  // Another's token store: the chown said once (the store's check and the token guard both said it).
  WriteBytes(data / "tokens.sqlite", "");
  {
    Process server({"/usr/bin/setpriv", "--reuid=65534", "--regid=65534", "--clear-groups",
                    BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0", "--data-dir",
                    data.string(), "--metrics-port", "-1"},
                   dir / "tokens-start.log");  // a log of its own: server.log holds the earlier refusals
    EXPECT_NE(server.Wait(), 0);
    const auto log = server.Log();
    EXPECT_NE(log.find((data / "tokens.sqlite").string() + " cannot be read and written by this user"),
              std::string::npos)
        << log;
    EXPECT_NE(log.find("chown it"), std::string::npos) << log;
    EXPECT_EQ(log.find("chown it"), log.rfind("chown it")) << log;
  }
  std::filesystem::remove(data / "tokens.sqlite");

  // Everything the server's user's: it starts (the refusals above were the owners').
  auto server = start();
  EXPECT_TRUE(
      WaitUntil([&] { return server->Log().find("endorecon-server listening on") != std::string::npos; },
                std::chrono::seconds(20)))
      << server->Log();
  server->Signal(SIGTERM);
  EXPECT_EQ(server->Wait(), 0) << server->Log();

  // Root in the server's user's folder: refused, the server and `token create` alike, before they make
  // a file there. Root passes every permission check: it started, and made its server.lock,
  // orphans.json and partial/ root's, beside nobody's store (found 2026-12-07).
  const auto before = std::distance(std::filesystem::directory_iterator(data), {});
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0",
                                 "--data-dir", data.string(), "--metrics-port", "-1"},
        std::vector<std::string>{BuiltBinary("server/endorecon-server"), "token", "create", "--data-dir",
                                 data.string(), "--role", "admin", "--name", "root-made"}}) {
    Process as_root(command, dir / "root.log");
    EXPECT_NE(as_root.Wait(), 0) << command[1];
    const auto log = as_root.Log();
    EXPECT_NE(log.find(data.string() + " belongs to user nobody (uid 65534)"), std::string::npos) << log;
    EXPECT_NE(log.find("runuser -u nobody"), std::string::npos) << log;
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(data), {}), before) << "made nothing";
}

// The dry run changes nothing: a restored folder without blobs/ or partial/ gained them (found
// 2026-12-07).
TEST(ServerStartTest, TheRetentionDryRunMakesNoFolder) {
  TempDir dir("dry-run");
  std::filesystem::create_directories(dir / "data");
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "data" / "jobs.sqlite").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(
      sqlite3_exec(db,
                   "PRAGMA journal_mode=WAL; CREATE TABLE jobs (seq INTEGER PRIMARY KEY AUTOINCREMENT, "
                   "id TEXT NOT NULL UNIQUE, state INTEGER NOT NULL, priority INTEGER NOT NULL, job BLOB "
                   "NOT NULL)",
                   nullptr, nullptr, nullptr),
      SQLITE_OK);
  sqlite3_close(db);
  Process dry_run({BuiltBinary("server/endorecon-server"), "retention", "--data-dir", (dir / "data").string(),
                   "--retention-days", "1", "--dry-run"},
                  dir / "dry-run.log");
  EXPECT_EQ(dry_run.Wait(), 0) << dry_run.Log();
  EXPECT_NE(dry_run.Log().find("0 job(s)"), std::string::npos) << dry_run.Log();
  EXPECT_FALSE(std::filesystem::exists(dir / "data" / "blobs"));
  EXPECT_FALSE(std::filesystem::exists(dir / "data" / "partial"));
}

// A token store that appears and does not open (`sqlite3 tokens.sqlite .backup` run where there is
// no store leaves an empty file, which another user may own): the running server goes on, refusing
// every call and saying why, and admits callers again once it is removed; a server started beside
// it refuses to start (it aborted within a second, and every restart after; found 2026-12-07).
TEST(ServerStartTest, ATokenStoreThatDoesNotOpenRefusesCallsAndDoesNotStopTheServer) {
  Cluster cluster;
  const auto store = cluster.data_dir() / "tokens.sqlite";
  // Put in place whole, as a file appears: written in place, a call between its truncation and its
  // bytes found an empty file, which SQLite opens as a new store, and the refusal never came (a CI
  // run under load, 2026-12-07).
  const auto put_bad_store = [&] {
    WriteBytes(cluster.path("bad-store"), "not a database, and not empty");
    std::filesystem::rename(cluster.path("bad-store"), store);
  };
  put_bad_store();  // as root, what does not open whoever owns it
  const auto list = [&] {
    grpc::ClientContext context;
    v1::ListJobsRequest request;
    v1::ListJobsResponse response;
    return cluster.stub().List(&context, request, &response);
  };
  ASSERT_TRUE(WaitUntil([&] { return !list().ok(); }, std::chrono::seconds(10)));
  const grpc::Status refused = list();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_NE(refused.error_message().find("token store cannot be opened"), std::string::npos)
      << refused.error_message();
  std::this_thread::sleep_for(std::chrono::seconds(2));  // the periodic work meets it too
  EXPECT_EQ(::kill(cluster.server_pid(), 0), 0) << cluster.ServerLog();
  EXPECT_NE(cluster.ServerLog().find("every call is refused until the token store opens"), std::string::npos)
      << cluster.ServerLog();
  std::filesystem::remove(store);
  EXPECT_TRUE(WaitUntil([&] { return list().ok(); }, std::chrono::seconds(10))) << cluster.ServerLog();

  // A job running meanwhile: its worker's calls are refused too, and the lease that expires for it
  // is the server's fault, not an attempt (it cost one each time; found 2026-12-07).
  MakeClip(cluster.path("clip"));
  auto& worker = cluster.StartWorker("w");
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "100000"});
  cluster.WaitForState(id, v1::RUNNING);
  put_bad_store();
  ASSERT_TRUE(
      WaitUntil([&] { return cluster.ServerLog().find("token store does not open") != std::string::npos; },
                std::chrono::seconds(30)))
      << cluster.ServerLog() << worker.Log();
  std::filesystem::remove(store);
  ASSERT_TRUE(WaitUntil([&] { return list().ok(); }, std::chrono::seconds(10)));
  const v1::Job requeued = cluster.Job(id);
  EXPECT_EQ(requeued.attempts(), 0) << requeued.error();
  EXPECT_NE(requeued.error().find("(not counted as an attempt)"), std::string::npos) << requeued.error();
  ASSERT_EQ(RunCli(cluster.address(), {"cancel", id}).exit_code, 0);

  cluster.KillServer(SIGTERM);
  WriteBytes(store, "not a database, and not empty");
  Process restarted({BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0", "--data-dir",
                     cluster.data_dir().string(), "--metrics-port", "-1"},
                    cluster.path("restarted.log"));
  EXPECT_NE(restarted.Wait(), 0);
  EXPECT_NE(restarted.Log().find("FAILED_PRECONDITION"), std::string::npos) << restarted.Log();
  EXPECT_NE(restarted.Log().find("an empty file that `sqlite3 tokens.sqlite .backup` left"),
            std::string::npos)
      << restarted.Log();
}

// A data folder restored without its tokens.sqlite: the server starts (the operator may mean it) but
// warns that its newest job came with a token, naming who sent it; it said only that every local
// caller may use every API (found 2026-12-07).
TEST(ServerStartTest, AStoreRestoredWithoutItsTokensIsWarnedOf) {
  Cluster cluster({}, false);
  const auto carol = MakeCredentials(cluster, "", "client", "research", "carol");
  cluster.UseCredentials(carol);
  cluster.StartServer();
  MakeClip(cluster.path("clip"));
  cluster.Submit(cluster.path("clip"), {});
  cluster.KillServer(SIGTERM);
  std::filesystem::remove(cluster.data_dir() / "tokens.sqlite");
  cluster.UseCredentials({});
  cluster.StartServer();
  EXPECT_NE(cluster.ServerLog().find("yet the newest job was submitted with a token ('carol' of tenant "
                                     "'research'): was tokens.sqlite left out of a restore?"),
            std::string::npos)
      << cluster.ServerLog();
}

// The Kubernetes manifest's --data-dir moved from the volume's root to a folder below it (2026-12-06:
// fsGroup makes the root group-owned, and the server warned of it at every start). A deployment
// upgraded with its data still at the root would have started an empty store beside it, and one
// rolled back with its data below would have started empty with every API open (no token store):
// both refused, saying what to do, and nothing is made.
TEST(ServerStartTest, AStoreInTheFolderAboveOrBelowIsRefused) {
  Cluster cluster;
  cluster.KillServer(SIGTERM);
  const auto moved = cluster.data_dir() / "endorecon";
  Process server({BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0", "--data-dir",
                  moved.string(), "--metrics-port", "-1"},
                 cluster.path("moved.log"));
  EXPECT_NE(server.Wait(), 0);
  EXPECT_NE(server.Log().find("has no store, but its parent " + cluster.data_dir().string() +
                              " has one (jobs.sqlite): a --data-dir moved one folder down?"),
            std::string::npos)
      << server.Log();
  EXPECT_FALSE(std::filesystem::exists(moved));
  // `token create` there made a second token store, which the move of the data then overwrote.
  std::filesystem::create_directories(moved);
  Process token({BuiltBinary("server/endorecon-server"), "token", "create", "--data-dir", moved.string(),
                 "--role", "admin", "--name", "ops"},
                cluster.path("token.log"));
  EXPECT_NE(token.Wait(), 0);
  EXPECT_NE(token.Log().find("a --data-dir moved one folder down?"), std::string::npos) << token.Log();
  EXPECT_FALSE(std::filesystem::exists(moved / "tokens.sqlite"));

  // And back up (a rollback, a unit file left behind): the store is in a folder of the data folder.
  const auto moved_up = cluster.path("up");
  std::filesystem::create_directories(moved_up);
  std::filesystem::rename(cluster.data_dir(), moved_up / "endorecon");
  Process parent({BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0", "--data-dir",
                  moved_up.string(), "--metrics-port", "-1"},
                 cluster.path("up.log"));
  EXPECT_NE(parent.Wait(), 0);
  EXPECT_NE(parent.Log().find("has no store, but its folder " + (moved_up / "endorecon").string() +
                              " has one (jobs.sqlite): point --data-dir at it"),
            std::string::npos)
      << parent.Log();
  EXPECT_FALSE(std::filesystem::exists(moved_up / "jobs.sqlite"));

  // Tokens made before the server's first start are a store too: a server beside them started
  // without tokens, every API open (found by the re-test, 2026-12-06).
  TempDir fresh("tokens-first");
  std::filesystem::create_directories(fresh / "data");
  WriteTokenFile(fresh / "t", CreateToken(fresh / "data", "admin", "", "ops"));
  Process beside({BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:0", "--data-dir",
                  (fresh / "data" / "endorecon").string(), "--metrics-port", "-1"},
                 fresh / "server.log");
  EXPECT_NE(beside.Wait(), 0);
  EXPECT_NE(beside.Log().find("has one (tokens.sqlite)"), std::string::npos) << beside.Log();
}

}  // namespace
}  // namespace endorecon::testing
