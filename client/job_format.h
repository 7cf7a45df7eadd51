// How jobs, progress and workers look on a terminal, and as JSON (protobuf's JSON mapping, with
// the .proto field names) for scripts.
#pragma once

#include <google/protobuf/message.h>

#include <cstdint>
#include <optional>
#include <string>

#include "endorecon/v1/job_service.pb.h"

namespace endorecon::client {

// protobuf's JSON mapping with the .proto field names, every scalar field written (0, "", false too);
// 64-bit integers are strings, as the mapping has them.
std::string ToJson(const google::protobuf::Message& message);
// A multi-line description of one job.
std::string DescribeJob(const v1::Job& job);
// The DICOM side of a job, one line each: the retrieval from a PACS ("retrieval from PACS1 by C-GET:
// 3 instance(s), 1.2 MB, done") and each destination's send ("send to PACS1: sent 4 of 4"; "failed
// after 5 attempt(s): <the peer's reason>"). Empty when the job has neither.
std::string DicomLines(const v1::Job& job);
// What a SUCCEEDED job's engine reported (its summary): "done: 1858 iterations in 41s of training,
// 1m02s in all, PSNR 31.10 dB (held-out 31.75)", and a line "  warning   ..." for each of the run's
// warnings (metrics.json "warnings"). Empty for any other job or an unreadable summary.
std::string OutcomeLine(const v1::Job& job);
// The iterations a job trained, from the engine's summary (summary_json, set when it SUCCEEDED); none
// without one.
std::optional<long long> TrainedIterations(const v1::Job& job);
// One line: bar, iteration, training seconds, loss, PSNR (training, held-out), held-out depth error,
// samples/s, and the ETA while the job runs (`stopped`: it ended, so no ETA).
std::string ProgressLine(const v1::Progress& progress, bool stopped = false);
// "1.2 MB", "3.4 GB".
std::string HumanBytes(std::int64_t bytes);
// "42s", "3m07s", "2h05m".
std::string HumanDuration(double seconds);
std::string HumanTime(std::int64_t unix_ms);

}  // namespace endorecon::client
