#include "client/job_format.h"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "common/job_bounds.h"

namespace endorecon::client {

std::string ToJson(const google::protobuf::Message& message) {
  std::string json;
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  // Zeros and empty strings too: a script reading job["priority"] or ["attempts"] met a missing key
  // whenever the value was 0 (found 2026-12-05).
  options.always_print_primitive_fields = true;
  (void)google::protobuf::util::MessageToJsonString(message, &json, options);
  return json;
}

std::string HumanBytes(std::int64_t bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1000 && unit < 4) {
    value /= 1000;
    ++unit;
  }
  return unit == 0 ? fmt::format("{} B", bytes) : fmt::format("{:.1f} {}", value, units[unit]);
}

std::string HumanDuration(double seconds) {
  // Clamped to a thousand years: a huge or infinite estimate overflowed the integer (an ETA of
  // -9223372036854775808s).
  const auto s =
      static_cast<std::int64_t>(std::llround(std::clamp(std::isnan(seconds) ? 0.0 : seconds, 0.0, 3.2e10)));
  if (s < 60) return fmt::format("{}s", s);
  if (s < 3600) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
}

std::string HumanTime(std::int64_t unix_ms) {
  if (unix_ms <= 0) return "-";
  const std::time_t t = static_cast<std::time_t>(unix_ms / 1000);
  return fmt::format("{:%Y-%m-%d %H:%M:%S}", fmt::localtime(t));
}

std::string ProgressLine(const v1::Progress& p, bool stopped) {
  const std::string eta = stopped ? "" : "  ETA " + HumanDuration(p.eta_s());
  if (p.phase() == "prepare") {
    return p.total_iterations() > 0
               ? fmt::format("preparing the recording: frame {}/{}", p.iteration(), p.total_iterations())
               : fmt::format("preparing the recording: frame {}", p.iteration());
  }
  if (p.phase() == "upload") return fmt::format("uploading the results: {} file(s)", p.total_iterations());
  if (p.phase() == "upload-wait") {
    return fmt::format(
        "the results ({} file(s)) wait on the worker for space on the server's data disk: sent once it is "
        "freed",
        p.total_iterations());
  }
  if (p.phase() == "evaluate") {
    return fmt::format("evaluating the results: frame {}/{}  {:.0f} s{}", p.iteration(), p.total_iterations(),
                       p.seconds(), eta);
  }
  const double fraction =
      p.total_iterations() > 0
          ? std::clamp(static_cast<double>(p.iteration()) / p.total_iterations(), 0.0, 1.0)
          : 0.0;
  constexpr int kWidth = 24;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string line = fmt::format("[{}{}]", std::string(static_cast<std::size_t>(filled), '#'),
                                 std::string(static_cast<std::size_t>(kWidth - filled), '.'));
  line += fmt::format(" {:3.0f}%  it {}/{}  {:.0f} s  loss {:.4g}  PSNR {:.2f} dB", 100 * fraction,
                      p.iteration(), p.total_iterations(), p.seconds(), p.loss(), p.train_psnr());
  if (p.heldout_psnr() >= 0) line += fmt::format(" (held-out {:.2f})", p.heldout_psnr());
  if (p.depth_rmse() >= 0) line += fmt::format("  depth RMSE {:.2f}% of range", 100 * p.depth_rmse());
  line += fmt::format("  {:.3g} samples/s{}", p.samples_per_second(), eta);
  return line;
}

std::optional<long long> TrainedIterations(const v1::Job& job) {
  const auto summary = nlohmann::json::parse(job.summary_json(), nullptr, /*allow_exceptions=*/false);
  if (!summary.is_object() || !summary.contains("iterations") || !summary["iterations"].is_number_integer())
    return std::nullopt;
  return summary["iterations"].get<long long>();
}

