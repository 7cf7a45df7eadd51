// endorecon-server retention --data-dir DIR --retention-days D --dry-run: what a server with
// --retention-days D would delete now. Reads only; deleting is the running server's job (it alone
// knows which blobs an upload in flight is about to reference).
#include <fmt/chrono.h>
#include <fmt/format.h>
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <vector>

#include "common/cli_checks.h"
#include "common/error.h"
#include "server/blob_store.h"
#include "server/commands.h"
#include "server/data_folder.h"
#include "server/job_coordinator.h"
#include "server/orphan_watch.h"
#include "server/retention.h"
#include "server/unix_time.h"
#include "server/upload_ledger.h"

namespace endorecon::server {
namespace {

struct RetentionFlags {
  std::string data_dir = "endorecon-data";
  double days = 0;
  double orphan_hours = 24;
  bool dry_run = false;
};

int DryRun(const RetentionFlags& flags) {
  if (!flags.dry_run) {
    FailInvalid(
        "retention deletes only inside a running server (--retention-days); this command shows what "
        "it would delete: add --dry-run");
  }
  const std::filesystem::path dir = flags.data_dir;
  // Before the store is opened: opening one of no table (a running server's, copied without its log)
  // made an empty jobs table, and the server then started on it and deleted every blob as no job's
  // (found 2026-12-07). Before the store's absence is said, too: blobs/ without it is refused as the
  // server refuses it, with the restore's hint.
  RefuseBlobsWithoutTheirStore(dir);
  if (!std::filesystem::exists(dir / "jobs.sqlite"))
    Fail(ErrorCode::kNotFound, "no job store in " + dir.string());
  // The blob store makes blobs/ and partial/ when they are missing; a dry run changes nothing, so the
  // ones it made go again, empty, however it ends (a restored folder without partial/ gained one).
  struct MadeFolders {
    std::vector<std::filesystem::path> folders;
    ~MadeFolders() {
      std::error_code ignored;
      for (const auto& folder : folders) std::filesystem::remove(folder, ignored);  // only if empty
    }
  } made;
  for (const char* folder : {"blobs", "partial"}) {
    if (std::error_code error; !std::filesystem::exists(dir / folder, error))
      made.folders.push_back(dir / folder);
  }
  ::umask(077);  // what SQLite makes beside the store (its log) is the server's alone, as the server makes it
  BlobStore blobs(dir);  // before the store, as the server: a refusal of its folders leaves no store made
  JobStore store(dir / "jobs.sqlite");
  UploadLedger uploads;  // read; written only at a change, which a dry run makes none of
  uploads.KeepIn(dir / "uploads.json");
  OrphanWatch orphans;  // read only
  orphans.ReadFrom(dir / "orphans.json");
  // The server's cutoffs: 0 days keeps every job, as --retention-days 0 there, and uploads last
  // noted before the orphan cutoff are given up.
  const auto orphan_cutoff = OrphanCutoffFor(flags.orphan_hours);
  const bool orphans_go = flags.orphan_hours > 0;
  auto plan = PlanRetention(
      store, blobs, JobCutoff(flags.days), orphans_go ? blobs.Files() : std::vector<BlobStore::StoredFile>{},
      [&](const std::string& digest) { return uploads.Holds(digest, orphan_cutoff.written_before); });
  if (orphans_go) orphans.Sift(plan, orphan_cutoff, NowUnixMs());
  for (const auto& job : plan.jobs) {
    std::cout << fmt::format("would expire job {} (tenant {}, {}, finished {:%Y-%m-%d %H:%M} UTC)\n",
                             job.id(), job.tenant().empty() ? "-" : job.tenant(),
                             v1::JobState_Name(job.state()),
                             fmt::gmtime(static_cast<std::time_t>(job.finished_unix_ms() / 1000)));
  }
  // "(0: none)" followed the days whatever they were (found 2026-12-07): --retention-days 0 is said.
  std::cout
      << (flags.days > 0 ? fmt::format("dry run: {} job(s) finished more than {} day(s) ago would expire",
                                       plan.jobs.size(), flags.days)
                         : std::string("dry run: --retention-days 0 expires no job"))
      << fmt::format(
             "; {} blob(s), {} bytes, would be deleted; {} blob(s) stay because other jobs share them, {} "
             "because uploads not yet submitted bring them\n",
             plan.blobs.size(), plan.bytes, plan.kept_shared, plan.kept_uploading);
  if (!orphans_go) {
    std::cout << "--orphan-hours 0 keeps the files no job references: not counted\n";
    return 0;
  }
  std::cout << fmt::format(
      "{} file(s), {} bytes, that no job references would be deleted (--orphan-hours {}); {} more are not "
      "old enough yet: each goes once that long has passed since it was last written and since the "
      "server first found that no job names it\n",
      plan.orphans.size(), plan.orphan_bytes, flags.orphan_hours, plan.orphans_waiting);
  return 0;
}

}  // namespace

Command AddRetentionCommand(CLI::App& app) {
  auto flags = std::make_shared<RetentionFlags>();
  auto* command = app.add_subcommand("retention", "show what retention would delete (--dry-run)");
  command->add_option("--data-dir", flags->data_dir, "the server's data folder")->capture_default_str();
  command->add_option("--retention-days", flags->days, "files of jobs finished longer ago than this go")
      ->required()
      ->check(AtLeastZero());
  command
      ->add_option("--orphan-hours", flags->orphan_hours,
                   "files no job references go once this long has passed both since each was last "
                   "written and since the server first found that no job names it (orphans.json) (0: kept)")
      ->capture_default_str()
      ->check(AtLeastZero());
  command->add_flag("--dry-run", flags->dry_run,
                    "required: list what would go and change nothing (a running server does the deleting)");
  return [flags] { return DryRun(*flags); };
}

}  // namespace endorecon::server
