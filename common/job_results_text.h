// What the server and the CLI say of a job asked for results it does not have.
#pragma once

#include <string>

#include "endorecon/v1/job.pb.h"

namespace endorecon {

// Why a job that has not SUCCEEDED has no results to be `use`d ("sent", "fetched"): one still to
// run has them once it succeeds, a FAILED or CANCELLED one never (it was told "once it has
// SUCCEEDED", which it never would; found 2026-12-07).
inline std::string NoResultsYet(const v1::Job& job, const std::string& use) {
  const bool ended = job.state() == v1::FAILED || job.state() == v1::CANCELLED;
  return "job " + job.id() + " is " + v1::JobState_Name(job.state()) +
         (ended ? ": it ended without results, so none can be " + use
                : "; its results can be " + use + " once it has SUCCEEDED");
}

}  // namespace endorecon