std::string OutcomeLine(const v1::Job& job) {
  if (job.state() != v1::SUCCEEDED || job.summary_json().empty()) return "";
  const auto summary = nlohmann::json::parse(job.summary_json(), nullptr, /*allow_exceptions=*/false);
  if (!summary.is_object() || !summary.contains("iterations")) return "";
  const auto number = [&](const char* key) {
    const auto found = summary.find(key);
    return found != summary.end() && found->is_number() ? found->get<double>() : -1.0;
  };
  // The training time in the units of the wall times after it ("41s of training, 1m02s in all").
  std::string line =
      fmt::format("done: {:.0f} iteration{} in {} of training", number("iterations"),
                  number("iterations") == 1 ? "" : "s", HumanDuration(number("train_seconds")));
  // Training seconds count every run of a resumed job; its wall time is said for the last run and
  // since the first ("36 s of training, 33s in all" read as a contradiction; found 2026-12-05). Not
  // "resumed": a run without a checkpoint to resume from started over (found 2026-12-06).
  if (job.started_unix_ms() > 0 && job.finished_unix_ms() >= job.started_unix_ms()) {
    const double last = (job.finished_unix_ms() - job.started_unix_ms()) / 1000.0;
    if (job.first_started_unix_ms() > 0 && job.first_started_unix_ms() < job.started_unix_ms()) {
      line += fmt::format(", {} in its last run, {} since it first started", HumanDuration(last),
                          HumanDuration((job.finished_unix_ms() - job.first_started_unix_ms()) / 1000.0));
    } else {
      line += fmt::format(", {} in all", HumanDuration(last));
    }
  }
  if (number("train_psnr") > 0) line += fmt::format(", PSNR {:.2f} dB", number("train_psnr"));
  if (number("heldout_psnr") >= 0) line += fmt::format(" (held-out {:.2f})", number("heldout_psnr"));
  // A reconstruction over its budget by more than the tenth it keeps to (a budget too small for the
  // clip's results): said here, not only in the worker's log (found 2026-12-06). The budget is the
  // engine's run's; the job's wall time above adds preparation and transfers.
  if (number("time_budget_s") > 0 && number("run_seconds") > 1.1 * number("time_budget_s")) {
    line += fmt::format("; the reconstruction took {} of its {} time budget",
                        HumanDuration(number("run_seconds")), HumanDuration(number("time_budget_s")));
  }
  if (number("budget_advised_s") > 0) {
    line += fmt::format(
        "; its results took more than a quarter of the time budget: {:.0f} s or more leaves training three "
        "quarters",
        number("budget_advised_s"));
  }
  // What the results' reader must know (metrics.json "warnings"), under the outcome.
  if (const auto warnings = summary.find("warnings"); warnings != summary.end() && warnings->is_array()) {
    for (const auto& warning : *warnings) {
      if (warning.is_string()) line += "\n  warning   " + PrintableLines(warning.get<std::string>());
    }
  }
  return line;
}

std::string DicomLines(const v1::Job& job) {
  std::string text;
  if (job.has_retrieval()) {
    const auto& r = job.retrieval();
    std::string state = r.state() == v1::Retrieval::RETRIEVING  ? "in progress"
                        : r.state() == v1::Retrieval::RETRIEVED ? "done"
                                                                : "failed";
    if (r.state() == v1::Retrieval::RETRIEVING && r.next_attempt_unix_ms() > 0) {
      state = fmt::format("waiting for the PACS (attempt {} failed; the next at {})", r.attempts(),
                          HumanTime(r.next_attempt_unix_ms()));
    }
    text += fmt::format("  retrieval from PACS {}{}: {} instance(s), {}, {}{}\n", r.source().pacs(),
                        r.method().empty() ? "" : " by " + r.method(), r.instances(), HumanBytes(r.bytes()),
                        state, r.error().empty() ? "" : ": " + r.error());
  }
  for (const auto& send : job.sends()) {
    std::string state;
    switch (send.state()) {
      case v1::DicomSend::PENDING:
        state = send.attempts() == 0
                    ? "pending"
                    : fmt::format("pending (attempt {} failed: {})", send.attempts(), send.error());
        break;
      case v1::DicomSend::SENDING:
        state = fmt::format("sending, {} of {} sent", send.sent(), send.total());
        break;
      case v1::DicomSend::SENT:
        state = fmt::format("sent {} of {}", send.sent(), send.total());
        break;
      default:
        state = send.attempts() == 0 ? send.error()  // never tried: the job ended without results
                                     : fmt::format("failed after {} attempt(s), {} of {} sent: {}",
                                                   send.attempts(), send.sent(), send.total(), send.error());
    }
    text += fmt::format("  send to {}: {}\n", send.destination(), state);
  }
  return text;
}

std::string DescribeJob(const v1::Job& job) {
  std::string text = job.name().empty() ? fmt::format("job {}\n", job.id())
                                        : fmt::format("job {} ({})\n", job.id(), job.name());
  text += fmt::format("  state     {}{}\n", v1::JobState_Name(job.state()),
                      job.cancel_requested() && job.state() == v1::RUNNING ? " (cancel requested)" : "");
  text += fmt::format("  priority  {}\n", job.priority());
  if (!job.tenant().empty()) text += fmt::format("  tenant    {}\n", job.tenant());
  if (!job.submitted_by().empty()) text += fmt::format("  by        {}\n", job.submitted_by());
  text += fmt::format("  created   {}\n", HumanTime(job.created_unix_ms()));
  // A job handed back or requeued starts again: its first start and its latest lease's both.
  const bool restarted =
      job.first_started_unix_ms() > 0 && job.first_started_unix_ms() != job.started_unix_ms();
  if (restarted) text += fmt::format("  started   {}\n", HumanTime(job.first_started_unix_ms()));
  // One lease: no more to say. A record from before first starts were kept: it may be a later lease.
  const bool one_lease = job.first_started_unix_ms() == job.started_unix_ms();
  if (job.started_unix_ms() > 0)
    text += fmt::format("  {} {}{}\n", restarted ? "restarted" : "started  ",
                        HumanTime(job.started_unix_ms()), one_lease ? "" : " (its latest lease)");
  if (job.finished_unix_ms() > 0) text += fmt::format("  finished  {}\n", HumanTime(job.finished_unix_ms()));
  text += fmt::format("  attempts  {} lost of {} allowed\n", job.attempts(), job.max_attempts());
  if (!job.worker_id().empty()) text += fmt::format("  worker    {}\n", job.worker_id());
  if (job.clip().files_size() > 0) {
    // The frames --frames picked of a DICOM recording (a clip folder's were cut before its upload,
    // and the job's name says which; a raw recording's are in its preparation's record,
    // clip/prepare.json).
    const std::string picked = !job.has_prepare() && !job.recording().frames().empty()
                                   ? " (frames " + job.recording().frames() + ")"
                                   : "";
    // The eyes' skips, which decide what was paired, are shown with the recording (found 2026-12-07).
    std::string skips;
    if (job.prepare().skip_left() > 0) skips += fmt::format(", --skip-left {}", job.prepare().skip_left());
    if (job.prepare().skip_right() > 0) skips += fmt::format(", --skip-right {}", job.prepare().skip_right());
    text += fmt::format("  {} {} file(s){}{}\n", job.has_prepare() ? "recording" : "clip     ",
                        job.clip().files_size(),
                        job.has_prepare() ? " (prepared into the results' clip/" + skips + ")" : "", picked);
  }
  if (const auto outcome = OutcomeLine(job); !outcome.empty()) {
    text += "  outcome   " + outcome + "\n";
  } else if (job.has_progress()) {
    // A job that ended otherwise shows where it stopped; a live one where it is; a requeued one where
    // its last run stopped, without that run's ETA (it showed one while queued; found 2026-12-06).
    const bool ended = job.finished_unix_ms() > 0;
    const bool waits = job.state() == v1::QUEUED;
    text += (ended   ? "  stopped   "
             : waits ? "  last run  "
                     : "  progress  ") +
            ProgressLine(job.progress(), ended || waits) + "\n";
  }
  // A job not finished has an error only from a lost run, which a running job no longer is in.
  const bool finished = job.finished_unix_ms() > 0;
  if (!job.error().empty())
    text += fmt::format("  {}{}\n", finished ? "reason    " : "requeued  ", job.error());
  text += DicomLines(job);
  if (job.expired_unix_ms() > 0) {
    text +=
        fmt::format("  expired   {} (its clip and results were deleted: retention, or `endorecon delete`)\n",
                    HumanTime(job.expired_unix_ms()));
  }
  if (job.result().files_size() > 0) {
    std::int64_t bytes = 0;
    for (const auto& file : job.result().files()) bytes += file.size();
    if (job.expired_unix_ms() == 0) {
      text += fmt::format("  results   {} file(s), {} (endorecon fetch {} -o DIR)\n",
                          job.result().files_size(), HumanBytes(bytes), job.id());
    }
  }
  return text;
}

}  // namespace endorecon::client
